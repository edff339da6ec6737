"""4x4 affine matrices for building test scenes by hand (column vectors, right-handed, degrees)."""
from __future__ import annotations

import numpy as np


def rotation(axis: str, deg: float) -> np.ndarray:
    """4x4 rotation by ``deg`` degrees about ``axis`` ("x", "y" or "z"), counter-clockwise seen from +axis."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def translation(v) -> np.ndarray:
    """4x4 translation by ``v`` (3,)."""
    m = np.eye(4)
    m[:3, 3] = v
    return m
