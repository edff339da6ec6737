"""Importers: turn a SmartBody behaviour set or a folder of BVH clips into a pack that reads them in place.

The importer writes only a manifest into the destination folder; the clips stay where they are (their
absolute paths are in the manifest) and ``infuse pack build`` then analyses them. Roles come from
the file names (idle, cycle, reach, grasp; transitions such as starts, stops and turns in place are
kept as ``other``); everything numeric is measured by the builder.
"""
from __future__ import annotations

import fnmatch
import re
from pathlib import Path

from ..errors import InputError
from .manifest import write_manifest

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


def import_smartbody(source: str | Path, dest: str | Path, name: str | None = None, version: str = "0.0.0") -> Path:
    """Write a manifest in ``dest`` for the SmartBody behaviour set at ``source`` (``skeletons/*.sk`` and
    ``motions/*.skm``); returns the manifest path. Transitions are listed with role ``other``."""
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
            "description": f"SmartBody behaviour set {source.name}, read in place"}
    return write_manifest(Path(dest) / "manifest.toml", pack, clips)


def import_bvh_folder(source: str | Path, dest: str | Path, name: str | None = None, pattern: str = "*.bvh",
                      kind: str = "locomotion", version: str = "0.0.0") -> Path:
    """Write a manifest in ``dest`` for the BVH files of ``source`` matching ``pattern`` (clips that are
    recorded takes, not loops: the builder finds a cycle in each); returns the manifest path."""
    source = Path(source).resolve()
    files = sorted(p for p in source.iterdir() if p.suffix.lower() == ".bvh" and fnmatch.fnmatch(p.name, pattern))
    if not files:
        raise InputError(source, None, f"no BVH files matching {pattern!r}")
    clips = [{"name": f.stem, "file": str(f), "role": "cycle" if kind == "locomotion" else "reach", "tags": _tags(f.stem),
              "loop": False} for f in files]
    pack = {"name": name or f"bvh-{source.name.lower()}", "version": version, "kind": kind, "skeleton": str(files[0]),
            "analysis": "analysis.json", "description": f"BVH clips from {source.name} ({pattern}), read in place"}
    return write_manifest(Path(dest) / "manifest.toml", pack, clips)
