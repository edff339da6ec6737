"""Reading ``.sk`` and ``.skm`` files into :class:`~infuse.asset.Asset` (metres, +Y up, +Z forward).

SmartBody already uses the core's axes, so by default only lengths are scaled. Options:
``units`` overrides the length unit of the file being read (for an ``.skm``, of its position
channels; its ``.sk`` keeps its own unit), ``up_axis`` ("Y" or "Z") declares the file's up axis,
and for ``.skm`` files ``skeleton=PATH`` names the ``.sk`` to play the motion on (``"none"``: no
skeleton, the channel joints alone).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from infuse import conventions
from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.errors import InputError, UsageError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .discover import find_skeleton, load_sk
from .pose import Rig, animate
from .sk import SkFile, parse_sk
from .skm import parse_skm
from .timing import frame_rate, resample


def _read_text(path: Path) -> str:
    data = path.read_bytes()
    if b"\x00" in data[:4096]:
        raise InputError(path, None, "binary data, not SmartBody text")
    return data.decode("utf-8", errors="replace")


def _scale(unit: str) -> float:
    try:
        return conventions.unit_scale(unit)
    except KeyError as exc:
        raise UsageError(str(exc.args[0])) from None


def _up_rotation(up_axis: str | None) -> tuple[str, np.ndarray]:
    axis = up_axis or "Y"
    if axis not in conventions.UP_AXIS_ROTATIONS:
        raise UsageError(f"unknown up axis {axis!r}; known: {', '.join(conventions.UP_AXIS_ROTATIONS)}")
    return axis, conventions.UP_AXIS_ROTATIONS[axis]


def _skeleton(path: Path, names, parents, translations, rotations) -> Skeleton:
    try:
        return Skeleton(names, parents, translations, rotations)
    except InputError as exc:
        raise exc.naming(path) from None


def sk_units(sk: SkFile, override: str | None = None) -> tuple[str, str, str]:
    """(unit, detected_by, rule) for a skeleton: the override, the header's ``Units:``, or a guess."""
    if override:
        return override, "override", "given by the caller"
    if sk.units:
        return sk.units, "file", f"header comment on line {sk.units_line}"
    rest_t, rest_r = Rig.from_sk(sk, 1.0).rest()
    skeleton = _skeleton(sk.path, sk.names, sk.parents, rest_t, rest_r)
    height = conventions.body_height(skeleton.rest_global_positions, skeleton.parents,
                                     skeleton.rest_end_site_positions, skeleton.end_site_parents)
    unit = conventions.guess_unit(height)
    return unit, "guess", f"no Units header; standing height {height:.4g} file units fits a human in {unit}"


def _channel_meta(sk: SkFile) -> dict:
    return {j.name: dict(j.channels) for j in sk.joints if j.channels}


def read_sk(path: Path, units: str | None = None, up_axis: str | None = None) -> Asset:
    """A SmartBody ``.sk`` skeleton; ``meta`` keeps channels, limits and pre-rotations as written."""
    path = Path(path)
    sk = parse_sk(path, _read_text(path))
    unit, detected_by, rule = sk_units(sk, units)
    rest_t, rest_r = Rig.from_sk(sk, _scale(unit)).rest()
    axis, up = _up_rotation(up_axis)
    skeleton = _skeleton(path, sk.names, sk.parents, rest_t, rest_r).transformed(1.0, up)
    meta: dict[str, object] = {
        "name": sk.name,
        "units_rule": rule,
        "channels": _channel_meta(sk),
        "prerot_joints": [j.name for j in sk.joints if not np.allclose(j.prerot, quat.IDENTITY)],
        "euler_joints": {j.name: j.euler_type for j in sk.joints if j.rot_type == "euler"},
    }
    if sk.scale != 1.0:
        meta["set_scale"] = sk.scale
    if sk.collision_free_pairs:
        meta["collision_free_pairs"] = sk.collision_free_pairs
    return Asset(path, "smartbody-sk", skeleton, source_units=unit, source_up_axis=axis,
                 units_detected_by=detected_by, meta=meta, payload=sk)


def _motion_units(skm, sk_unit: tuple[str, str, str] | None, override: str | None) -> tuple[str, str, str]:
    if override:
        return override, "override", "given by the caller"
    if skm.units:
        return skm.units, "file", f"header comment on line {skm.units_line}"
    if sk_unit is not None:
        return sk_unit[0], "guess", "no Units header; same unit as the skeleton file"
    return "m", "guess", "no Units header and no skeleton file; assumed metres"


def read_skm(path: Path, units: str | None = None, up_axis: str | None = None, skeleton: str | Path | None = None) -> Asset:
    """A SmartBody ``.skm`` motion on its skeleton (``skeleton=PATH`` or found beside the file).

    A channel naming a joint the skeleton lacks is an error; with no skeleton found (or
    ``skeleton="none"``) the joints are the channel joints alone, all roots at the origin.
    ``meta["skeleton_file"]`` says which ``.sk`` was used. Timing metadata (ready, stroke, relax...) become ``sync_points`` in seconds
    from the first frame. The motion's ``animated_joints`` marks the joints its channels name.
    """
    path = Path(path)
    skm = parse_skm(path, _read_text(path))
    meta: dict = {"name": skm.name, "channels": len(skm.channels)}
    if skeleton == "none":
        sk, meta["skeleton_found_in"] = None, "not used (skeleton='none')"
    elif skeleton is not None:
        sk_path = Path(skeleton)
        if not sk_path.is_file():
            raise InputError(sk_path, None, "skeleton file not found")
        sk = load_sk(sk_path)
        meta["skeleton_found_in"] = "given by the caller"
    else:
        sk, record = find_skeleton(path, skm.joints)
        meta.update(record)
    if sk is not None:
        known = set(sk.names)
        unknown = next((c for c in skm.channels if c.joint not in known), None)
        if unknown is not None:
            raise InputError(path, f"line {unknown.line}", f"channel {unknown.joint} {unknown.type}: joint "
                             f"{unknown.joint!r} is not in the skeleton {sk.path.name} (pass skeleton=PATH, or 'none')")
        sk_unit = sk_units(sk)
        rig = Rig.from_sk(sk, _scale(sk_unit[0]))
        meta.update(skeleton_file=str(sk.path), skeleton_units=sk_unit[0], skeleton_units_rule=sk_unit[2])
    else:
        sk_unit = None
        rig = Rig.free_roots(skm.joints)
        meta["skeleton_file"] = None
        meta["skeleton_note"] = "no .sk used: flat skeleton of the channel joints, all roots at the origin"
    unit, detected_by, rule = _motion_units(skm, sk_unit, units)
    meta["units_rule"] = rule

    rotations, translations, notes = animate(rig, skm, _scale(unit))
    meta.update({k: v for k, v in notes.items() if v})
    fps, regular = frame_rate(skm.key_times, path)
    if not regular:
        rotations, translations = resample(skm.key_times, fps, rotations, translations)
        meta["resampled"] = f"irregular key times resampled to {fps:g} fps"
    if skm.key_times.size == 1:
        meta["fps_note"] = f"single frame; {fps:g} fps assumed"

    axis, up = _up_rotation(up_axis)
    rest_t, rest_r = rig.rest()
    roots = rig.parents < 0
    rotations[:, roots] = quat.multiply(up, rotations[:, roots])
    translations[:, roots] = quat.rotate(up, translations[:, roots])
    skel = _skeleton(path, rig.names, rig.parents, rest_t, rest_r).transformed(1.0, up)
    joint_translations = None
    if np.any(np.abs(translations[:, 1:] - skel.rest_translations[1:]) > 1e-12):
        joint_translations = translations
    base = skm.start_kt if skm.start_kt is not None else float(skm.key_times[0])
    sync = {name: t - base for name, t in skm.timings.items()}
    if skm.metadata:
        meta["metadata"] = skm.metadata
    meta["first_key_time"] = float(skm.key_times[0])
    try:
        motion = Motion(skel, fps, rotations, translations[:, 0], joint_translations, name=skm.name, sync_points=sync,
                        animated_joints=np.isin(skel.names, skm.joints))
    except InputError as exc:
        raise exc.naming(path) from None
    return Asset(path, "smartbody-skm", skel, {skm.name: motion}, source_units=unit, source_up_axis=axis,
                 units_detected_by=detected_by, meta=meta, payload=(skm, sk))
