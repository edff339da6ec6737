"""Reading an FBX 7.x ``.fbx`` file (binary or ASCII) into an :class:`~infuse.asset.Asset` (metres, +Y up).

Joints are the skeleton models (see :func:`.models.joint_models`); other models above them are
folded into the roots. The rest pose is the models' static ``Lcl`` transforms. Units come from
``GlobalSettings/UnitScaleFactor`` (centimetres per unit, default 1) and the up axis from
``UpAxis``/``UpAxisSign``; ``units=`` / ``up_axis=`` override them. Each animation stack becomes a
Motion sampled at the file's frame rate (``TimeMode``) over the stack's local time span. Names of
blend-shape channels become ``morph_targets``. ``meshes`` (decoded on first use): the skinned
surfaces, see :mod:`infuse_fbx.mesh`; geometry left out is explained in ``Asset.warnings``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from infuse.asset import Asset
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS
from infuse.errors import UnusableInputError, UsageError
from infuse.transforms import frame_change, nearest_joint_parents, sampled_motion, skeleton_from_globals

from . import animation, ascii_format, binary, models
from .document import Document, build, number
from .mesh import MeshLoader

#: Largest take read, in frames x joints (bounds memory on absurd time spans).
MAX_JOINT_FRAMES = 10_000_000

_AXES = "XYZ"


def read(path: Path, units: str | None = None, up_axis: str | None = None, **_options) -> Asset:
    """Read an FBX file; see the module docstring for what is kept and how it is converted."""
    # Huge but finite numbers may overflow on the way; the model's checks then name the non-finite
    # joint, so numpy's own warnings would only add lines.
    with np.errstate(all="ignore"):
        return _read(Path(path), units, up_axis)


def _read(path: Path, units: str | None, up_axis: str | None) -> Asset:
    data = path.read_bytes()
    if not binary.is_binary_fbx(data) and ascii_format.is_ascii_fbx(data):
        version, root = ascii_format.parse(path, data)
    else:
        version, root = binary.parse(path, data)
    if version < 7000:
        raise UnusableInputError(path, f"FBX version {version} (6.x) is not supported; re-export as FBX 2011 or later (7.x)")
    doc = build(path, version, root)
    settings = doc.settings()
    scale, unit_name, units_by = _units(doc, settings, units)
    up = _up_axis(doc, settings, up_axis)
    ms = models.models(doc)
    joints = models.joint_models(doc, ms)
    if not joints:
        raise UnusableInputError(path, "no skeleton: the file has no LimbNode, Root or skinned models")
    change = frame_change(scale, up)
    rest_parts = [np.stack(part, axis=1) for part in
                  zip(*[models.local_parts(m, m.translation[None], m.rotation[None], m.scaling[None]) for m in ms])]
    world = models.world_matrices(ms, *rest_parts)[0]
    rest = change @ world[joints]
    parents, folded = nearest_joint_parents([m.parent for m in ms], joints, return_folded=True)
    skeleton = skeleton_from_globals(models.unique_names(ms, joints), parents, rest)

    fps = animation.frame_rate(doc, settings)
    motions = {}
    takes_meta = []
    for take in animation.takes(doc):
        frames = int(np.floor((take.stop - take.start) * fps + 1e-6)) + 1
        if frames * len(joints) > MAX_JOINT_FRAMES:
            raise UnusableInputError(path, f"animation {take.name!r} is too long to sample: {frames} frames")

        def globals_between(a, b, take=take):
            t = take.start + np.arange(a, b) / fps
            parts = [np.broadcast_to(part, (b - a,) + part.shape[1:]).copy() for part in rest_parts]
            for i, m in enumerate(ms):
                channels = [take.tracks.get((m.obj.id, c)) for c in range(3)]
                if any(channels):
                    trs = [_channel(track, static, t) for track, static in zip(channels, (m.translation, m.rotation, m.scaling))]
                    for part, value in zip(parts, models.local_parts(m, *trs)):
                        part[:, i] = value
            return change @ models.world_matrices(ms, *parts)[:, joints]

        motions[take.name] = sampled_motion(skeleton, fps, frames, globals_between, name=take.name)
        takes_meta.append({"name": take.name, "start_s": take.start, "layers": take.layers})
    meta = {"fbx_version": version, "unit_scale_factor_cm": number(doc, settings, "UnitScaleFactor", 1.0),
            "axes": _axis_meta(doc, settings), "takes": takes_meta,
            "folded_models": [ms[i].obj.name for i in folded]}
    warnings: list[str] = []
    has_mesh = any(o.kind == "Geometry" and o.subclass == "Mesh" for o in doc.objects.values())
    meshes = MeshLoader(doc, ms, world, joints, change, skeleton, warnings) if has_mesh else None
    return Asset(path, "fbx", skeleton, motions, _morph_targets(doc), source_units=unit_name, source_up_axis=up,
                 units_detected_by=units_by, meta=meta, mesh_loader=meshes, warnings=warnings)


def _channel(track, static: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Per-frame (F, 3) values of one T/R/S channel: curves where present, else defaults or the rest value."""
    out = np.broadcast_to(static, (len(t), 3)).copy()
    for axis, comp in enumerate(track or ()):
        if isinstance(comp, animation.Curve):
            out[:, axis] = animation.sample(comp, t)
        elif np.isfinite(comp):
            out[:, axis] = comp
    return out


def _units(doc: Document, settings: dict, override: str | None) -> tuple[float, str, str]:
    if override is not None:
        if override not in UNIT_SCALES:
            raise UsageError(f"unknown unit {override!r}; known: {', '.join(UNIT_SCALES)}")
        return UNIT_SCALES[override], override, "override"
    cm = number(doc, settings, "UnitScaleFactor", 1.0)
    if cm <= 0:
        raise doc.error(doc.root.find("GlobalSettings"), f"UnitScaleFactor {cm} must be positive")
    scale = cm * 0.01
    name = next((u for u, s in UNIT_SCALES.items() if abs(s - scale) <= 1e-9 * s), f"{scale:g} m")
    return scale, name, "file"


def _up_axis(doc: Document, settings: dict, override: str | None) -> str:
    if override is not None:
        if override not in UP_AXIS_ROTATIONS:
            raise UsageError(f"unknown up axis {override!r}; known: {', '.join(UP_AXIS_ROTATIONS)}")
        return override
    axis = int(number(doc, settings, "UpAxis", 1.0))
    sign = number(doc, settings, "UpAxisSign", 1.0)
    if axis not in (0, 1, 2):
        raise doc.error(doc.root.find("GlobalSettings"), f"UpAxis {axis} is not 0, 1 or 2")
    name = ("-" if sign < 0 else "") + _AXES[axis]
    if name not in UP_AXIS_ROTATIONS:
        raise UnusableInputError(doc.path, f"up axis {name} is not supported")
    return name


def _axis_meta(doc: Document, settings: dict) -> dict:
    """The file's axis system as signed axis names (up, front, coord)."""
    out = {}
    for key in ("Up", "Front", "Coord"):
        axis = int(number(doc, settings, f"{key}Axis", -1.0))
        if axis in (0, 1, 2):
            out[key.lower()] = ("-" if number(doc, settings, f"{key}AxisSign", 1.0) < 0 else "+") + _AXES[axis]
    return out


def _morph_targets(doc: Document) -> list[str]:
    names: list[str] = []
    for obj in doc.objects.values():
        if obj.kind == "Deformer" and obj.subclass == "BlendShapeChannel" and obj.name not in names:
            names.append(obj.name)
    return names
