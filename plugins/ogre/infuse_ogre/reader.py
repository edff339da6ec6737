"""Reading an Ogre ``.skeleton.xml`` into an :class:`~infuse.asset.Asset` (metres, +Y up).

Ogre semantics: a bone's local transform is T(position) R(rotation) S(scale), scale inherited.
A keyframe is an offset from the binding pose: position + translate, rotation * rotate,
scale * scale. Keys are interpolated linearly (rotations by shortest-path nlerp, Ogre's default);
past the last key a track wraps towards its first key over the animation length, as Ogre does.
Animations are resampled at 30 fps.

Ogre has no length unit. Unless ``units=`` is given, the unit is guessed from the figure's height
(its extent along the up axis): the named unit that makes it closest to a 1.7 m human, when that
gives a human-sized figure, otherwise a scale that makes it 1.7 m tall. ``meta["units_guess"]``
says which. The up axis is Ogre's +Y unless the binding pose is clearly taller along Z.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.conventions import HUMAN_HEIGHT_M, UNIT_SCALES, UP_AXIS_ROTATIONS, body_height, guess_unit, guess_up_axis
from infuse.errors import UnusableInputError, UsageError
from infuse.transforms import (compose, frame_change, global_matrices, require_finite, sampled_motion,
                               skeleton_from_globals)

from .skeleton_xml import Animation, Bones, parse

FPS = 30.0

#: Named units tried when guessing, and the figure heights (metres) accepted as human-sized.
UNIT_CANDIDATES = ("m", "cm", "mm", "inch")
HUMAN_HEIGHT_RANGE_M = (1.2, 2.3)

#: Largest animation read, in frames x bones (bounds memory on absurd lengths).
MAX_JOINT_FRAMES = 10_000_000


def read(path: Path, units: str | None = None, up_axis: str | None = None, **_options) -> Asset:
    """Read an Ogre skeleton XML file; see the module docstring for the conversions."""
    # Huge but finite numbers may overflow on the way; the model's checks then name the non-finite
    # joint, so numpy's own warnings would only add lines.
    with np.errstate(all="ignore"):
        return _read(Path(path), units, up_axis)


def _read(path: Path, units: str | None, up_axis: str | None) -> Asset:
    bones, animations = parse(path)
    rest_local = compose(bones.positions, bones.rotations, bones.scales)
    rest_global = global_matrices(bones.parents, rest_local[None])[0]
    require_finite(bones.names, rest_global, "binding pose")
    up, up_by = _up_axis(rest_global[:, :3, 3], up_axis)
    scale, unit_name, units_by, how = _units(path, rest_global[:, :3, 3], bones.parents, up, units)
    change = frame_change(scale, up)
    skeleton = skeleton_from_globals(bones.names, bones.parents, change @ rest_global)
    motions = {}
    for anim in animations:
        frames = int(np.floor(anim.length * FPS + 1e-6)) + 1
        if frames * len(bones.names) > MAX_JOINT_FRAMES:
            raise UnusableInputError(path, f"animation {anim.name!r} is too long to sample: {frames} frames")

        def globals_between(a, b, anim=anim):
            return change @ global_matrices(bones.parents, _animated_locals(bones, anim, np.arange(a, b) / FPS))

        motions[anim.name] = sampled_motion(skeleton, FPS, frames, globals_between, name=anim.name)
    meta = {"units_guess": how, "up_axis_detected_by": up_by,
            "bone_scales": bool(np.any(np.abs(bones.scales - 1.0) > 1e-9))}
    return Asset(path, "ogre", skeleton, motions, source_units=unit_name, source_up_axis=up,
                 units_detected_by=units_by, meta=meta)


def _up_axis(positions: np.ndarray, override: str | None) -> tuple[str, str]:
    if override is not None:
        if override not in UP_AXIS_ROTATIONS:
            raise UsageError(f"unknown up axis {override!r}; known: {', '.join(UP_AXIS_ROTATIONS)}")
        return override, "override"
    return guess_up_axis(positions), "guess"


def _units(path: Path, positions: np.ndarray, parents: np.ndarray, up: str,
           override: str | None) -> tuple[float, str, str, str]:
    """(metres per unit, unit name, how detected, how guessed) for bones at binding ``positions`` (J, 3)."""
    if override is not None:
        if override not in UNIT_SCALES:
            raise UsageError(f"unknown unit {override!r}; known: {', '.join(UNIT_SCALES)}")
        return UNIT_SCALES[override], override, "override", "given by the caller"
    height = body_height(quat.rotate(UP_AXIS_ROTATIONS[up], positions), parents)
    if not height > 1e-9:
        raise UnusableInputError(path, "the binding pose has no height: cannot guess its unit")
    unit = guess_unit(height, UNIT_CANDIDATES)
    lo, hi = HUMAN_HEIGHT_RANGE_M
    if lo <= height * UNIT_SCALES[unit] <= hi:
        return UNIT_SCALES[unit], unit, "guess", f"named unit {unit!r} makes the {height:.4g}-unit figure human-sized"
    scale = HUMAN_HEIGHT_M / height
    return scale, f"{scale:.6g} m", "guess", (f"no named unit makes the {height:.4g}-unit figure human-sized; "
                                             f"scaled to {HUMAN_HEIGHT_M} m")


def _animated_locals(bones: Bones, anim: Animation, t: np.ndarray) -> np.ndarray:
    """Local matrices (F, J, 4, 4) of every bone at times ``t``: binding pose plus track offsets."""
    frames, j = len(t), len(bones.names)
    trans = np.broadcast_to(bones.positions, (frames, j, 3)).copy()
    rots = np.broadcast_to(bones.rotations, (frames, j, 4)).copy()
    scales = np.broadcast_to(bones.scales, (frames, j, 3)).copy()
    for track in anim.tracks:
        k1, k2, u = _key_pairs(track.times, anim.length, t)
        w = u[:, None]
        b = track.bone
        trans[:, b] += track.translations[k1] + w * (track.translations[k2] - track.translations[k1])
        scales[:, b] *= track.scales[k1] + w * (track.scales[k2] - track.scales[k1])
        q1, q2 = track.rotations[k1], track.rotations[k2]
        q2 = np.where(np.sum(q1 * q2, axis=-1, keepdims=True) < 0.0, -q2, q2)
        rots[:, b] = quat.multiply(rots[:, b], quat.normalize(q1 + w * (q2 - q1)))
    return compose(trans, rots, scales)


def _key_pairs(times: np.ndarray, length: float, t: np.ndarray):
    """Ogre's key lookup: indices of the keys around each time and the blend factor between them.

    Before the first key the first key holds; after the last key the track blends towards the
    first key, reached at ``length + times[0]``.
    """
    k = len(times)
    t = np.where((t > length) & (length > 0), np.fmod(t, length if length > 0 else 1.0), t)
    i = np.searchsorted(times, t, side="left")
    after_last = i >= k
    k2 = np.where(after_last, 0, np.minimum(i, k - 1))
    t2 = np.where(after_last, length + times[0], times[k2])
    step_back = after_last | ((i > 0) & (t < times[np.minimum(i, k - 1)]))
    k1 = np.where(step_back, np.maximum(np.minimum(i, k) - 1, 0), k2)
    t1 = times[k1]
    span = t2 - t1
    u = np.where(span > 0, (t - t1) / np.where(span > 0, span, 1.0), 0.0)
    return k1, k2, np.clip(u, 0.0, 1.0)
