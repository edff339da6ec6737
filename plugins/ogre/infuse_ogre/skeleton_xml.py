"""Parsing an Ogre ``.skeleton.xml`` into arrays: bones, their hierarchy, and keyframe tracks.

Values stay in the file's units and axes. Rotations are given as ``angle`` (radians) plus an
``<axis>`` child, or as ``qx qy qz qw`` attributes; they are returned as (x, y, z, w) quaternions.
Parsing is safe: no entities, no DTD, no network.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree

from infuse import quaternions as quat
from infuse.errors import InputError

_PARSER_OPTIONS = dict(resolve_entities=False, no_network=True, huge_tree=False, load_dtd=False,
                       remove_comments=True, remove_pis=True)


@dataclass
class Bones:
    """The binding pose, bones in topological order (parents first). Positions in file units."""

    names: list[str]
    parents: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray
    scales: np.ndarray


@dataclass
class Track:
    """Keyframes of one bone, sorted by time: offsets from the binding pose (Ogre semantics)."""

    bone: int
    times: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray
    scales: np.ndarray


@dataclass
class Animation:
    name: str
    length: float
    tracks: list[Track]


class _Reader:
    def __init__(self, path: Path):
        self.path = path

    def error(self, element, problem: str) -> InputError:
        where = f"line {element.sourceline} <{element.tag}>" if element is not None and element.sourceline else None
        return InputError(self.path, where, problem)

    def number(self, element, name: str, default: float | None = None) -> float:
        raw = element.get(name)
        if raw is None:
            if default is None:
                raise self.error(element, f"missing attribute {name!r}")
            return default
        try:
            value = float(raw)
        except ValueError:
            raise self.error(element, f"{name}={raw[:40]!r} is not a number") from None
        if not math.isfinite(value):
            raise self.error(element, f"{name}={raw!r} is not finite")
        return value

    def vector(self, element, default: tuple[float, float, float] | None = None) -> list[float]:
        """``x y z`` attributes (a ``factor`` attribute means a uniform scale)."""
        if element is None:
            if default is None:
                raise InputError(self.path, None, "missing vector element")
            return list(default)
        if element.get("factor") is not None:
            return [self.number(element, "factor")] * 3
        return [self.number(element, k) for k in "xyz"]

    def raw_rotation(self, element) -> list[float]:
        """``[kind, a, b, c, d]``: kind 0 is angle + axis (radians), 1 a quaternion (x, y, z, w); no element: identity."""
        if element is None:
            return [1.0, 0.0, 0.0, 0.0, 1.0]
        if element.get("qw") is not None:
            return [1.0] + [self.number(element, k) for k in ("qx", "qy", "qz", "qw")]
        axis_el = element.find("axis")
        if axis_el is None:
            raise self.error(element, "rotation has no <axis>")
        return [0.0, self.number(element, "angle")] + self.vector(axis_el)

    def rotations(self, raw: np.ndarray, elements) -> np.ndarray:
        """Unit quaternions (K, 4) from raw rotations (K, 5), vectorized; ``elements`` place errors."""
        is_quat = raw[:, 0] == 1.0
        axis = raw[:, 2:5]
        norm = np.linalg.norm(np.where(is_quat[:, None], raw[:, 1:4], axis), axis=-1)
        qnorm = np.linalg.norm(raw[:, 1:5], axis=-1)
        bad = np.nonzero(np.where(is_quat, qnorm < 1e-12, (norm < 1e-12) & (np.abs(raw[:, 1]) > 1e-12)))[0]
        if bad.size:
            raise self.error(elements[bad[0]], "rotation axis or quaternion is zero")
        unit_axis = axis / np.where(norm > 1e-12, norm, 1.0)[:, None]
        from_axis = quat.from_axis_angle(unit_axis, np.where(norm > 1e-12, raw[:, 1], 0.0))
        return np.where(is_quat[:, None], raw[:, 1:5] / np.where(qnorm > 0, qnorm, 1.0)[:, None], from_axis)


def parse(path: Path) -> tuple[Bones, list[Animation]]:
    """The bones and animations of an Ogre skeleton XML file; malformed input raises :class:`InputError`."""
    try:
        # From bytes, so bad encodings are syntax errors too (lxml reports them as OSError on files).
        root = etree.fromstring(path.read_bytes(), etree.XMLParser(**_PARSER_OPTIONS))
    except etree.XMLSyntaxError as exc:
        raise InputError(path, f"line {exc.lineno}" if exc.lineno else None, f"not well-formed XML: {exc.msg}") from None
    r = _Reader(path)
    if root.tag != "skeleton":
        raise r.error(root, f"root element is <{root.tag}>, expected <skeleton>")
    bones = _bones(r, root)
    index = {n: i for i, n in enumerate(bones.names)}
    animations = [_animation(r, el, index) for el in root.iterfind("animations/animation")]
    return bones, animations


def _bones(r: _Reader, root) -> Bones:
    elements = root.findall("bones/bone")
    if not elements:
        raise r.error(root, "no <bones>: the skeleton has no bones")
    names: list[str] = []
    ids: list[float] = []
    pos, rot, scl = [], [], []  # (3,) position, raw rotation and (3,) scale of each bone
    for el in elements:
        name = el.get("name")
        if not name:
            raise r.error(el, "bone has no name")
        if name in names:
            raise r.error(el, f"duplicate bone name {name!r}")
        names.append(name)
        ids.append(r.number(el, "id", float(len(ids))))
        pos_el = el.find("position")
        if pos_el is None:
            raise r.error(el, f"bone {name!r} has no <position>")
        pos.append(r.vector(pos_el))
        rot_el = el.find("rotation")
        if rot_el is None:
            raise r.error(el, f"bone {name!r} has no <rotation>")
        rot.append(r.raw_rotation(rot_el))
        scl.append(r.vector(el.find("scale"), (1.0, 1.0, 1.0)))
    parent_of: dict[int, int] = {}
    index = {n: i for i, n in enumerate(names)}
    for bp in root.iterfind("bonehierarchy/boneparent"):
        bone, parent = bp.get("bone"), bp.get("parent")
        for label, name in (("bone", bone), ("parent", parent)):
            if name not in index:
                raise r.error(bp, f"{label} {name!r} is not a bone of this skeleton")
        if index[bone] in parent_of:
            raise r.error(bp, f"bone {bone!r} has two parents")
        parent_of[index[bone]] = index[parent]
    rotations = r.rotations(np.array(rot), elements)
    order = _topological(r, names, ids, parent_of)
    new = {old: k for k, old in enumerate(order)}
    parents = np.array([new[parent_of[i]] if i in parent_of else -1 for i in order], dtype=np.int64)
    return Bones([names[i] for i in order], parents, np.array(pos)[order], rotations[order], np.array(scl)[order])


def _topological(r: _Reader, names, ids, parent_of: dict[int, int]) -> list[int]:
    """Bones depth-first from the roots, siblings by id; bones never reached sit on a cycle."""
    children: dict[int, list[int]] = {}
    for child, parent in parent_of.items():
        children.setdefault(parent, []).append(child)
    roots = sorted((i for i in range(len(names)) if i not in parent_of), key=lambda i: ids[i])
    order: list[int] = []
    stack = list(reversed(roots))
    while stack:
        i = stack.pop()
        order.append(i)
        stack.extend(sorted(children.get(i, []), key=lambda c: ids[c], reverse=True))
    if len(order) != len(names):
        stuck = sorted(set(range(len(names))) - set(order))
        raise InputError(r.path, "bonehierarchy", f"cycle through bone {names[stuck[0]]!r}")
    return order


def _animation(r: _Reader, el, index: dict[str, int]) -> Animation:
    name = el.get("name") or f"animation{el.sourceline}"
    length = r.number(el, "length")
    if length < 0:
        raise r.error(el, f"animation {name!r} has a negative length")
    tracks = []
    for track in el.iterfind("tracks/track"):
        bone = track.get("bone")
        if bone not in index:
            raise r.error(track, f"track of unknown bone {bone!r}")
        keys = track.findall("keyframes/keyframe")
        if not keys:
            continue
        columns = _columns(track, len(keys))
        if columns is None:  # element by element, to name the faulty one or fill absent parts
            columns = (np.array([r.number(k, "time") for k in keys]),
                       np.array([r.vector(k.find("translate"), (0.0, 0.0, 0.0)) for k in keys]),
                       np.array([r.raw_rotation(k.find("rotate")) for k in keys]),
                       np.array([r.vector(k.find("scale"), (1.0, 1.0, 1.0)) for k in keys]))
        times, trans, raw_rots, scales = columns
        rots = r.rotations(raw_rots, keys)
        order = np.argsort(times, kind="stable")  # Ogre keeps keyframes sorted by time
        tracks.append(Track(index[bone], times[order], trans[order], rots[order], scales[order]))
    return Animation(name, length, tracks)


def _columns(track, k: int):
    """A track's keyframe columns read in bulk (times, translations, raw rotations, scales), or
    ``None`` when some keyframe lacks a part, uses another form or holds a bad number."""
    def column(element: str, attribute: str, default: float) -> np.ndarray | None:
        present = len(track.xpath(f"keyframes/keyframe/{element}")) if element else k
        if present == 0:
            return np.full(k, default)
        values = track.xpath(f"keyframes/keyframe/{element + '/' if element else ''}@{attribute}")
        if present != k or len(values) != k:
            return None
        try:
            return np.array(values, dtype=np.float64)
        except ValueError:
            return None

    parts = [column("", "time", 0.0)]
    parts += [column("translate", a, 0.0) for a in "xyz"]
    parts += [column("rotate", "angle", 0.0)]
    parts += [column("rotate/axis", a, 1.0 if a == "x" else 0.0) for a in "xyz"]
    parts += [column("scale", a, 1.0) for a in "xyz"]
    read = [p for p in parts if p is not None and np.all(np.isfinite(p))]
    if len(read) < len(parts):
        return None
    return read[0], np.stack(read[1:4], axis=1), np.stack([np.zeros(k), *read[4:8]], axis=1), np.stack(read[8:11], axis=1)
