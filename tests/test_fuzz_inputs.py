"""The quick fuzz run: mutated files of every format end in a typed error or a clean load.

Hypothesis draws a seed and one to four mutations (fixed seed, no example database) per case; each
case runs in a child process with a memory and a time limit (see ``fuzz_support``). A typed error is
exit code 2 or 3 with one line naming the file; a load reads finite numbers and writes back as glTF and
BVH. The long run is ``benchmarks/fuzz.py``.
"""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, seed, settings, strategies as st

from corpus_data import CORPUS, UNDER_CI, corpus_available
from fuzz_support import FORMATS, GOOD, KINDS, Worker, built_seeds, corpus_seeds, mutate

#: Cases per format; the text formats that parse in milliseconds get more.
CASES = {"bml": 300, "scene": 300}
DEFAULT_CASES = 100
#: Largest corpus file used as a seed here, and largest mutated case (the long run takes bigger ones).
MAX_SEED_BYTES = 64_000
MAX_CASE_BYTES = 256_000
OPS = st.lists(st.tuples(st.sampled_from(KINDS), st.floats(0.0, 1.0), st.integers(0, 2 ** 32 - 1)), min_size=1, max_size=4)


@pytest.fixture(scope="module")
def worker():
    w = Worker(timeout_s=20.0, memory_bytes=1 << 30)
    yield w
    w.close()


def _seeds(fmt: str) -> list:
    seeds = built_seeds(fmt)
    if corpus_available():
        seeds += corpus_seeds(fmt, [CORPUS], MAX_SEED_BYTES)[:6]
    if not seeds:
        message = f"no seed for {fmt}: corpus not found at {CORPUS} (set INFUSE_CORPUS)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return seeds


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_mutated_input_is_a_typed_error_or_a_clean_load(fmt, worker):
    seeds = _seeds(fmt)
    outcomes = []

    @seed(21)
    @settings(max_examples=CASES.get(fmt, DEFAULT_CASES), derandomize=True, database=None, deadline=None,
              suppress_health_check=list(HealthCheck), print_blob=False)
    @given(st.integers(0, len(seeds) - 1), OPS)
    def case(index, ops):
        outcome = worker.run(fmt, seeds[index], mutate(seeds[index].data, ops, MAX_CASE_BYTES))
        outcomes.append(outcome.kind)
        assert outcome.kind in GOOD, f"{outcome.kind}: {outcome.detail} (seed {seeds[index].label}, ops {ops})"

    case()
    # every drawn case ran, and the mutations reached the parsers' own errors
    assert "typed error" in outcomes and len(outcomes) >= CASES.get(fmt, DEFAULT_CASES) // 2
