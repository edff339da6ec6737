VENV := .venv
TEST_WORKERS ?= 2

.PHONY: setup demo test bench fuzz clean

setup:
	@scripts/setup.sh

demo: setup
	$(VENV)/bin/python examples/demo.py

test: setup
	$(VENV)/bin/python -m pytest -q -n $(TEST_WORKERS) tests

bench: setup
	@for b in benchmarks/*.py; do [ "$$b" = benchmarks/fuzz.py ] && continue; echo "== $$b"; $(VENV)/bin/python $$b || exit 1; done

# The long fuzz run (20,000 mutated inputs; see docs/robustness.md): FUZZ_ARGS="--cases 2000 --seed 7" for others.
fuzz: setup
	$(VENV)/bin/python benchmarks/fuzz.py $(FUZZ_ARGS)

clean:
	rm -rf $(VENV) build *.egg-info
