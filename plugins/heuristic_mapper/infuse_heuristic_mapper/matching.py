"""The least-cost one-to-one matching of a small cost matrix (rows to columns), exactly.

Sub-decisions of the mapper that pair a few things with a few roles (finger chains with the
digits index..pinky) are bipartite matchings; their matrices are at most a handful wide, so every
matching is scored at once (numpy over the permutations) instead of greedily one after another.
"""
from __future__ import annotations

from functools import lru_cache
from itertools import permutations

import numpy as np


#: Matrices this wide at most: every matching is enumerated (7 columns: 5,040 matchings).
MAX_COLUMNS = 7


@lru_cache(maxsize=32)
def _injections(rows: int, cols: int) -> np.ndarray:
    """(N, rows) every way of giving each of ``rows`` items a different one of ``cols`` columns."""
    return np.array(list(permutations(range(cols), rows)), dtype=np.int64).reshape(-1, rows)


def best_matching(cost: np.ndarray) -> tuple[np.ndarray, float]:
    """Column of each row in the least-cost matching of ``cost`` (R, C) with R <= C (each row one
    column, no column twice), and the cost margin to the second-best matching (inf when there is
    only one)."""
    rows, cols = cost.shape
    if rows > cols or cols > MAX_COLUMNS:
        raise ValueError(f"a matching of {rows} rows into {cols} columns (at most {MAX_COLUMNS} columns)")
    options = _injections(rows, cols)
    totals = cost[np.arange(rows), options].sum(axis=1)
    order = np.argsort(totals, kind="stable")
    margin = float(totals[order[1]] - totals[order[0]]) if len(order) > 1 else np.inf
    return options[order[0]], margin
