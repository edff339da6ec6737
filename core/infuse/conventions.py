"""Units and up axes: how readers bring a file's coordinates into the core frame.

The core frame is metres, right-handed, +Y up, +Z forward. A reader records what it found
(``Asset.source_units``, ``Asset.source_up_axis``) and honours explicit overrides.
"""
from __future__ import annotations

import numpy as np

from . import quaternions as quat

#: metres per unit. "cmu" is the CMU amc2bvh unit (1/0.45 inch).
UNIT_SCALES: dict[str, float] = {
    "m": 1.0,
    "dm": 0.1,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "ft": 0.3048,
    "cmu": 0.0254 / 0.45,
}

#: Rotation taking a file's up axis to +Y (for right-handed files).
UP_AXIS_ROTATIONS: dict[str, np.ndarray] = {
    "Y": quat.IDENTITY,
    "Z": quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), -np.pi / 2),  # +Z up -> +Y up, +Y -> -Z
    "X": quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2),  # +X up -> +Y up
    "-Y": quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi),
    "-Z": quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2),
}

#: Typical human standing height in metres, the prior used when a file states no unit.
HUMAN_HEIGHT_M = 1.7


def unit_scale(unit: str) -> float:
    """Metres per ``unit``; raises KeyError with the known names for an unknown unit."""
    try:
        return UNIT_SCALES[unit]
    except KeyError:
        raise KeyError(f"unknown unit {unit!r}; known: {', '.join(UNIT_SCALES)}") from None


def guess_unit(extent: float, candidates: tuple[str, ...] = ("m", "cm", "mm")) -> str:
    """The unit in ``candidates`` that makes a figure of size ``extent`` closest to a human height.

    Closeness is measured on a log scale. ``extent`` is the rest pose's largest extent in file units.
    """
    if not np.isfinite(extent) or extent <= 0:
        return "m"
    return min(candidates, key=lambda u: abs(np.log(extent * UNIT_SCALES[u] / HUMAN_HEIGHT_M)))


def guess_up_axis(positions: np.ndarray) -> str:
    """``"Y"`` or ``"Z"``: the axis along which rest joint positions (J,3) spread the most.

    Humanoid rests (T, A or relaxed) are taller than wide, so the largest spread of Y and Z is up.
    """
    spread = np.ptp(np.asarray(positions, dtype=np.float64), axis=0)
    return "Z" if spread[2] > spread[1] * 1.05 else "Y"
