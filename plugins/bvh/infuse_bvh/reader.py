"""BVH file -> :class:`infuse.Asset` in the core frame (metres, +Y up, quaternions x,y,z,w).

Euler channels are intrinsic in their listed order, the first axis outermost (``Zrotation
Xrotation Yrotation`` means ``R = Rz · Rx · Ry``), in degrees. Position channels replace the
matching components of a joint's OFFSET (as in Blender and most mocap tools); any joint may have
them (Bandai files animate every joint) and they then become ``Motion.joint_translations``.

BVH declares no unit and no up axis. The up axis is +Y unless the figure is clearly taller along
Z (:func:`infuse.conventions.guess_up_axis` on its extent averaged over a few frames, or on the
rest pose when there is no motion). The unit is the one of :data:`UNIT_CANDIDATES` that gives the
figure an adult's standing height (:func:`infuse.conventions.guess_unit` on
:func:`infuse.conventions.figure_height`: head-to-toe extent and hip height of the rest pose, or
of a few frames when the rest pose does not stand). Both measure the body only: leading
single-child joints such as a ground-projected root are left out. ``units=`` and ``up_axis=``
override both. ``Asset.meta`` keeps what a writer needs to reproduce the file: channels per
joint, the frame time and the unit scale.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS, body_joints, figure_height, guess_unit, guess_up_axis
from infuse.errors import InputError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .parse import BvhDocument, parse

_AXIS = {"X": 0, "Y": 1, "Z": 2}
#: Units a BVH file is guessed to use, the most common first (ties go to the earlier): centimetres
#: (MotionBuilder, Mixamo, Bandai), metres, CMU units (1/0.45 inch: the CMU database's amc2bvh and
#: cgspeed conversions), inches (Biovision, Poser), decimetres (MakeHuman), millimetres, feet.
UNIT_CANDIDATES = ("cm", "m", "cmu", "inch", "dm", "mm", "ft")
#: Frames whose poses decide the up axis, and the unit when the rest pose does not stand
#: (evenly spread over the clip).
UP_AXIS_SAMPLE_FRAMES = 8


@lru_cache(maxsize=64)
def channel_layout(channels: tuple[tuple[str, ...], ...]):
    """Column indices of the channels, as arrays for vectorized gathers (cached: files of one
    dataset share their layout; the arrays are read-only).

    Returns ``(rotation_columns, rotation_axes, position_columns)``: ``rotation_columns`` (J, 3)
    is the column of each joint's 1st, 2nd and 3rd rotation channel in file order (-1 where a
    joint has fewer), ``rotation_axes`` (J, 3) a permutation of (0, 1, 2) = (X, Y, Z) per joint
    starting with its listed axes (unlisted ones follow, with zero angles), and
    ``position_columns`` is ``(joints, axes, columns)``, one entry per position channel.
    """
    joints = len(channels)
    rot_cols = np.full((joints, 3), -1, dtype=np.int64)
    rot_axes = np.zeros((joints, 3), dtype=np.int64)
    pos_joints: list[int] = []
    pos_axes: list[int] = []
    pos_cols: list[int] = []
    column = 0
    for j, chans in enumerate(channels):
        axes: list[int] = []
        for c in chans:
            if c.endswith("rotation"):
                rot_cols[j, len(axes)] = column
                axes.append(_AXIS[c[0]])
            else:
                pos_joints.append(j)
                pos_axes.append(_AXIS[c[0]])
                pos_cols.append(column)
            column += 1
        rot_axes[j] = axes + [a for a in (0, 1, 2) if a not in axes]
    out = (rot_cols, rot_axes, np.array(pos_joints, dtype=np.int64), np.array(pos_axes, dtype=np.int64),
           np.array(pos_cols, dtype=np.int64))
    for array in out:
        array.setflags(write=False)
    return out[0], out[1], out[2:]


def local_rotations(values: np.ndarray, rotation_columns: np.ndarray, rotation_axes: np.ndarray) -> np.ndarray:
    """(F, J, 4) local rotations (x, y, z, w) from Euler channels in degrees, all frames at once.

    Intrinsic rotations in file order, R = R_a(v1) · R_b(v2) · R_c(v3), the first listed axis
    outermost; (a, b, c) is each joint's axis permutation and missing channels are zero angles.
    The product of the three half-angle quaternions is written out in closed form, with
    e_a x e_b = s e_c (s = +1 for XYZ, YZX, ZXY and -1 for the other orders).
    """
    frames, joints = values.shape[0], rotation_columns.shape[0]
    half = np.where(rotation_columns >= 0, values[:, rotation_columns], 0.0) * (np.pi / 360.0)  # (F, J, 3)
    s1, s2, s3 = np.moveaxis(np.sin(half), -1, 0)
    c1, c2, c3 = np.moveaxis(np.cos(half), -1, 0)
    a, b = rotation_axes[:, 0], rotation_axes[:, 1]
    sign = np.where((b - a) % 3 == 1, 1.0, -1.0)  # +1 when (a, b, c) is a cyclic permutation
    s1c2, c1s2, c1c2, s1s2 = s1 * c2, c1 * s2, c1 * c2, s1 * s2
    out = np.empty((frames, joints, 4))
    rows = np.arange(joints)
    out[:, rows, a] = c3 * s1c2 + sign * (s3 * c1s2)
    out[:, rows, b] = c3 * c1s2 - sign * (s3 * s1c2)
    out[:, rows, rotation_axes[:, 2]] = s3 * c1c2 + sign * (c3 * s1s2)
    out[..., 3] = c3 * c1c2 - sign * (s3 * s1s2)
    return out


def local_translations(doc: BvhDocument, position_columns) -> np.ndarray:
    """(F, J, 3) local translations in file units: OFFSETs with position channels written over them."""
    frames = doc.values.shape[0]
    out = np.broadcast_to(doc.offsets, (frames,) + doc.offsets.shape).copy()
    js, axes, cols = position_columns
    out[:, js, axes] = doc.values[:, cols]
    return out


def sampled_positions(parents: np.ndarray, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
    """(K, J, 3) global positions of a few frames, chaining rotation matrices joint by joint.

    For the handful of frames that decide the up axis this beats level-by-level FK, whose cost
    does not shrink with the frame count. ``rotations`` (K, J, 4), ``translations`` (K, J, 3).
    """
    local = quat.to_matrix(rotations)
    rot = np.empty_like(local)
    pos = np.empty(translations.shape)
    for j, p in enumerate(parents):
        if p < 0:
            rot[:, j], pos[:, j] = local[:, j], translations[:, j]
        else:
            rot[:, j] = rot[:, p] @ local[:, j]
            pos[:, j] = pos[:, p] + np.einsum("kab,kb->ka", rot[:, p], translations[:, j])
    return pos


def rest_positions(doc: BvhDocument) -> tuple[np.ndarray, np.ndarray]:
    """Global joint (J, 3) and end-site (E, 3) positions at rest, file units (BVH rests have no rotations)."""
    joints = np.array(doc.offsets)
    for j, p in enumerate(doc.parents):
        if p >= 0:
            joints[j] += joints[p]
    return joints, joints[doc.end_site_parents] + doc.end_site_offsets


def _unit(doc: BvhDocument, body: np.ndarray, axis: str, poses: np.ndarray | None,
          units: str | None) -> tuple[str, str | None]:
    """(unit, how it was guessed or None): ``units``, or the guess from the body's standing height."""
    if units is not None:
        if units not in UNIT_SCALES:
            raise InputError(None, "units", f"unknown unit {units!r}; known: {', '.join(UNIT_SCALES)}")
        return units, None
    up = UP_AXIS_ROTATIONS[axis]
    joints, sites = rest_positions(doc)
    rest = quat.rotate(up, np.concatenate((joints[body], sites[np.isin(doc.end_site_parents, body)])))
    frames = None if poses is None else quat.rotate(up, poses[:, body])
    height = figure_height(rest, 0, frames)  # body[0], the joint the body branches from, is the pelvis
    unit = guess_unit(height, UNIT_CANDIDATES)
    return unit, f"standing height {height:.4g} file units: {height * UNIT_SCALES[unit]:.2f} m in {unit}"


def _up_axis(doc: BvhDocument, body: np.ndarray, poses: np.ndarray | None, up_axis: str | None) -> str:
    """``up_axis``, or the axis a figure is tallest along, averaged over ``poses`` (K, J, 3) when given."""
    if up_axis is not None:
        if up_axis not in UP_AXIS_ROTATIONS:
            raise InputError(None, "up_axis", f"unknown up axis {up_axis!r}; known: {', '.join(UP_AXIS_ROTATIONS)}")
        return up_axis
    if poses is None:
        return guess_up_axis(rest_positions(doc)[0][body])
    spread = np.ptp(poses[:, body], axis=1).mean(axis=0)  # mean extent per axis over the sampled frames
    return guess_up_axis(np.stack((np.zeros(3), spread)))


def to_asset(path: Path, doc: BvhDocument, units: str | None = None, up_axis: str | None = None) -> Asset:
    """Convert a parsed document into the core frame (see the module docstring)."""
    joints = len(doc.names)
    rotation_columns, rotation_axes, position_columns = channel_layout(doc.channels)
    frames = doc.values.shape[0]
    rots = local_rotations(doc.values, rotation_columns, rotation_axes)
    pos_joints = position_columns[0]
    if np.any(pos_joints != 0):  # translations beyond joint 0's: Motion.joint_translations
        trans = local_translations(doc, position_columns)
        root = trans[:, 0]
    else:
        trans = None
        root = np.broadcast_to(doc.offsets[0], (frames, 3)).copy()
        root[:, position_columns[1]] = doc.values[:, position_columns[2]]
    body = body_joints(doc.parents)
    poses = None
    if frames and (up_axis is None or units is None):
        sample = np.unique(np.linspace(0, frames - 1, min(frames, UP_AXIS_SAMPLE_FRAMES)).astype(np.int64))
        sample_trans = np.broadcast_to(doc.offsets, (len(sample), joints, 3)).copy() if trans is None else trans[sample]
        sample_trans[:, 0] = root[sample]
        poses = sampled_positions(doc.parents, rots[sample], sample_trans)
    axis = _up_axis(doc, body, poses, up_axis)
    unit, unit_guess = _unit(doc, body, axis, poses, units)
    scale = UNIT_SCALES[unit]
    up = UP_AXIS_ROTATIONS[axis]
    roots = np.flatnonzero(doc.parents < 0)
    rest_translations = doc.offsets * scale
    rest_rotations = quat.identity((joints,))
    if axis != "Y":
        rest_translations[roots] = quat.rotate(up, rest_translations[roots])
        rest_rotations[roots] = up
    skeleton = Skeleton(doc.names, doc.parents, rest_translations, rest_rotations,
                        doc.end_site_parents, doc.end_site_offsets * scale)
    motions = {}
    if frames:
        root = root * scale
        if axis != "Y":
            rots[:, roots] = quat.multiply(up, rots[:, roots])
            root = quat.rotate(up, root)
        if trans is not None:
            trans *= scale
            if axis != "Y":
                trans[:, roots] = quat.rotate(up, trans[:, roots])
        motion = Motion(skeleton, 1.0 / doc.frame_time, rots, root, trans, name=path.stem)
        motions[motion.name] = motion
    meta = {
        "channels": {n: list(c) for n, c in zip(doc.names, doc.channels)},
        "frame_time": doc.frame_time,
        "unit_scale_m": scale,
    }
    if unit_guess is not None:
        meta["units_guess"] = unit_guess
    return Asset(path=path, format="bvh", skeleton=skeleton, motions=motions, source_units=unit,
                 source_up_axis=axis, units_detected_by="override" if units is not None else "guess", meta=meta)


def read(path: str | Path, units: str | None = None, up_axis: str | None = None, **_options) -> Asset:
    """Read a BVH file into an :class:`~infuse.Asset` (see the module docstring for conventions)."""
    path = Path(path)
    try:
        return to_asset(path, parse(path), units=units, up_axis=up_axis)
    except InputError as exc:
        if exc.file is None:  # raised by the core's checks (finite values, options): name the file
            raise exc.naming(path) from None
        raise
