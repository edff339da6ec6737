"""The pack manifest: a TOML file naming a pack's skeleton, clips and kind of parameterization.

::

    [pack]
    name = "locomotion-female"
    version = "1.0.0"
    kind = "locomotion"            # or "reach", "gesture", "posture"
    skeleton = "skeleton.bvh"      # relative to the manifest (pack import and pack new write only such)
    analysis = "analysis.json"     # written by 'infuse pack build'
    description = "..."

    [[clips]]
    name = "walk"
    file = "clips/walk.bvh"        # BVH or SmartBody .skm
    role = "cycle"                 # cycle (a locomotion loop), idle, reach, grasp, gesture, posture, other
    tags = ["walk"]
    loop = true
    hand = "left"                  # reach and gesture examples: which hand ("both" for gestures)
    sync = { ready = 0.4, stroke_start = 0.5, stroke = 0.6, stroke_end = 0.8, relax = 1.1 }
                                   # gestures: their phases, seconds from the clip's start

Everything else about a clip (contacts, cycles, keys, parameters) is computed by the builder. The files a
manifest names must lie in its folder or below it (no absolute paths, no ``..`` out of it) unless
``INFUSE_ALLOW_EXTERNAL=1`` allows them elsewhere (:mod:`infuse.references`).
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..atomic import atomic_path
from .. import references
from ..errors import InputError

KINDS = ("locomotion", "reach", "gesture", "posture")
ROLES = ("cycle", "idle", "reach", "grasp", "gesture", "posture", "other")
HANDS = ("left", "right", "both")
#: A gesture's phases in the order they happen: manifest key -> BML sync point.
GESTURE_PHASES = {"ready": "ready", "stroke_start": "strokeStart", "stroke": "stroke", "stroke_end": "strokeEnd",
                  "relax": "relax"}


@dataclass(frozen=True)
class ClipEntry:
    """One clip of a pack: ``file`` resolved against the manifest's folder."""

    name: str
    file: Path
    role: str = "cycle"
    tags: tuple[str, ...] = ()
    loop: bool = True
    hand: str | None = None
    sync: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Manifest:
    """A parsed manifest; ``path`` is the manifest file, paths are absolute."""

    path: Path
    name: str
    version: str
    kind: str
    skeleton: Path
    analysis: Path
    clips: tuple[ClipEntry, ...]
    description: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def folder(self) -> Path:
        return self.path.parent

    def clip(self, name: str) -> ClipEntry:
        for c in self.clips:
            if c.name == name:
                return c
        raise KeyError(name)


def _resolve(manifest: Path, value: str, place: str) -> Path:
    """A file the manifest names, kept inside the pack's folder (:mod:`infuse.references`)."""
    return references.inside(manifest, value, place, "pack file")


def read_manifest(path: str | Path) -> Manifest:
    """Parse and check a manifest; :class:`InputError` names the key at fault."""
    path = Path(path)
    if path.is_dir():
        path = path / "manifest.toml"
    if not path.is_file():
        raise InputError(path, None, "pack manifest not found")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(path, None, f"not a TOML manifest: {exc}") from None
    pack = doc.get("pack")
    if not isinstance(pack, dict):
        raise InputError(path, "pack", "missing [pack] table")
    for key in ("name", "version", "kind", "skeleton"):
        if not isinstance(pack.get(key), str) or not pack[key]:
            raise InputError(path, f"pack.{key}", "expected a non-empty string")
    if pack["kind"] not in KINDS:
        raise InputError(path, "pack.kind", f"unknown kind {pack['kind']!r}; expected one of {', '.join(KINDS)}")
    clips = []
    names = set()
    raw = doc.get("clips")
    if not isinstance(raw, list) or not raw:
        raise InputError(path, "clips", "expected at least one [[clips]] entry")
    for k, c in enumerate(raw):
        where = f"clips[{k}]"
        if not isinstance(c, dict) or not isinstance(c.get("file"), str):
            raise InputError(path, where, "expected a table with a 'file' string")
        name = str(c.get("name") or Path(c["file"]).stem)
        if name in names:
            raise InputError(path, f"{where}.name", f"duplicate clip name {name!r}")
        names.add(name)
        role = str(c.get("role", "cycle"))
        if role not in ROLES:
            raise InputError(path, f"{where}.role", f"unknown role {role!r}; expected one of {', '.join(ROLES)}")
        hand = c.get("hand")
        if hand is not None and hand not in HANDS:
            raise InputError(path, f"{where}.hand", f"expected one of {', '.join(HANDS)}")
        tags = c.get("tags", [])
        if not isinstance(tags, list) or not all(isinstance(t, str) for t in tags):
            raise InputError(path, f"{where}.tags", "expected a list of strings")
        sync = _sync(path, f"{where}.sync", c.get("sync", {}))
        if role == "gesture" and "stroke" not in sync:
            raise InputError(path, f"{where}.sync", "a gesture names its phases (at least its stroke), seconds")
        clips.append(ClipEntry(name, _resolve(path, c["file"], f"{where}.file"), role, tuple(tags), bool(c.get("loop", role in ("cycle", "idle"))), hand,
                               sync))
    extra = {k: v for k, v in pack.items() if k not in ("name", "version", "kind", "skeleton", "analysis", "description")}
    return Manifest(path.resolve(), pack["name"], pack["version"], pack["kind"], _resolve(path, pack["skeleton"], "pack.skeleton"),
                    _resolve(path, pack.get("analysis", "analysis.json"), "pack.analysis"), tuple(clips), str(pack.get("description", "")), extra)


def _sync(path: Path, where: str, table) -> dict:
    """A clip's phases: :data:`GESTURE_PHASES` keys -> seconds, in that order (not decreasing)."""
    if not isinstance(table, dict):
        raise InputError(path, where, "expected a table of phase = seconds")
    unknown = sorted(set(table) - set(GESTURE_PHASES))
    if unknown:
        raise InputError(path, where, f"unknown phase {unknown[0]!r}; expected {', '.join(GESTURE_PHASES)}")
    times = [(k, table[k]) for k in GESTURE_PHASES if k in table]
    for k, t in times:
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not (t >= 0.0 and t < float("inf")):
            raise InputError(path, f"{where}.{k}", f"expected seconds >= 0, got {t!r}")
    for (k0, t0), (k1, t1) in zip(times, times[1:]):
        if t1 < t0:
            raise InputError(path, f"{where}.{k1}", f"{k1} ({t1:g} s) comes before {k0} ({t0:g} s)")
    return {k: float(t) for k, t in times}


def _toml_value(value) -> str:
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    text = str(value).replace("\\", "\\\\").replace('"', '\\"')
    return f'"{text}"'


def manifest_text(pack: dict, clips: list[dict]) -> str:
    """TOML text of a manifest from a ``pack`` table and a list of clip tables (plain values only)."""
    lines = ["[pack]"] + [f"{k} = {_toml_value(v)}" for k, v in pack.items() if v is not None]
    for c in clips:
        lines += ["", "[[clips]]"] + [f"{k} = {_toml_value(v)}" for k, v in c.items() if v is not None]
    return "\n".join(lines) + "\n"


def write_manifest(path: str | Path, pack: dict, clips: list[dict]) -> Path:
    """Write a manifest atomically (see :func:`manifest_text`); returns ``path``."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(manifest_text(pack, clips), encoding="utf-8")
    return path
