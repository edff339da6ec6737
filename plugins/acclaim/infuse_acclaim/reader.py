"""Reading ``.asf`` and ``.amc`` files into :class:`~infuse.asset.Asset` (metres, +Y up, +Z forward).

Units: ``:units length L`` means one file unit is ``1/L`` inch (CMU writes ``length 0.45``); when
that gives no human-sized figure the unit is guessed from the rest pose. The up axis is guessed
from the rest pose (CMU files are +Y up). Options: ``units``, ``up_axis``, and for ``.amc``
``skeleton=PATH`` (the ``.asf``; otherwise one beside the motion whose bones match) and ``fps``
(AMC states no frame rate; CMU captured at 120 fps).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
from infuse import conventions
from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.errors import InfuseError, InputError, UnusableInputError, UsageError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .amc import AmcFile, bone_values, parse_amc
from .asf import ROTATION_DOFS, AsfFile, axis_rotation, parse_asf

#: AMC files state no frame rate; the CMU database was captured at 120 Hz.
DEFAULT_FPS = 120.0
_INCH = conventions.UNIT_SCALES["inch"]
#: Longest line of an ``.asf`` or ``.amc`` file (a keyword and a few values, a bone and its values). The
#: AMC parser makes the lines one fixed-width array, as wide as the longest line: this bounds it.
MAX_LINE_CHARS = 4096


def _read_text(path: Path) -> str:
    data = path.read_bytes()
    if b"\x00" in data[:4096]:
        raise InputError(path, None, "binary data, not Acclaim text")
    text = data.decode("utf-8", errors="replace")
    lengths = [len(line) for line in text.split("\n")]
    longest = max(lengths)
    if longest > MAX_LINE_CHARS:
        raise InputError(path, f"line {lengths.index(longest) + 1}", f"is {longest:,} characters long: not Acclaim text "
                         f"(a line holds a keyword or a bone and its values, at most {MAX_LINE_CHARS:,} characters)")
    return text


@lru_cache(maxsize=16)
def _load_asf(path: str, mtime_ns: int, size: int) -> AsfFile:
    return parse_asf(Path(path), _read_text(Path(path)))


def load_asf(path: Path) -> AsfFile:
    """Parse ``path`` (cached while the file is unchanged)."""
    st = path.stat()
    return _load_asf(str(path.absolute()), st.st_mtime_ns, st.st_size)


def _skeleton(asf: AsfFile, metres: float) -> Skeleton:
    """Joints at the start of each bone, world-aligned rest frames; leaf bones end in end sites."""
    names = ("root", *asf.order)
    index = {n: i for i, n in enumerate(names)}
    parents = np.array([-1] + [index[asf.parent[b]] for b in asf.order])
    offsets = np.zeros((len(names), 3))
    offsets[0] = asf.root_position
    for i, b in enumerate(asf.order, start=1):
        p = asf.parent[b]
        if p != "root":
            offsets[i] = asf.bones[p].direction * asf.bones[p].length
    has_child = set(asf.parent.values())
    leaves = [b for b in asf.order if b not in has_child and asf.bones[b].length > 0]
    ends = np.array([asf.bones[b].direction * asf.bones[b].length for b in leaves]).reshape(-1, 3)
    try:
        return Skeleton(names, parents, offsets * metres, quat.identity((len(names),)),
                        np.array([index[b] for b in leaves], dtype=np.int64), ends * metres)
    except InputError as exc:
        raise exc.naming(asf.path) from None


def _length_unit(asf: AsfFile, override: str | None) -> tuple[str, float, str, str]:
    """(unit name, metres per file unit, detected_by, rule)."""
    if override:
        try:
            return override, conventions.unit_scale(override), "override", "given by the caller"
        except KeyError as exc:
            raise UsageError(str(exc.args[0])) from None
    length = asf.length_scale
    if abs(length - 0.45) < 1e-9:
        return "cmu", _INCH / 0.45, "file", "units length 0.45: CMU units, 1/0.45 inch"
    name = "inch" if length == 1.0 else f"inch/{length:g}"
    scale = _INCH / length
    skeleton = _skeleton(asf, 1.0)
    height = conventions.body_height(skeleton.rest_global_positions, skeleton.parents,
                                     skeleton.rest_end_site_positions, skeleton.end_site_parents)
    if 0.5 < height * scale < 3.0:
        return name, scale, "file", f"units length {length:g}: 1/{length:g} inch"
    guess = conventions.guess_unit(height, ("m", "cm", "mm", "inch"))
    return guess, conventions.unit_scale(guess), "guess", (
        f"units length {length:g} read as 1/{length:g} inch gives a {height * scale:.3g} m figure; "
        f"standing height {height:.4g} fits a human in {guess}")


def _up_axis(skeleton: Skeleton, override: str | None) -> tuple[str, np.ndarray, str]:
    axis = override or conventions.guess_up_axis(skeleton.rest_global_positions)
    if axis not in conventions.UP_AXIS_ROTATIONS:
        raise UsageError(f"unknown up axis {axis!r}; known: {', '.join(conventions.UP_AXIS_ROTATIONS)}")
    return axis, conventions.UP_AXIS_ROTATIONS[axis], "given by the caller" if override else "guessed from the rest pose"


def _bone_meta(asf: AsfFile) -> dict:
    return {b.name: {"dof": b.dof, "limits": [list(limit) for limit in b.limits], "axis": b.axis.tolist(),
                     "axis_order": b.axis_order, "length": b.length, **b.extra} for b in asf.bones.values()}


def _prepare(asf: AsfFile, units: str | None, up_axis: str | None):
    unit, metres, detected_by, rule = _length_unit(asf, units)
    skeleton = _skeleton(asf, metres)
    axis, up, up_rule = _up_axis(skeleton, up_axis)
    meta = {"name": asf.name, "version": asf.version, "units_rule": rule, "up_axis_rule": up_rule,
            "mass": asf.units.get("mass"), "angle_unit": asf.units.get("angle", "deg"),
            "root_order": asf.root_order, "root_axis": asf.root_axis, "bones": _bone_meta(asf)}
    return unit, metres, detected_by, skeleton.transformed(1.0, up), axis, up, meta


def read_asf(path: Path, units: str | None = None, up_axis: str | None = None) -> Asset:
    """An Acclaim skeleton: one joint per bone start (plus ``root``), end sites at leaf bone tips."""
    path = Path(path)
    asf = parse_asf(path, _read_text(path))
    unit, _, detected_by, skeleton, axis, _, meta = _prepare(asf, units, up_axis)
    return Asset(path, "acclaim-asf", skeleton, source_units=unit, source_up_axis=axis,
                 units_detected_by=detected_by, meta=meta, payload=asf)


def _matching_asf(amc_path: Path, amc: AmcFile) -> tuple[AsfFile, dict]:
    """The ``.asf`` beside the motion that has all its bones; a name like ``11_01.amc`` prefers ``11.asf``."""
    bones = set(amc.values) - {"root"}
    candidates = sorted(p for p in amc_path.absolute().parent.glob("*.asf") if p.is_file())
    if not candidates:
        raise UnusableInputError(amc_path, "no .asf skeleton beside it; pass skeleton=PATH")
    fitting: list[tuple[int, AsfFile]] = []
    partial: list[tuple[int, AsfFile]] = []
    unreadable: dict[str, str] = {}
    for candidate in candidates:
        try:
            asf = load_asf(candidate)
        except (InfuseError, OSError, ValueError) as exc:
            unreadable[str(candidate)] = str(exc)
            continue
        missing = bones - set(asf.bones)
        (partial if missing else fitting).append((len(missing), asf))
    if not fitting:
        if not partial:
            raise UnusableInputError(amc_path, f"no readable .asf beside it ({len(unreadable)} unreadable); pass skeleton=PATH")
        best = min(partial, key=lambda c: c[0])[1]
        _check_bones(amc, best)
    stem = amc_path.stem.split("_")[0]
    fitting.sort(key=lambda c: (c[1].path.stem != stem, not amc_path.stem.startswith(c[1].path.stem), c[1].path.name))
    chosen = fitting[0][1]
    record: dict[str, object] = {"skeleton_file": str(chosen.path), "skeleton_candidates": [str(c) for c in candidates]}
    if len(fitting) > 1 and chosen.path.stem != stem:
        record["skeleton_note"] = f"{len(fitting)} .asf files fit; chose the first by name"
    if unreadable:
        record["skeleton_candidates_unreadable"] = unreadable
    return chosen, record


def _check_bones(amc: AmcFile, asf: AsfFile) -> None:
    for name in amc.values:
        if name != "root" and name not in asf.bones:
            raise InputError(amc.path, f"line {amc.lines[name][0]}", f"bone {name!r} is not in the skeleton {asf.path.name}")


def _local_rotations(asf: AsfFile, amc: AmcFile, radians: float, skeleton_names) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Local rotations (F,J,4) ``C M C^-1`` and root translations (F,3, file units) of every frame."""
    frames = amc.frames
    rotations = quat.identity((frames, len(skeleton_names)))
    root_t = np.broadcast_to(asf.root_position, (frames, 3)).copy()
    idle: list[str] = []
    if "root" in amc.values:
        vals = bone_values(amc, "root", len(asf.root_order))
        for k, channel in enumerate(asf.root_order):
            if channel[0] == "T":
                root_t[:, "XYZ".index(channel[1])] = vals[:, k]
        rot = [k for k, c in enumerate(asf.root_order) if c[0] == "R"]
        if rot:
            c = axis_rotation(asf.root_axis, asf.root_orientation * asf.radians_per_unit)
            m = axis_rotation("".join(asf.root_order[k][1] for k in rot), vals[:, rot] * radians)
            rotations[:, 0] = quat.multiply(c, quat.multiply(m, quat.conjugate(c)))
    for j, name in enumerate(skeleton_names[1:], start=1):
        bone = asf.bones[name]
        dofs = [d for d in bone.dof if d in ROTATION_DOFS]
        if not dofs:
            continue
        if name not in amc.values:
            idle.append(name)
            continue
        vals = bone_values(amc, name, len(bone.dof))
        cols = [bone.dof.index(d) for d in dofs]
        c = axis_rotation(bone.axis_order, bone.axis * asf.radians_per_unit)
        m = axis_rotation("".join(d[1] for d in dofs), vals[:, cols] * radians)
        rotations[:, j] = quat.multiply(c, quat.multiply(m, quat.conjugate(c)))
    return rotations, root_t, idle


def read_amc(path: Path, units: str | None = None, up_axis: str | None = None, skeleton: str | Path | None = None,
             fps: float | None = None) -> Asset:
    """An Acclaim motion on its ``.asf`` skeleton (``skeleton=PATH`` or a matching one beside it).

    ``meta["skeleton_file"]`` says which ``.asf`` was used.
    """
    path = Path(path)
    amc = parse_amc(path, _read_text(path))
    if skeleton is not None:
        sk_path = Path(skeleton)
        if not sk_path.is_file():
            raise InputError(sk_path, None, "skeleton file not found")
        asf = load_asf(sk_path)
        record = {"skeleton_file": str(sk_path)}
        _check_bones(amc, asf)
    else:
        asf, record = _matching_asf(path, amc)
    amc.check_frames()
    unit, metres, detected_by, skel, axis, up, meta = _prepare(asf, units, up_axis)
    meta.update(record)
    angle = amc.angle_unit or ("rad" if asf.radians_per_unit == 1.0 else "deg")
    meta["amc_angle_unit"] = angle
    rotations, root_t, idle = _local_rotations(asf, amc, 1.0 if angle == "rad" else np.pi / 180.0, skel.names)
    if idle:
        meta["bones_without_values"] = idle
    rotations[:, 0] = quat.multiply(up, rotations[:, 0])
    root_t = quat.rotate(up, root_t * metres)
    if fps is None:
        fps = DEFAULT_FPS
        meta["fps_rule"] = f"AMC files state no frame rate; {DEFAULT_FPS:g} fps (the CMU capture rate) assumed"
    meta["first_frame_number"] = amc.first_frame
    name = path.stem
    try:
        motion = Motion(skel, float(fps), rotations, root_t, name=name)
    except InputError as exc:
        raise exc.naming(path) from None
    return Asset(path, "acclaim-amc", skel, {name: motion}, source_units=unit, source_up_axis=axis,
                 units_detected_by=detected_by, meta=meta, payload=(amc, asf))
