"""Scene files: characters, objects and timed BML blocks, in TOML or XML, for ``infuse run``.

TOML::

    fps = 30                      # optional (30)
    duration = 12.0               # optional: seconds to realize (default: until every block has ended)
    generators = ["nonverbal"]    # optional: BML generators on for every block (gestures from speech...)
    [tts]                         # optional: engine ("espeak"), voice, rate...
    rate = 160

    [[character]]
    name = "bob"
    file = "${INFUSE_CORPUS:-../corpus}/runxaway-models/Xbot.glb"
    position = [0.0, 0.0, 0.0]    # metres (default the origin)
    facing = "ann"                # degrees about +Y (0 = +Z), a point [x, z] / [x, y, z], or a name
    packs = ["gestures"]          # behaviour packs (optional)
    map = "bob.map.json"          # a saved joint map, may declare face channels (optional)
    voice = "en-us"               # TTS voice (optional)

    [[object]]
    name = "cup"
    position = [0.4, 1.0, 1.6]
    size = 0.1                    # metres (default 0.1)

    [[block]]
    at = 0.5                      # global start, seconds (default 0)
    character = "bob"             # optional when the BML names its characterId
    bml = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1"><head id="h1" lexeme="NOD"/></bml>'
    # or: file = "blocks/nod.xml"

XML: ``<scene fps="30" duration="12" generators="nonverbal">`` holding ``<tts engine=... voice=... rate=.../>``,
``<character name file position="0 0 0" facing packs="a,b" map voice/>``, ``<object name position size/>``
and ``<block at character file=...>`` elements, the BML inline as the block's child element
(``<bml>`` or SmartBody's ``<act>``).

Paths are relative to the scene file; ``$NAME``, ``${NAME}`` and ``${NAME:-default}`` take environment
variables. Any mistake raises :class:`~infuse.errors.InputError` naming the file, the place
(``character[2].position``) and the problem; unknown keys are mistakes too.
"""
from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from .. import limits
from ..errors import InputError

_VARIABLE = re.compile(r"\$(?:\{(\w+)(?::-([^}]*))?\}|(\w+))")
_CHARACTER_KEYS = {"name", "file", "position", "facing", "packs", "map", "voice", "mapper", "format", "units", "up_axis",
                   "idle"}
_OBJECT_KEYS = {"name", "position", "size"}
_BLOCK_KEYS = {"at", "character", "bml", "file"}
_TOP_KEYS = {"fps", "duration", "tts", "seed", "idle", "generators", "character", "object", "block"}
_TTS_KEYS = {"engine", "voice", "rate", "volume"}


@dataclass
class CharacterSpec:
    name: str
    file: Path
    position: tuple = (0.0, 0.0, 0.0)
    facing: object = None
    packs: tuple = ()
    map: Path | None = None
    voice: str | None = None
    mapper: str | None = None
    format: str | None = None
    units: str | None = None
    up_axis: str | None = None
    idle: bool | None = None


@dataclass
class ObjectSpec:
    name: str
    position: tuple
    size: float = 0.1


@dataclass
class BlockSpec:
    """A BML document to play from ``at`` seconds: ``bml`` (text) or ``file``; ``place`` names it in errors."""

    at: float
    character: str | None
    bml: str | None
    file: Path | None
    place: str


@dataclass
class SceneSpec:
    path: Path
    fps: float = 30.0
    duration: float | None = None
    seed: int = 0
    idle: bool = True
    generators: tuple = ()
    tts: dict = field(default_factory=dict)
    characters: list[CharacterSpec] = field(default_factory=list)
    objects: list[ObjectSpec] = field(default_factory=list)
    blocks: list[BlockSpec] = field(default_factory=list)


def expand(text: str) -> str:
    """``text`` with ``$NAME``, ``${NAME}`` and ``${NAME:-default}`` replaced from the environment."""
    def value(m):
        name = m.group(1) or m.group(3)
        if name in os.environ:
            return os.environ[name]
        if m.group(2) is not None:
            return m.group(2)
        return m.group(0)
    return _VARIABLE.sub(value, text)


class _Reader:
    """Checks values of one scene file, raising InputError(file, place, problem)."""

    def __init__(self, path: Path):
        self.path = path

    def fail(self, place: str, problem: str):
        raise InputError(self.path, place, problem)

    def keys(self, table: dict, allowed: set, place: str) -> None:
        unknown = sorted(set(table) - allowed)
        if unknown:
            self.fail(f"{place}.{unknown[0]}" if place else unknown[0],
                      f"unknown key; expected one of: {', '.join(sorted(allowed))}")

    def number(self, value, place: str, minimum: float | None = None, positive: bool = False,
               maximum: float = limits.MAX_COORDINATE_M) -> float:
        """A finite number within +-``maximum`` (by default the largest coordinate, which bounds every
        number a scene holds; times are bounded by the day of :data:`~infuse.limits.MAX_TIME_S`)."""
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                self.fail(place, f"{value!r} is not a number")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(place, f"expected a finite number, got {value!r}")
        if positive and value <= 0:
            self.fail(place, f"must be positive, got {value!r}")
        if minimum is not None and value < minimum:
            self.fail(place, f"must be at least {minimum:g}, got {value!r}")
        if abs(value) > maximum:
            self.fail(place, f"must be within +-{maximum:g}, got {value!r}")
        return float(value)

    def text(self, value, place: str) -> str:
        if not isinstance(value, str) or not value.strip():
            self.fail(place, f"expected a non-empty string, got {value!r}")
        return value.strip()

    def flag(self, value, place: str) -> bool:
        if isinstance(value, str) and value.lower() in ("true", "false", "yes", "no", "1", "0"):
            return value.lower() in ("true", "yes", "1")
        if not isinstance(value, bool):
            self.fail(place, f"expected true or false, got {value!r}")
        return value

    def point(self, value, place: str, sizes=(3,)) -> tuple:
        if isinstance(value, str):
            value = value.replace(",", " ").split()
        if not isinstance(value, (list, tuple)) or len(value) not in sizes:
            self.fail(place, f"expected {' or '.join(str(s) for s in sizes)} numbers, got {value!r}")
        return tuple(self.number(v, f"{place}[{k}]") for k, v in enumerate(value))

    def file(self, value, place: str) -> Path:
        path = Path(expand(self.text(value, place)))
        if not path.is_absolute():
            path = self.path.parent / path
        try:
            found = path.is_file()
        except OSError as exc:  # a name too long for the file system, say
            self.fail(place, f"cannot be a file name: {exc.strerror or exc}")
        if not found:
            self.fail(place, f"file not found: {path}")
        return path

    def facing(self, value, place: str):
        if value is None or isinstance(value, str) and not _is_numbers(value):
            return value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return self.number(value, place)
        numbers = self.point(value, place, sizes=(1, 2, 3))
        return numbers[0] if len(numbers) == 1 else numbers


def _is_numbers(text: str) -> bool:
    try:
        [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        return False
    return bool(text.split())


def read_scene_file(path) -> SceneSpec:
    """Read a TOML (``.toml``) or XML (``.xml``) scene file (see the module doc)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "scene file not found")
    suffix = path.suffix.lower()
    if suffix == ".toml":
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise InputError(path, None, f"not a TOML scene file: {exc}") from None
    elif suffix == ".xml":
        doc = _xml_document(path)
    else:
        raise InputError(path, None, f"a scene file is .toml or .xml, not {suffix or 'a file without extension'}")
    return _spec(doc, _Reader(path))


def _spec(doc: dict, r: _Reader) -> SceneSpec:
    r.keys(doc, _TOP_KEYS, "")
    spec = SceneSpec(r.path)
    if "fps" in doc:
        spec.fps = r.number(doc["fps"], "fps", positive=True, maximum=limits.MAX_FPS)
    if doc.get("duration") is not None:
        spec.duration = r.number(doc["duration"], "duration", minimum=0.0, maximum=limits.MAX_TIME_S)
    if "seed" in doc:
        spec.seed = int(r.number(doc["seed"], "seed"))
    if "idle" in doc:
        spec.idle = r.flag(doc["idle"], "idle")
    if "generators" in doc:
        spec.generators = _names(doc["generators"], "generators", r)
    tts = doc.get("tts") or {}
    if not isinstance(tts, dict):
        r.fail("tts", "expected a table of TTS settings")
    r.keys(tts, _TTS_KEYS, "tts")
    spec.tts = {k: (r.number(v, f"tts.{k}") if k in ("rate", "volume") else r.text(v, f"tts.{k}")) for k, v in tts.items()}
    if "rate" in spec.tts:
        spec.tts["rate"] = int(spec.tts["rate"])
    for k, item in enumerate(_tables(doc, "character", r)):
        place = f"character[{k + 1}]"
        r.keys(item, _CHARACTER_KEYS, place)
        if "file" not in item:
            r.fail(place, "a character needs a file")
        c = CharacterSpec(r.text(item.get("name", ""), f"{place}.name") if "name" in item else "",
                          r.file(item["file"], f"{place}.file"))
        c.name = c.name or c.file.stem
        if "position" in item:
            c.position = r.point(item["position"], f"{place}.position")
        c.facing = r.facing(item.get("facing"), f"{place}.facing")
        c.packs = _names(item.get("packs", ()), f"{place}.packs", r)
        if "map" in item:
            c.map = r.file(item["map"], f"{place}.map")
        for key in ("voice", "mapper", "format", "units", "up_axis"):
            if key in item:
                setattr(c, key, r.text(item[key], f"{place}.{key}"))
        if "idle" in item:
            c.idle = r.flag(item["idle"], f"{place}.idle")
        spec.characters.append(c)
    for k, item in enumerate(_tables(doc, "object", r)):
        place = f"object[{k + 1}]"
        r.keys(item, _OBJECT_KEYS, place)
        if "position" not in item:
            r.fail(place, "an object needs a position")
        spec.objects.append(ObjectSpec(r.text(item.get("name"), f"{place}.name"), r.point(item["position"], f"{place}.position"),
                                       r.number(item.get("size", 0.1), f"{place}.size", positive=True)))
    for k, item in enumerate(_tables(doc, "block", r)):
        place = f"block[{k + 1}]"
        r.keys(item, _BLOCK_KEYS, place)
        if ("bml" in item) == ("file" in item):
            r.fail(place, "a block holds either bml (inline) or file")
        spec.blocks.append(BlockSpec(r.number(item.get("at", 0.0), f"{place}.at", maximum=limits.MAX_TIME_S),
                                     r.text(item["character"], f"{place}.character") if "character" in item else None,
                                     r.text(item["bml"], f"{place}.bml") if "bml" in item else None,
                                     r.file(item["file"], f"{place}.file") if "file" in item else None, place))
    if not spec.characters:
        r.fail("character", "the scene has no character")
    return spec


def _names(value, place: str, r: _Reader) -> tuple[str, ...]:
    """A list of names: a TOML list, or one string of names separated by commas or spaces (XML)."""
    if isinstance(value, str):
        value = [p for p in value.replace(",", " ").split() if p]
    if not isinstance(value, (list, tuple)) or not all(isinstance(p, str) and p for p in value):
        r.fail(place, f"expected a list of names, got {value!r}")
    return tuple(value)


def _tables(doc: dict, key: str, r: _Reader) -> list[dict]:
    items = doc.get(key, [])
    if isinstance(items, dict):
        items = [items]
    if not isinstance(items, list) or not all(isinstance(i, dict) for i in items):
        r.fail(key, f"expected [[{key}]] tables")
    return items


def _xml_document(path: Path) -> dict:
    """An XML scene file as the dict the TOML form gives."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False)
    try:
        tree = etree.parse(str(path), parser)
    except (etree.XMLSyntaxError, OSError) as exc:
        raise InputError(path, None, f"not an XML scene file: {exc}") from None
    if tree.docinfo.doctype:
        raise InputError(path, "line 1", "DOCTYPE declarations are refused")
    root = tree.getroot()
    if etree.QName(root).localname != "scene":
        raise InputError(path, f"line {root.sourceline}", f"the root element is <{etree.QName(root).localname}>, not <scene>")
    doc: dict = dict(root.attrib)
    kinds = {"character": "character", "object": "object", "block": "block", "tts": "tts"}
    nested = sorted(set(doc) & set(kinds))
    if nested:
        raise InputError(path, f"line {root.sourceline}", f"<scene {nested[0]}=...>: {nested[0]} is an element, not an attribute")
    for child in root:
        if not isinstance(child.tag, str):
            continue  # comments, processing instructions
        name = etree.QName(child).localname
        if name not in kinds:
            raise InputError(path, f"line {child.sourceline}", f"unknown element <{name}>; expected character, object, block, tts")
        item = dict(child.attrib)
        if name == "tts":
            doc["tts"] = item
            continue
        if name == "block":
            inner = [c for c in child if isinstance(c.tag, str)]
            if len(inner) > 1:
                raise InputError(path, f"line {child.sourceline}", "a <block> holds one BML document (<bml> or <act>)")
            if inner:
                item["bml"] = etree.tostring(inner[0], encoding="unicode")
        doc.setdefault(kinds[name], []).append(item)
    return doc
