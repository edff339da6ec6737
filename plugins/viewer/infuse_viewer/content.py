"""What the page shows for each file: a GLB, the joints with their canonical names, targets, audio.

Every input becomes a binary glTF so the page has one loading path: ``.glb``/``.vrm``/``.vrma`` are
sent as they are, any other readable file (BVH, ``.sk``/``.skm``, ``.gltf``...) is read and written
to GLB in memory with the installed glTF writer. Joints are tied to glTF node indices, which the
page turns into three.js objects.
"""
from __future__ import annotations

import json
import re
import struct
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import infuse
from infuse.canonical import CANONICAL_NAMES
from infuse.errors import InfuseError, InputError, UsageError
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton

from .targets import read_targets, sidecar_for, to_file_frame

BINARY_GLTF = (".glb", ".vrm", ".vrma")
FOLDER_MODELS = (".glb",)
AUDIO = ".wav"
LOW_CONFIDENCE = 0.7


@dataclass(frozen=True)
class Source:
    """One file the page offers, and the targets sidecar to use with it (``None``: look beside it)."""

    path: Path
    targets: Path | None = None

    @property
    def name(self) -> str:
        return self.path.stem


@dataclass
class Prepared:
    """One file, ready for the page: ``glb`` bytes, ``info`` (JSON-ready), ``audio`` [(key, wav path)]
    where the key is a clip name or ``"*"`` (every clip)."""

    glb: bytes
    info: dict
    audio: list[tuple[str, Path]] = field(default_factory=list)


def sources(path: str | Path, targets: str | Path | None = None) -> list[Source]:
    """The files ``infuse view PATH`` shows: the file itself, or every ``.glb`` in the folder."""
    path = Path(path)
    if path.is_dir():
        if targets is not None:
            raise UsageError("--targets names the targets of one file; in a folder each model uses <stem>.targets.json")
        found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in FOLDER_MODELS)
        if not found:
            raise InputError(path, None, "no .glb files in this folder")
        return [Source(p) for p in found]
    if not path.exists():
        raise InputError(path, None, "file not found")
    return [Source(path, Path(targets) if targets is not None else None)]


def glb_json(data: bytes, file: str | Path | None = None) -> dict:
    """The JSON chunk of a binary glTF."""
    if len(data) < 20 or data[:4] != b"glTF":
        raise InputError(file, "GLB header", "not a binary glTF file")
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON" or 20 + length > len(data):
        raise InputError(file, "GLB header", "the first chunk is not a JSON chunk")
    try:
        return json.loads(data[20:20 + length].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(file, "GLB JSON chunk", str(exc)) from None


def joint_nodes(nodes: list, names) -> dict[str, int]:
    """Joint name -> glTF node index, undoing how the glTF reader names joints: the node's name,
    ``node<i>`` for an unnamed node, ``<name>_<i>`` for the second and later nodes of a repeated name."""
    out: dict[str, int] = {}
    plain: dict[str, list[int]] = {}
    for i, node in enumerate(nodes):
        plain.setdefault(node.get("name") or "", []).append(i)
    claimed = set()
    for name in names:
        suffixed = re.fullmatch(r"(.*)_(\d+)", name)
        unnamed = re.fullmatch(r"node(\d+)", name)
        if name not in plain and suffixed and int(suffixed[2]) < len(nodes) and nodes[int(suffixed[2])].get("name") == suffixed[1]:
            out[name] = int(suffixed[2])
        elif name not in plain and unnamed and int(unnamed[1]) < len(nodes) and not nodes[int(unnamed[1])].get("name"):
            out[name] = int(unnamed[1])
        claimed.update(out.values())
    for name in names:
        if name not in out:
            free = [i for i in plain.get(name, []) if i not in claimed]
            if free:
                out[name] = free[0]
                claimed.add(free[0])
    return out


def _bone_tips(nodes: list, joint_of_node: dict[int, int]) -> list[tuple[int, int]]:
    """(node, parent joint) for leaf nodes under joints that are not joints themselves (BVH end
    sites written to glTF, bone tips): drawn so limbs reach their ends."""
    tips = []
    for node_index, joint in joint_of_node.items():
        for child in nodes[node_index].get("children", []):
            if not isinstance(child, int) or not 0 <= child < len(nodes) or child in joint_of_node:
                continue
            c = nodes[child]
            if not c.get("children") and "mesh" not in c and "camera" not in c and "skin" not in c:
                tips.append((child, joint))
    return tips


def stretching_links(asset, tolerance: float = 0.05) -> np.ndarray:
    """(J,) bool: joints whose distance to their parent changes by more than ``tolerance`` x the
    skeleton's height in some clip. Such a link is no bone but a free joint (a BVH root left at
    the origin while the hips run away) and is not drawn."""
    skeleton = asset.skeleton
    free = np.zeros(skeleton.num_joints, dtype=bool)
    child = np.nonzero(skeleton.parents >= 0)[0]
    for motion in asset.motions.values():
        if motion.skeleton.names != skeleton.names or motion.num_frames < 2:
            continue
        _, pos = motion_fk(motion)
        lengths = np.linalg.norm(pos[:, child] - pos[:, skeleton.parents[child]], axis=-1)  # (F, links)
        free[child] |= np.ptp(lengths, axis=0) > tolerance * max(skeleton.height(), 1e-6)
    return free


def _joints_info(asset, doc: dict, mapping, low: float) -> tuple[list[dict], list[dict]]:
    """The joints the page draws, and the required canonical names that found no joint."""
    nodes = doc.get("nodes", [])
    skeleton = asset.skeleton
    node_of = joint_nodes(nodes, skeleton.names)
    free = stretching_links(asset)
    canon: dict[str, list[str]] = {}
    if mapping is not None:
        for name, joint in mapping.joints.items():
            if joint is not None:
                canon.setdefault(joint, []).append(name)
    joints, index_of = [], {}
    for j, name in enumerate(skeleton.names):
        if name not in node_of:
            continue
        parent = int(skeleton.parents[j])
        names = canon.get(name, [])
        confidence = min(mapping.confidence[n] for n in names) if names else None
        index_of[j] = len(joints)
        joints.append({
            "node": node_of[name], "name": name, "parent": index_of.get(parent, -1), "canonical": names,
            "confidence": None if confidence is None else round(confidence, 3),
            "reason": "; ".join(f"{n}: {mapping.reasons[n]}" for n in names if mapping.reasons.get(n)),
            "low": confidence is not None and confidence < low,
            "free": bool(free[j]),
        })
    joint_of_node = {joints[k]["node"]: k for k in range(len(joints))}
    for node, parent in _bone_tips(nodes, joint_of_node):
        joints.append({"node": node, "name": nodes[node].get("name") or f"node{node}", "parent": parent,
                       "canonical": [], "confidence": None, "reason": "", "low": False, "free": False, "tip": True})
    missing = []
    if mapping is not None:
        missing = [{"canonical": n, "confidence": round(mapping.confidence[n], 3), "reason": mapping.reasons.get(n, "")}
                   for n in CANONICAL_NAMES if mapping.joints.get(n) is None]
    return joints, missing


def _audio_for(path: Path, clips: list[str]) -> list[tuple[str, Path]]:
    """Audio beside the model: ``<stem>.wav`` for every clip, ``<stem>.<clip>.wav`` or ``<clip>.wav`` for one clip."""
    folder, stem = path.parent, path.stem
    found = []
    if (folder / f"{stem}{AUDIO}").is_file():
        found.append(("*", folder / f"{stem}{AUDIO}"))
    for clip in clips:
        if "/" in clip or clip in ("", ".", ".."):
            continue
        for candidate in (folder / f"{stem}.{clip}{AUDIO}", folder / f"{clip}{AUDIO}"):
            if candidate.is_file() and candidate != folder / f"{stem}{AUDIO}":
                found.append((clip, candidate))
                break
    return found


def _glb_of(source: Path, asset) -> bytes:
    if source.suffix.lower() in BINARY_GLTF:
        return source.read_bytes()
    with tempfile.TemporaryDirectory(prefix="infuse-view-") as tmp:
        out = Path(tmp) / f"{source.stem}.glb"
        infuse.save(asset, out)
        return out.read_bytes()


def prepare(source: Source, mapper: str | None = None, saved_map=None, low_confidence: float = LOW_CONFIDENCE) -> Prepared:
    """Read ``source`` and build what the page needs (see :class:`Prepared`).

    A file that cannot be read raises (as :func:`infuse.load` does); a skeleton the mapper refuses is
    shown without canonical names, the reason in ``info["mapping"]["error"]``.
    """
    path = source.path
    asset = infuse.load(path)
    glb = _glb_of(path, asset)
    doc = glb_json(glb, path)
    clips = [a.get("name") or f"animation{i}" for i, a in enumerate(doc.get("animations", []))]
    mapping, error = None, None
    try:
        mapping = map_skeleton(asset, mapper=mapper, saved_map=saved_map)
    except (InfuseError, ValueError) as exc:
        error = str(exc)
    joints, missing = _joints_info(asset, doc, mapping, low_confidence)
    targets_file = source.targets or sidecar_for(path)
    targets = []
    if source.targets is not None or targets_file.is_file():
        targets = to_file_frame(read_targets(targets_file), asset.facing_turned)
    audio = _audio_for(path, clips)
    info = {
        "name": source.name,
        "file": path.name,
        "format": asset.format,
        "clips": clips,
        "joints": joints,
        "mapping": {
            "mapper": mapping.mapper if mapping else None,
            "overall_confidence": round(mapping.overall_confidence, 3) if mapping else None,
            "mapped": len([n for n in CANONICAL_NAMES if mapping.joints.get(n)]) if mapping else 0,
            "required": len(CANONICAL_NAMES),
            "missing": missing,
            "low_confidence": low_confidence,
            "error": error,
        },
        "targets": targets,
        "targets_file": targets_file.name if targets else None,
        "audio": {key: wav.name for key, wav in audio},
        "height_m": round(float(asset.skeleton.height()), 4),
    }
    return Prepared(glb, info, audio)
