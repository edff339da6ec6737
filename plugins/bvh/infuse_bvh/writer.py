""":class:`infuse.Asset` -> BVH text: the skeleton and its first motion (or the rest pose).

Layout. An asset read from BVH is written with the channels, unit and up axis it was read with
(``Asset.meta["channels"]``, ``source_units``, ``source_up_axis``), so read -> write -> read gives
the same global joint positions. Any other asset is written in **centimetres, +Y up**, the scale
Blender's BVH importer and most tools expect, with ``Zrotation Xrotation Yrotation`` on every
joint and ``Xposition Yposition Zposition`` on roots and on joints whose translation is animated.
A joint whose motion needs channels its recorded layout lacks (a rotation about an axis it has no
channel for, a translation it cannot express) gets the missing ones added.

Rest rotations. BVH has none: a joint's frame at rest is the world frame. The writer folds the
asset's global rest rotations ``G`` into offsets and channels, ``offset_j = G_parent · t_j`` and
``R_j = G_parent · L_j · G_j^-1``, which keeps every global joint position. Angles are degrees,
intrinsic, first listed axis outermost (``ZXY`` means ``R = Rz · Rx · Ry``). Numbers carry ten
significant digits.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS
from infuse.errors import UnusableInputError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .parse import CHANNEL_NAMES

DEFAULT_ROTATION = ("Zrotation", "Xrotation", "Yrotation")
POSITIONS = ("Xposition", "Yposition", "Zposition")
DEFAULT_UNITS = "cm"
NUMBER = "%.10g"
#: Below this (degrees) an angle the layout has no channel for counts as zero.
ANGLE_TOLERANCE_DEG = 1e-6
#: Below this (metres) a translation the layout has no channel for counts as its offset.
TRANSLATION_TOLERANCE_M = 1e-9


def _recorded_layout(asset: Asset, skeleton: Skeleton) -> list[tuple[str, ...]] | None:
    channels = asset.meta.get("channels") if asset.format == "bvh" else None
    if not isinstance(channels, dict) or list(channels) != list(skeleton.names):
        return None
    layout = [tuple(channels[n]) for n in skeleton.names]
    if not all(c in CHANNEL_NAMES for chans in layout for c in chans):
        return None
    return layout


def _default_layout(skeleton: Skeleton, translations: np.ndarray) -> list[tuple[str, ...]]:
    moving = np.any(np.abs(translations - skeleton.rest_translations) > TRANSLATION_TOLERANCE_M, axis=(0, 2))
    moving[skeleton.roots] = True
    return [(POSITIONS + DEFAULT_ROTATION) if moving[j] else DEFAULT_ROTATION for j in range(skeleton.num_joints)]


def _euler(rotations: np.ndarray, order: str) -> np.ndarray:
    """(N, len(order)) intrinsic Euler angles in degrees; raises ValueError if ``order`` cannot express them."""
    missing = "".join(a for a in "XYZ" if a not in order)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # gimbal lock: scipy picks a valid solution
        angles = quat.to_euler(order + missing, rotations, degrees=True)
    if missing and np.any(np.abs(angles[:, len(order):]) > ANGLE_TOLERANCE_DEG):
        raise ValueError(order)
    return angles[:, : len(order)]


def bvh_frame(skeleton: Skeleton, motion: Motion, unit_scale: float, up_axis: str):
    """Offsets, end-site offsets, local rotations and translations in BVH's frame (file units, no rest rotations).

    Returns ``(offsets (J,3), site_offsets (E,3), rotations (F,J,4), translations (F,J,3))``.
    """
    to_file = quat.conjugate(UP_AXIS_ROTATIONS[up_axis])
    roots = skeleton.roots
    rest_rot = np.array(skeleton.rest_rotations)
    rest_rot[roots] = quat.multiply(to_file, rest_rot[roots])
    rest_t = np.array(skeleton.rest_translations)
    rest_t[roots] = quat.rotate(to_file, rest_t[roots])
    rest = Skeleton(skeleton.names, skeleton.parents, rest_t / unit_scale, rest_rot,
                    skeleton.end_site_parents, skeleton.end_site_offsets / unit_scale)
    g_rest = rest.rest_global_rotations
    g_parent = np.where((skeleton.parents >= 0)[:, None], g_rest[skeleton.parents], quat.IDENTITY)
    offsets = quat.rotate(g_parent, rest.rest_translations)
    sites = quat.rotate(g_rest[skeleton.end_site_parents], rest.end_site_offsets)
    rots = np.array(motion.local_rotations)
    rots[:, roots] = quat.multiply(to_file, rots[:, roots])
    rots = quat.multiply(quat.multiply(g_parent, rots), quat.conjugate(g_rest))
    trans = motion.local_translations()
    trans[:, roots] = quat.rotate(to_file, trans[:, roots])
    trans = quat.rotate(g_parent, trans / unit_scale)
    return offsets, sites, rots, trans


def channel_values(layout, offsets, rotations, translations, unit_scale):
    """The final per-joint channel lists and the (F, C) matrix of their values, file order per joint.

    A joint whose motion its listed channels cannot express gets the missing channels added.
    """
    frames = rotations.shape[0]
    final: list[tuple[str, ...]] = []
    columns: list[np.ndarray] = []
    for j, chans in enumerate(layout):
        rot_order = "".join(c[0] for c in chans if c.endswith("rotation"))
        pos_axes = [c[0] for c in chans if c.endswith("position")]
        try:
            angles = _euler(rotations[:, j], rot_order) if rot_order else None
            if not rot_order and np.any(quat.angle_between(rotations[:, j], quat.IDENTITY) > np.radians(ANGLE_TOLERANCE_DEG)):
                raise ValueError(rot_order)
        except ValueError:
            full = rot_order + "".join(a for a in "XYZ" if a not in rot_order)
            chans = tuple(c for c in chans if c.endswith("position")) + tuple(f"{a}rotation" for a in full)
            rot_order, angles = full, _euler(rotations[:, j], full)
        fixed = [k for k, a in enumerate("XYZ") if a not in pos_axes]
        if np.any(np.abs(translations[:, j, fixed] - offsets[j, fixed]) * unit_scale > TRANSLATION_TOLERANCE_M):
            chans = POSITIONS + tuple(c for c in chans if c.endswith("rotation"))
        k_rot = 0
        for c in chans:
            if c.endswith("rotation"):
                columns.append(angles[:, k_rot])
                k_rot += 1
            else:
                columns.append(translations[:, j, "XYZ".index(c[0])])
        final.append(tuple(chans))
    values = np.stack(columns, axis=1) if columns else np.zeros((frames, 0))
    return final, values


def _depth_first(skeleton: Skeleton) -> list[int]:
    order: list[int] = []
    stack = [int(r) for r in skeleton.roots[::-1]]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(skeleton.children[j]))
    return order


def _numbers(values) -> str:
    return " ".join(NUMBER % v for v in values)


def to_text(asset: Asset) -> str:
    """The BVH document for ``asset`` (see the module docstring for the layout)."""
    skeleton = asset.skeleton
    motion = next(iter(asset.motions.values()), None) or Motion.rest_pose(skeleton, 1)
    if motion.skeleton.names != skeleton.names:
        skeleton = motion.skeleton
    layout = _recorded_layout(asset, skeleton)
    if layout is not None:
        units, up_axis = asset.source_units, asset.source_up_axis
    else:
        units, up_axis = DEFAULT_UNITS, "Y"
    if units not in UNIT_SCALES or up_axis not in UP_AXIS_ROTATIONS:
        raise UnusableInputError(asset.path, f"cannot write BVH in unit {units!r} with up axis {up_axis!r}")
    scale = UNIT_SCALES[units]
    offsets, sites, rots, trans = bvh_frame(skeleton, motion, scale, up_axis)
    if layout is None:
        layout = _default_layout(skeleton, motion.local_translations())
    channels, values = channel_values(layout, offsets, rots, trans, scale)

    order = _depth_first(skeleton)
    sites_of: dict[int, list[int]] = {}
    for e, p in enumerate(skeleton.end_site_parents):
        sites_of.setdefault(int(p), []).append(e)
    lines = ["HIERARCHY"]
    depth_of = skeleton.depths

    def close_until(depth: int, open_joints: list[int]) -> None:
        while open_joints and depth_of[open_joints[-1]] >= depth:
            j = open_joints.pop()
            pad = "\t" * int(depth_of[j])
            for e in sites_of.get(j, ()):
                lines.extend((f"{pad}\tEnd Site", f"{pad}\t{{", f"{pad}\t\tOFFSET {_numbers(sites[e])}", f"{pad}\t}}"))
            lines.append(f"{pad}}}")

    open_joints: list[int] = []
    for j in order:
        close_until(int(depth_of[j]), open_joints)
        pad = "\t" * int(depth_of[j])
        keyword = "ROOT" if skeleton.parents[j] < 0 else "JOINT"
        lines.extend((f"{pad}{keyword} {skeleton.names[j]}", f"{pad}{{", f"{pad}\tOFFSET {_numbers(offsets[j])}"))
        if channels[j]:
            lines.append(f"{pad}\tCHANNELS {len(channels[j])} {' '.join(channels[j])}")
        open_joints.append(j)
    close_until(0, open_joints)

    frame_time = 1.0 / motion.fps
    recorded = asset.meta.get("frame_time") if asset.format == "bvh" else None
    if isinstance(recorded, float) and abs(recorded - frame_time) < 1e-9:
        frame_time = recorded  # keep the file's own digits
    lines += ["MOTION", f"Frames: {motion.num_frames}", f"Frame Time: {frame_time!r}"]

    starts = np.cumsum([0] + [len(c) for c in channels])
    columns = np.concatenate([np.arange(starts[j], starts[j + 1]) for j in order]).astype(np.int64)
    data = values[:, columns]
    width = data.shape[1]
    text = "\n".join(lines) + "\n"
    if width:
        row = " ".join([NUMBER] * width) + "\n"
        text += (row * data.shape[0]) % tuple(data.ravel().tolist())
    else:
        text += "\n" * data.shape[0]
    return text


def write(asset: Asset, path: str | Path, **_options) -> None:
    """Write ``asset`` as BVH to ``path`` (see the module docstring)."""
    Path(path).write_text(to_text(asset), encoding="utf-8", newline="\n")
