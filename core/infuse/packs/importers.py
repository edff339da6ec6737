"""Importers: turn a SmartBody behaviour set or a folder of BVH clips into a self-contained pack folder.

The importer copies the skeleton and the clips into the destination folder and writes a manifest
naming them by relative paths (:mod:`infuse.packs.folder`); the source is only read, and ``infuse
pack build`` then analyses the copy. Roles come from the file names (idle, cycle, reach, grasp;
transitions such as starts, stops and turns in place are kept as ``other``); everything numeric is
measured by the builder.
"""
from __future__ import annotations

import fnmatch
import re
from pathlib import Path

from ..errors import InputError
from .folder import write_pack_folder
from .pack import file_digest

#: The version of a newly imported pack.
FIRST_VERSION = "0.1.0"

#: SmartBody clip names that are transitions or one-offs, not blendable loops.
_TRANSITION = re.compile(r"(To(Walk|Idle)|Turn\d|Step|Lift|Jump|StopTo|Shuffle01_)", re.IGNORECASE)


def _tags(stem: str) -> list[str]:
    return [t for t in re.split(r"[_@\-\s]+", stem) if t and not t.isdigit()]


def smartbody_role(stem: str) -> tuple[str, str]:
    """(role, kind) of a SmartBody motion from its name."""
    name = stem.split("@")[-1]
    if "Reach" in name and "Hand" not in name:
        return "reach", "reach"
    if re.search(r"Hand(Grasp|Default|Reach|Release)", name):
        return "grasp", "reach"
    if _TRANSITION.search(name):
        return "other", "locomotion"
    if re.search(r"Idle", name):
        return "idle", "locomotion"
    if re.search(r"(Walk|Jog|Run|Strafe|Meander|Shuffle)", name):
        return "cycle", "locomotion"
    return "other", "locomotion"


def import_smartbody(source: str | Path, dest: str | Path, name: str | None = None, version: str = FIRST_VERSION,
                     description: str | None = None) -> Path:
    """Copy the SmartBody behaviour set at ``source`` (``skeletons/*.sk`` and ``motions/*.skm``) into a pack
    folder ``dest``; returns the manifest path. Transitions are listed with role ``other``."""
    source = Path(source).resolve()
    skeletons = sorted((source / "skeletons").glob("*.sk"))
    motions = sorted((source / "motions").glob("*.skm"))
    if not skeletons or not motions:
        raise InputError(source, None, "not a SmartBody behaviour set: expected skeletons/*.sk and motions/*.skm")
    clips, kinds = [], []
    for m in motions:
        role, kind = smartbody_role(m.stem)
        kinds.append(kind)
        clips.append({"name": m.stem.split("@")[-1], "file": str(m), "role": role, "tags": _tags(m.stem),
                      "loop": role in ("cycle", "idle")})
    kind = "reach" if kinds.count("reach") > kinds.count("locomotion") else "locomotion"
    pack = {"name": name or f"smartbody-{source.name.lower()}", "version": version, "kind": kind,
            "skeleton": str(skeletons[0]), "analysis": "analysis.json",
            "description": description or f"SmartBody behaviour set {source.name}"}
    return write_pack_folder(dest, pack, clips)


def import_bvh_folder(source: str | Path, dest: str | Path, name: str | None = None, pattern: str = "*.bvh",
                      kind: str = "locomotion", version: str = FIRST_VERSION, description: str | None = None) -> Path:
    """Copy the BVH files of ``source`` matching ``pattern`` into a pack folder ``dest`` (clips that are
    recorded takes, not loops: the builder finds a cycle in each); returns the manifest path. The pack
    skeleton is the hierarchy of the file first by content (SHA-256), not by name."""
    source = Path(source).resolve()
    if not source.is_dir():
        raise InputError(source, None, "not a folder of BVH files")
    files = sorted(p for p in source.iterdir() if p.suffix.lower() == ".bvh" and fnmatch.fnmatch(p.name, pattern))
    if not files:
        raise InputError(source, None, f"no BVH files matching {pattern!r}")
    role = {"locomotion": "cycle", "posture": "posture"}.get(kind, "reach")
    clips = [{"name": f.stem, "file": str(f), "role": role, "tags": _tags(f.stem), "loop": kind == "posture"} for f in files]
    skeleton = min(files, key=file_digest)  # the pack skeleton by content: the same whatever the files are called
    pack = {"name": name or f"bvh-{source.name.lower()}", "version": version, "kind": kind, "skeleton": str(skeleton),
            "analysis": "analysis.json", "description": description or f"BVH clips from {source.name} ({pattern})"}
    return write_pack_folder(dest, pack, clips)
