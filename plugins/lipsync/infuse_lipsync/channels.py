"""Which face channels a character offers: found from its names, or declared in its map file.

A character offers *vocabularies* of channels (``names.toml``): Meta/Oculus visemes, ARKit shapes,
VRM expressions, the SmartBody viseme sets and FACS poses. Each offered channel is bound to what
drives it on this character:

- ``"morph"``: morph target names (a VRM expression name counts: the glTF writer drives its binds),
  as ``[(target, weight)]``;
- ``"pose"``: SmartBody face poses (``<Character>@<pose>.skm`` beside the skeleton or in ``face/``),
  as ``[(pose name, weight)]``; the pose files are in :attr:`FaceChannels.poses`;
- a jaw joint (:attr:`FaceChannels.jaw`) for the plain joint face.

A map file may declare them (its ``"face"`` entry), e.g.::

    {"mapping": {...},
     "face": {"vocabularies": {"oculus": {"PP": "MouthClosed", "aa": ["MouthOpen", 0.8]},
                               "arkit": {"jawOpen": [["JawDown", 1.0], ["LipsApart", 0.3]]}},
              "jaw": "JawBone", "viseme_set": "oculus"}}

Declared vocabularies replace detected ones of the same name.
"""
from __future__ import annotations

import json
import functools
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from infuse.errors import InputError

from .tables import VISEME_SETS, names_table, viseme_set

Binding = list[tuple[str, float]]


_SEPARATORS = re.compile(r"[\s_\-.:|]+")


@functools.lru_cache(maxsize=4096)
def normalized(name: str) -> str:
    """Lower case without ``_ - . : |`` and spaces, for comparing names (the same few names recur)."""
    return _SEPARATORS.sub("", name).lower()


def _name_keys(name: str) -> list[str]:
    """The name, and the name without a leading mesh or rig prefix ("Head.viseme_aa", "rig|jawOpen")."""
    keys = [normalized(name)]
    for sep in (".", "|", ":"):
        if sep in name:
            keys.append(normalized(name.rsplit(sep, 1)[-1]))
    return keys


@dataclass
class FaceChannels:
    """The face channels of one character.

    - ``vocabularies``: vocabulary -> channel -> ``[(target, weight)]``;
    - ``kinds``: vocabulary -> ``"morph"`` or ``"pose"``;
    - ``jaw``: the jaw joint name, if any; ``poses``: SmartBody pose name -> ``.skm`` path;
    - ``declared``: vocabularies that came from a map file; ``notes``: what was seen but is unusable.
    """

    vocabularies: dict[str, dict[str, Binding]] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)
    jaw: str | None = None
    poses: dict[str, Path] = field(default_factory=dict)
    declared: tuple[str, ...] = ()
    preferred_set: str | None = None
    notes: list[str] = field(default_factory=list)

    def viseme_sets(self) -> list[str]:
        """The viseme sets this character can show, best first."""
        out = [s for s in VISEME_SETS if s != "jaw" and s in self.vocabularies]
        if self.jaw is not None:
            out.append("jaw")
        if self.preferred_set in out:
            out.remove(self.preferred_set)
            out.insert(0, self.preferred_set)
        return out

    def summary(self) -> dict[str, Any]:
        return {
            "viseme_sets": self.viseme_sets(),
            "vocabularies": {v: {c: [list(b) for b in binds] for c, binds in chans.items()} for v, chans in self.vocabularies.items()},
            "kinds": dict(self.kinds), "jaw": self.jaw, "poses": sorted(self.poses), "declared": list(self.declared),
            "notes": list(self.notes),
        }


def _match(names: list[str], vocab: dict) -> dict[str, Binding]:
    """Channel -> [(name, 1.0)] for the names that mean each channel (first match in ``names`` order)."""
    by_key: dict[str, str] = {}
    for n in names:
        for k in _name_keys(n):
            by_key.setdefault(k, n)
    found: dict[str, Binding] = {}
    for channel, aliases in vocab["channels"].items():
        for alias in [channel, *aliases]:
            hit = by_key.get(normalized(alias))
            if hit is not None:
                found[channel] = [(hit, 1.0)]
                break
    return found


def _offered(found: dict[str, Binding], vocab: dict) -> bool:
    return len(found) >= vocab.get("min_found", 1) and all(r in found for r in vocab.get("required", []))


def find_jaw(joint_names: list[str]) -> str | None:
    """The jaw joint among ``joint_names`` (see ``[jaw]`` in names.toml), or ``None``."""
    spec = names_table()["jaw"]
    keys = {normalized(n): n for n in joint_names}
    for preferred in spec["names"]:
        if normalized(preferred) in keys:
            return keys[normalized(preferred)]
    excluded = [normalized(w) for w in spec["exclude"]]
    for n in joint_names:
        k = normalized(n)
        if "jaw" in k and not any(w in k for w in excluded):
            return n
    return None


def find_face_poses(path: Path | None) -> dict[str, Path]:
    """SmartBody face poses beside a ``.sk``/``.skm`` (``<name>@<pose>.skm`` there or in ``face/``)."""
    if path is None:
        return {}
    folder = Path(path).parent
    poses: dict[str, Path] = {}
    for where in (folder / "face", folder):
        if where.is_dir():
            for f in sorted(where.glob("*@*.skm")):
                poses.setdefault(f.stem.split("@", 1)[1], f)
    return poses


def _drivable_morphs(asset) -> tuple[list[str], list[str]]:
    """Morph target names a writer can animate, and notes about names it cannot (VRM expressions that
    bind no morph target, e.g. texture-only expressions)."""
    names = list(getattr(asset, "morph_targets", []) or [])
    vrm = getattr(getattr(asset, "payload", None), "vrm", None)
    notes = []
    if vrm is not None:
        undrivable = [e.name for e in getattr(vrm, "expressions", []) if not getattr(e, "binds", None) and getattr(e, "node", None) is None]
        if undrivable:
            notes.append(f"VRM expressions {', '.join(undrivable)} bind no morph targets (e.g. texture changes only) and cannot be animated")
            names = [n for n in names if n not in undrivable]
    return names, notes


def detect_face(asset, map_file: str | Path | dict | None = None) -> FaceChannels:
    """The face channels of ``asset`` (an :class:`~infuse.asset.Asset`), from its names and an optional
    map file (path or parsed document) with a ``"face"`` entry."""
    vocabularies = names_table()["vocabularies"]
    morphs, notes = _drivable_morphs(asset)
    face = FaceChannels(notes=notes)
    for name, vocab in vocabularies.items():
        found = _match(morphs, vocab)
        if _offered(found, vocab):
            face.vocabularies[name] = found
            face.kinds[name] = "morph"
    is_smartbody = str(getattr(asset, "format", "")).startswith("smartbody")
    poses = find_face_poses(getattr(asset, "path", None)) if is_smartbody else {}
    if poses:
        for name in ("smartbody_diphone", "smartbody_facs", "smartbody"):
            found = _match(list(poses), vocabularies[name])
            if name not in face.vocabularies and _offered(found, vocabularies[name]):
                face.vocabularies[name] = found
                face.kinds[name] = "pose"
        face.poses = poses
    skeleton = getattr(asset, "skeleton", None)
    face.jaw = find_jaw(list(skeleton.names)) if skeleton is not None else None
    if map_file is not None:
        _declare(face, map_file, morphs, skeleton)
    return face


def _declare(face: FaceChannels, map_file, morphs: list[str], skeleton) -> None:
    if isinstance(map_file, dict):
        doc, source = map_file, "<map>"
    else:
        source = str(map_file)
        path = Path(map_file)
        if not path.is_file():
            raise InputError(path, None, "map file not found")
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InputError(path, None, f"not a JSON map file: {exc}") from None
    spec = doc.get("face") if isinstance(doc, dict) else None
    if spec is None:
        return
    if not isinstance(spec, dict):
        raise InputError(source, "face", 'expected an object {"vocabularies": {...}, "jaw": ..., "viseme_set": ...}')
    vocabularies = names_table()["vocabularies"]
    declared = []
    known = set(morphs) | set(face.poses)
    for vname, channels in (spec.get("vocabularies") or {}).items():
        if vname not in vocabularies:
            raise InputError(source, f"face.vocabularies.{vname}", f"unknown vocabulary; known: {', '.join(vocabularies)}")
        if not isinstance(channels, dict):
            raise InputError(source, f"face.vocabularies.{vname}", "expected an object {channel: target}")
        bound: dict[str, Binding] = {}
        for channel, target in channels.items():
            place = f"face.vocabularies.{vname}.{channel}"
            if channel not in vocabularies[vname]["channels"]:
                raise InputError(source, place, f"{channel!r} is not a {vname} channel")
            bound[channel] = _binding(target, source, place)
            for t, _ in bound[channel]:
                if t not in known:
                    raise InputError(source, place, f"{t!r} is not a morph target or face pose of this character")
        face.vocabularies[vname] = bound
        face.kinds[vname] = "pose" if all(t in face.poses for b in bound.values() for t, _ in b) and face.poses else "morph"
        declared.append(vname)
    if spec.get("jaw") is not None:
        jaw = spec["jaw"]
        if skeleton is None or jaw not in skeleton.index:
            raise InputError(source, "face.jaw", f"joint {jaw!r} is not in the skeleton")
        face.jaw = jaw
    if spec.get("viseme_set") is not None:
        if spec["viseme_set"] not in VISEME_SETS:
            raise InputError(source, "face.viseme_set", f"unknown viseme set; known: {', '.join(VISEME_SETS)}")
        face.preferred_set = spec["viseme_set"]
    face.declared = tuple(declared)


def _binding(target, source: str, place: str) -> Binding:
    """``"name"``, ``["name", weight]`` or ``[["name", weight], ...]`` -> ``[(name, weight)]``."""
    if isinstance(target, str):
        return [(target, 1.0)]
    if isinstance(target, list) and len(target) == 2 and isinstance(target[0], str) and isinstance(target[1], (int, float)):
        return [(target[0], float(target[1]))]
    if isinstance(target, list) and all(isinstance(t, list) and len(t) == 2 and isinstance(t[0], str)
                                        and isinstance(t[1], (int, float)) for t in target):
        return [(t[0], float(t[1])) for t in target]
    raise InputError(source, place, 'expected "target", ["target", weight] or [["target", weight], ...]')


def viseme_set_binding(face: FaceChannels, set_name: str) -> dict[str, Binding]:
    """Channel -> binding for the channels of viseme set ``set_name`` this character has."""
    if set_name == "jaw":
        return {"jaw": [(face.jaw, 1.0)]} if face.jaw else {}
    offered = face.vocabularies.get(set_name, {})
    return {c: offered[c] for c in viseme_set(set_name).channels if c in offered}
