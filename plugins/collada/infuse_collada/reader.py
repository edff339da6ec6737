"""Reading a ``.dae`` file into an :class:`~infuse.asset.Asset` (metres, +Y up).

The rest pose is the visual scene as stored. Non-joint nodes above or between joints are folded
into the joints below them. ``<asset><unit meter>`` and ``<up_axis>`` are honoured (COLLADA's
defaults: metre, Y up) unless ``units=`` / ``up_axis=`` override them. Animations become one
Motion per ``<animation_clip>``, or one for the whole timeline, sampled on the frame grid the key
times lie on (30 fps when they fit none). The skinned meshes (``Asset.meshes``) are decoded on
first use, in the skeleton's frame (:mod:`infuse_collada.mesh`); what cannot be drawn is said in
``Asset.warnings``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from infuse.asset import Asset
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS
from infuse.errors import UnusableInputError, UsageError
from infuse.transforms import frame_change, global_matrices, nearest_joint_parents, sampled_motion, skeleton_from_globals

from . import animation
from .document import Document
from .mesh import MeshLoader
from .scene import flatten, joint_indices, local_matrices, unique_names, visual_scene

_UP_AXES = {"X_UP": "X", "Y_UP": "Y", "Z_UP": "Z"}

#: Largest clip read, in frames x joints (bounds memory on absurd clip lengths).
MAX_JOINT_FRAMES = 10_000_000


def read(path: Path, units: str | None = None, up_axis: str | None = None, **_options) -> Asset:
    """Read a COLLADA file; see the module docstring for what is kept and how it is converted."""
    # Huge but finite numbers may overflow on the way; the model's checks then name the non-finite
    # joint, so numpy's own warnings would only add lines.
    with np.errstate(all="ignore"):
        return _read(Path(path), units, up_axis)


def _read(path: Path, units: str | None, up_axis: str | None) -> Asset:
    doc = Document(path)
    scale, unit_name, detected_by = _units(doc, units)
    up = _up_axis(doc, up_axis)
    nodes, elements = flatten(doc, visual_scene(doc))
    joints = joint_indices(doc, nodes, elements)
    if not joints:
        raise UnusableInputError(path, "no joints: the scene has no JOINT nodes and no skin controllers")
    node_parents = np.array([n.parent for n in nodes], dtype=np.int64)
    change = frame_change(scale, up)
    world = global_matrices(node_parents, local_matrices(nodes))[0]
    rest = change @ world[joints]
    parents, folded = nearest_joint_parents(node_parents, joints, return_folded=True)
    skeleton = skeleton_from_globals(unique_names(nodes, joints), parents, rest)

    chs, skipped = animation.channels(doc, nodes)
    relevant = set(joints).union(folded.tolist())  # nodes whose animation moves a joint
    chs = [c for c in chs if any(n in relevant for n in c.nodes)]
    motions = {}
    meta: dict = {"unit_meter": _declared_scale(doc),
                  "folded_nodes": [nodes[n].name for n in folded],
                  "skins": sum(len(el.findall("instance_controller")) for el in elements),
                  "authoring_tool": (doc.root.findtext("asset/contributor/authoring_tool") or "").strip()}
    if chs:
        fps = animation.frame_rate(chs)
        clips = _clips(doc, chs)
        for name, start, end, clip_chs in clips:
            frames = int(round((end - start) * fps)) + 1
            if frames * len(joints) > MAX_JOINT_FRAMES:
                raise UnusableInputError(path, f"animation {name!r} is too long to sample: {frames} frames of {len(joints)} joints")
            times = start + np.arange(frames) / fps

            def globals_between(a, b, times=times, clip_chs=clip_chs):
                values = animation.sample_transforms(nodes, clip_chs, times[a:b])
                return change @ global_matrices(node_parents, local_matrices(nodes, values, b - a))[:, joints]

            motions[name] = sampled_motion(skeleton, fps, frames, globals_between, name=name)
        meta["animation"] = {"fps": fps, "channels": len(chs), "skipped_channels": skipped,
                             "clip_start_s": {name: start for name, start, _, _ in clips}}
    warnings: list[str] = []
    has_mesh = any(child.tag in ("instance_controller", "instance_geometry") for el in elements for child in el)
    meshes = MeshLoader(doc, nodes, elements, joints, world, change, skeleton, warnings) if has_mesh else None
    return Asset(path, "collada", skeleton, motions, _morph_targets(doc), source_units=unit_name,
                 source_up_axis=up, units_detected_by=detected_by, meta=meta, mesh_loader=meshes, warnings=warnings)


def _units(doc: Document, override: str | None) -> tuple[float, str, str]:
    if override is not None:
        if override not in UNIT_SCALES:
            raise UsageError(f"unknown unit {override!r}; known: {', '.join(UNIT_SCALES)}")
        return UNIT_SCALES[override], override, "override"
    scale = _declared_scale(doc)
    name = next((u for u, s in UNIT_SCALES.items() if abs(s - scale) <= 1e-9 * s), f"{scale:g} m")
    return scale, name, "file"


def _declared_scale(doc: Document) -> float:
    unit = doc.root.find("asset/unit")
    if unit is None or unit.get("meter") is None:
        return 1.0
    try:
        scale = float(unit.get("meter"))
    except ValueError:
        raise doc.error(unit, f"meter={unit.get('meter')!r} is not a number") from None
    if not (np.isfinite(scale) and scale > 0):
        raise doc.error(unit, f"meter={unit.get('meter')!r} must be a positive number")
    return scale


def _up_axis(doc: Document, override: str | None) -> str:
    if override is not None:
        if override not in UP_AXIS_ROTATIONS:
            raise UsageError(f"unknown up axis {override!r}; known: {', '.join(UP_AXIS_ROTATIONS)}")
        return override
    element = doc.root.find("asset/up_axis")
    if element is None:
        return "Y"
    text = (element.text or "").strip().upper()
    if text not in _UP_AXES:
        raise doc.error(element, f"up_axis {text[:20]!r} is not X_UP, Y_UP or Z_UP")
    return _UP_AXES[text]


def _clips(doc: Document, chs: list[animation.Channel]):
    """(name, start s, end s, channels) for each ``<animation_clip>``, or one clip spanning every key."""
    clips: list[tuple[str, float, float, list[animation.Channel]]] = []
    for clip in doc.root.iterfind("library_animation_clips/animation_clip"):
        ids = {(inst.get("url") or "").lstrip("#") for inst in clip.findall("instance_animation")}
        clip_chs = [c for c in chs if c.animations & ids]
        if not clip_chs:
            continue
        start = _float_attr(doc, clip, "start", 0.0)
        end = _float_attr(doc, clip, "end", max(float(c.curve.times[-1]) for c in clip_chs))
        if end < start:
            raise doc.error(clip, f"clip ends ({end}) before it starts ({start})")
        clips.append((clip.get("name") or clip.get("id") or f"clip{len(clips)}", start, end, clip_chs))
    if clips:
        return clips
    start = min(float(c.curve.times[0]) for c in chs)
    end = max(float(c.curve.times[-1]) for c in chs)
    return [(doc.path.stem, start, end, chs)]


def _float_attr(doc: Document, element, name: str, default: float) -> float:
    raw = element.get(name)
    if raw is None:
        return default
    try:
        value = float(raw)
    except ValueError:
        raise doc.error(element, f"{name}={raw!r} is not a number") from None
    if not np.isfinite(value):
        raise doc.error(element, f"{name}={raw!r} is not finite")
    return value


def _morph_targets(doc: Document) -> list[str]:
    """Names of the morph targets of every ``<morph>`` controller, in file order, without repeats."""
    names: list[str] = []
    for morph in doc.root.iterfind("library_controllers/controller/morph"):
        targets = morph.find("targets/input[@semantic='MORPH_TARGET']")
        if targets is None:
            raise doc.error(morph, "morph has no MORPH_TARGET input")
        for ref in doc.source(targets.get("source"), targets, numeric=False).ravel():
            element = doc.ids.get(str(ref))
            name = (element.get("name") if element is not None else None) or str(ref)
            if name not in names:
                names.append(name)
    return names
