VENV := .venv
TEST_WORKERS ?= 2

.PHONY: setup demo test bench clean

setup:
	@scripts/setup.sh

demo: setup
	$(VENV)/bin/python examples/demo.py

test: setup
	$(VENV)/bin/python -m pytest -q -n $(TEST_WORKERS) tests

bench: setup
	@for b in benchmarks/*.py; do echo "== $$b"; $(VENV)/bin/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info
