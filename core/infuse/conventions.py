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

#: Typical human standing height in metres (the figure size a reader scales to when no unit fits).
HUMAN_HEIGHT_M = 1.7
#: Standing heights, metres, that count as an adult human's when a unit is guessed.
HUMAN_HEIGHT_RANGE_M = (1.4, 2.0)
#: Hip joint height as a share of standing height (adult anthropometry puts it near 0.52).
HIP_HEIGHT_SHARE = 0.52
#: Hip height over head-to-toe extent for which the hip height is trusted: a human's is about 0.5;
#: CMU figures, whose torso and head are short, reach 0.68. Outside (no legs, a pelvis chosen
#: badly) only the extent is used.
HIP_SHARE_TRUSTED = (0.4, 0.8)
#: A pose is upright when it is at least this tall (along +Y) for its widest horizontal extent:
#: T and A poses are about 1, walking frames 2 to 3, a rest pose laid along one axis about 0.1.
UPRIGHT_RATIO = 0.5
#: Two units whose misses (natural log of how far the figure falls outside
#: :data:`HUMAN_HEIGHT_RANGE_M`) differ by less than this are a tie: the one listed first wins.
UNIT_TIE_LOG = float(np.log(1.1))


def unit_scale(unit: str) -> float:
    """Metres per ``unit``; raises KeyError with the known names for an unknown unit."""
    try:
        return UNIT_SCALES[unit]
    except KeyError:
        raise KeyError(f"unknown unit {unit!r}; known: {', '.join(UNIT_SCALES)}") from None


def unit_miss(size: float, unit: str) -> float:
    """How far a figure of ``size`` file units, read in ``unit``, falls outside
    :data:`HUMAN_HEIGHT_RANGE_M`: 0 inside, else the natural log of the ratio to the nearer bound."""
    lo, hi = HUMAN_HEIGHT_RANGE_M
    metres = size * UNIT_SCALES[unit]
    return float(max(np.log(lo / metres), np.log(metres / hi), 0.0))


def guess_unit(size: float, candidates: tuple[str, ...] = ("m", "cm", "mm")) -> str:
    """The unit in ``candidates`` that makes a figure of ``size`` file units an adult human's height.

    ``size`` is the figure's standing height in file units (:func:`figure_height`), or at least
    its largest extent. Each unit is scored by :func:`unit_miss`; the lowest miss wins, and misses
    within :data:`UNIT_TIE_LOG` of it tie, won by the unit listed first: list ``candidates`` from
    the most to the least common for the format.
    """
    if not np.isfinite(size) or size <= 0:
        return "m"
    misses = [unit_miss(size, u) for u in candidates]
    if not all(np.isfinite(misses)):  # a size no unit makes human (1e308 file units): the first candidate
        return candidates[0]
    best = min(misses)
    return next(u for u, miss in zip(candidates, misses) if miss - best < UNIT_TIE_LOG)


def standing_heights(points: np.ndarray, pelvis: int) -> np.ndarray:
    """The standing height (file units) each upright pose of a human figure implies.

    ``points`` (..., N, 3): joint and end-site positions of one or more poses, +Y up, file units;
    ``pelvis``: the index among them of the joint the legs hang from. Returns shape ``(...)``.

    Two readings, both of which read short more often than long: the head-to-toe extent (short
    when the head ends at its joint with no head-top end site, or the torso is short, as CMU's;
    long when the arms are raised) and the hip height over :data:`HIP_HEIGHT_SHARE` (short when
    the knees bend; legs are what motion capture measures best). The larger is used; the hip
    reading only when the hip sits where a human's does (:data:`HIP_SHARE_TRUSTED` of the extent).
    """
    y = np.asarray(points, dtype=np.float64)[..., 1]
    extent = np.ptp(y, axis=-1)
    hip = y[..., pelvis] - y.min(axis=-1)
    share = np.divide(hip, extent, out=np.zeros_like(extent), where=extent > 0)
    lo, hi = HIP_SHARE_TRUSTED
    trusted = (share >= lo) & (share <= hi)
    return np.where(trusted, np.maximum(extent, hip / HIP_HEIGHT_SHARE), extent)


def body_joints(parents: np.ndarray) -> np.ndarray:
    """Indices of the figure itself: the subtree of the first joint below root 0 that branches.

    Leading single-child joints (a ground-projected ``joint_Root``, a ``reference`` node) may sit
    metres away from the body; they would distort any size or orientation measured on positions.
    A skeleton that never branches (a plain chain) is all body. ``parents`` (J,), parents first.
    """
    parents = np.asarray(parents, dtype=np.int64)
    joints = len(parents)
    if joints == 0:
        return np.arange(0)
    children = np.bincount(parents[parents >= 0], minlength=joints)
    j = 0
    while children[j] == 1:
        j = int(np.flatnonzero(parents == j)[0])
    if children[j] == 0:
        return np.arange(joints)
    inside = np.zeros(joints, dtype=bool)
    inside[j] = True
    for i in range(j + 1, joints):  # parents precede children
        p = parents[i]
        inside[i] = p >= 0 and inside[p]
    return np.flatnonzero(inside)


def body_height(positions: np.ndarray, parents: np.ndarray, sites: np.ndarray | None = None,
                site_parents: np.ndarray | None = None) -> float:
    """A skeleton's standing height in file units, the size :func:`guess_unit` expects.

    :func:`figure_height` of its rest pose's body (:func:`body_joints`, the joint it branches from
    taken as the pelvis) and the end sites hanging from it. ``positions`` (J, 3) are the rest joint
    positions, +Y up; ``sites`` (E, 3) end-site positions with their parent joints ``site_parents`` (E,).
    """
    body = body_joints(parents)
    points = np.asarray(positions, dtype=np.float64)[body]
    if sites is not None and site_parents is not None and len(sites):
        points = np.concatenate((points, np.asarray(sites, dtype=np.float64)[np.isin(site_parents, body)]))
    return figure_height(points, 0)


def upright(points: np.ndarray) -> np.ndarray:
    """Whether each pose ``points`` (..., N, 3), +Y up, stands: see :data:`UPRIGHT_RATIO`."""
    extent = np.ptp(np.asarray(points, dtype=np.float64), axis=-2)
    return extent[..., 1] >= UPRIGHT_RATIO * np.maximum(extent[..., 0], extent[..., 2])


def figure_height(rest: np.ndarray, pelvis: int, poses: np.ndarray | None = None) -> float:
    """A figure's standing height in file units, the size :func:`guess_unit` expects.

    ``rest`` (N, 3): the rest pose's joint and end-site positions, +Y up; ``poses`` (K, M, 3):
    optional animated poses (joints only is fine), +Y up; ``pelvis`` indexes the hip joint in both.
    Measured (:func:`standing_heights`) on the rest pose when it is upright, else as the median
    over the upright ``poses`` (a rest pose laid along one axis, as Bandai's), else the rest
    pose's largest extent.
    """
    rest = np.asarray(rest, dtype=np.float64)
    if len(rest) < 2:
        return 0.0
    if upright(rest):
        return float(standing_heights(rest, pelvis))
    if poses is not None and len(poses):
        poses = np.asarray(poses, dtype=np.float64)
        standing = poses[upright(poses)]
        if len(standing):
            return float(np.median(standing_heights(standing, pelvis)))
    return float(np.max(np.ptp(rest, axis=0)))


def guess_up_axis(positions: np.ndarray) -> str:
    """``"Y"`` or ``"Z"``: the axis along which rest joint positions (J,3) spread the most.

    Humanoid rests (T, A or relaxed) are taller than wide, so the largest spread of Y and Z is up.
    """
    spread = np.ptp(np.asarray(positions, dtype=np.float64), axis=0)
    return "Z" if spread[2] > spread[1] * 1.05 else "Y"
