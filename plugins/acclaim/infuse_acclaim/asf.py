"""Parsing Acclaim ``.asf`` skeletons.

Sections (``#`` comments)::

    :version 1.10          :name VICON
    :units   mass M / length L / angle deg|rad
    :documentation  free text
    :root    order TX TY TZ RX RY RZ / axis XYZ / position x y z / orientation a b c
    :bonedata  begin id N / name S / direction x y z / length l / axis a b c XYZ /
               dof rx ry rz / limits (lo hi) per dof [/ bodymass m / cofmass c] end ...
    :hierarchy begin / PARENT CHILD... / end
    :skin    file names (ignored)

``axis a b c ORDER``: ``a b c`` are the angles about the axes named by ``ORDER`` (first number,
first letter); the rotation applies them in that order about fixed axes, so ``XYZ`` is
``Rz(c) Ry(b) Rx(a)``. Lengths are in file units (``length L`` scales them, see :func:`length_unit`).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from infuse import quaternions as quat
from infuse.errors import InputError, UnusableInputError

ROTATION_DOFS = ("rx", "ry", "rz")
_AXES = {"x": np.array([1.0, 0.0, 0.0]), "y": np.array([0.0, 1.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}
_LIMIT = re.compile(r"\(\s*(\S+?)\s*,?\s+(\S+?)\s*\)")


def axis_rotation(order: str, angles: np.ndarray) -> np.ndarray:
    """Quaternions (...,4) turning by ``angles[..., i]`` (radians) about axis ``order[i]``, in that order.

    Fixed-axis (extrinsic) composition: ``order = "xyz"`` gives ``Rz Ry Rx``, the first axis applied first.
    """
    angles = np.asarray(angles, dtype=np.float64)
    q = quat.identity(angles.shape[:-1])
    for i, axis in enumerate(order.lower()):
        q = quat.multiply(quat.from_axis_angle(_AXES[axis], angles[..., i]), q)
    return q


@dataclass
class Bone:
    name: str
    line: int
    direction: np.ndarray
    length: float
    axis: np.ndarray  # angles in the file's angle unit, in ``axis_order``
    axis_order: str = "XYZ"
    dof: list[str] = field(default_factory=list)
    limits: list[tuple[float, float]] = field(default_factory=list)
    extra: dict = field(default_factory=dict)


@dataclass
class AsfFile:
    """A parsed ``.asf``; ``order`` lists the bones parents-first (without the root)."""

    path: Path
    version: str | None
    name: str | None
    units: dict
    documentation: str
    root_order: list[str]
    root_axis: str
    root_position: np.ndarray
    root_orientation: np.ndarray
    bones: dict[str, Bone]
    parent: dict[str, str]
    order: list[str]

    @property
    def length_scale(self) -> float:
        return float(self.units.get("length", 1.0))

    @property
    def radians_per_unit(self) -> float:
        return 1.0 if str(self.units.get("angle", "deg")).lower().startswith("rad") else math.pi / 180.0


class _Lines:
    """Non-empty lines without comments, with their 1-based numbers."""

    def __init__(self, text: str, file: Path):
        self.file = file
        self.items = [(i + 1, line.split("#", 1)[0].strip()) for i, line in enumerate(text.splitlines())]
        self.items = [(n, line) for n, line in self.items if line]
        self.pos = 0

    def error(self, line: int, problem: str) -> InputError:
        return InputError(self.file, f"line {line}", problem)

    def peek(self):
        return self.items[self.pos] if self.pos < len(self.items) else None

    def next(self, what: str):
        if self.pos >= len(self.items):
            last = self.items[-1][0] if self.items else 1
            raise self.error(last, f"unexpected end of file, expected {what}")
        item = self.items[self.pos]
        self.pos += 1
        return item


def _numbers(lines: _Lines, line: int, words: list[str], count: int, what: str) -> np.ndarray:
    if len(words) < count:
        raise lines.error(line, f"{what} needs {count} numbers, found {len(words)}")
    try:
        values = np.array([float(w) for w in words[:count]])
    except ValueError:
        raise lines.error(line, f"{what}: {' '.join(words[:count])!r} are not all numbers") from None
    if not np.all(np.isfinite(values)):
        raise lines.error(line, f"{what} is not finite")
    return values


def _order(lines: _Lines, line: int, word: str, what: str) -> str:
    if sorted(word.upper()) != ["X", "Y", "Z"]:
        raise lines.error(line, f"{what} must be an order of X, Y and Z, found {word!r}")
    return word.upper()


def _read_bone(lines: _Lines, start: int) -> Bone:
    name = ""
    direction: np.ndarray | None = None
    length: float | None = None
    axis: np.ndarray | None = None
    axis_order = "XYZ"
    dof: list[str] = []
    limits: list[tuple[float, float]] = []
    extra: dict = {}
    while True:
        line, text = lines.next(f"'end' of the bone that begins on line {start}")
        key, *words = text.split()
        key = key.lower()
        if key == "end":
            break
        if key == "begin":
            raise lines.error(line, f"'begin' before the 'end' of the bone that begins on line {start}")
        if key == "id":
            extra["id"] = " ".join(words)
        elif key == "name":
            if len(words) != 1:
                raise lines.error(line, "a bone name is one word")
            name = words[0]
        elif key == "direction":
            direction = _numbers(lines, line, words, 3, "direction")
        elif key == "length":
            length = float(_numbers(lines, line, words, 1, "length")[0])
            if length < 0:
                raise lines.error(line, f"negative bone length {length}")
        elif key == "axis":
            axis = _numbers(lines, line, words, 3, "axis")
            axis_order = _order(lines, line, words[3] if len(words) > 3 else "", "the axis order")
        elif key == "dof":
            dof = [w.lower() for w in words]
            bad = [w for w in dof if w not in ROTATION_DOFS + ("tx", "ty", "tz", "l")]
            if bad or len(set(dof)) != len(dof):
                raise lines.error(line, f"bad dof list {' '.join(words)!r} (rx ry rz tx ty tz l, each once)")
        elif key == "limits":
            rest = " ".join(words)
            found = len(_LIMIT.findall(rest))  # counted line by line: re-reading the whole text each time was quadratic
            while found < len(dof) and lines.peek() and lines.peek()[1].startswith("("):
                more = lines.next("a limit")[1]
                rest += " " + more
                found += len(_LIMIT.findall(more))
            pairs = _LIMIT.findall(rest)
            if len(pairs) != len(dof):
                raise lines.error(line, f"{len(pairs)} limits for {len(dof)} dofs")
            try:
                limits = [(float(a), float(b)) for a, b in pairs]
            except ValueError:
                raise lines.error(line, f"limits {rest!r} are not numbers") from None
            if any(math.isnan(a) or math.isnan(b) or a > b for a, b in limits):  # +-inf: no limit that way
                raise lines.error(line, f"limits {rest!r} are not ordered pairs of numbers")
        elif key in ("bodymass", "cofmass"):
            extra[key] = float(_numbers(lines, line, words, 1, key)[0])
        else:
            raise lines.error(line, f"unexpected {key!r} in a bone")
    if not name:
        raise lines.error(start, "bone without name")
    if direction is None:
        raise lines.error(start, "bone without direction")
    if length is None:
        raise lines.error(start, "bone without length")
    if axis is None:
        raise lines.error(start, "bone without axis")
    return Bone(name, start, direction, length, axis, axis_order, dof, limits, extra)


def _read_hierarchy(lines: _Lines, bones: dict[str, Bone]) -> dict[str, str]:
    line, text = lines.next("'begin' of the hierarchy")
    if text.lower() != "begin":
        raise lines.error(line, f"expected 'begin' after :hierarchy, found {text[:30]!r}")
    parent: dict[str, str] = {}
    while True:
        line, text = lines.next("'end' of the hierarchy")
        names = text.split()
        if names[0].lower() == "end":
            return parent
        if len(names) < 2:
            raise lines.error(line, f"a hierarchy line names a parent and its children, found {text[:30]!r}")
        for name in names:
            if name != "root" and name not in bones:
                raise lines.error(line, f"unknown bone {name!r} in the hierarchy")
        for child in names[1:]:
            if child == "root":
                raise lines.error(line, "root cannot be a child")
            if child in parent:
                raise lines.error(line, f"bone {child!r} has two parents ({parent[child]!r} and {names[0]!r})")
            parent[child] = names[0]


def _topological(file: Path, bones: dict[str, Bone], parent: dict[str, str]) -> list[str]:
    children: dict[str, list[str]] = {}
    for child, p in parent.items():
        children.setdefault(p, []).append(child)
    order: list[str] = []
    stack = list(reversed(children.get("root", [])))
    while stack:
        name = stack.pop()
        order.append(name)
        stack.extend(reversed(children.get(name, [])))
    unreached = [b for b in bones if b not in set(order)]
    if unreached:
        b = bones[unreached[0]]
        problem = "is not connected to the root in :hierarchy" + (" (a cycle)" if unreached[0] in parent else "")
        raise InputError(file, f"line {b.line}", f"bone {b.name!r} {problem}")
    return order


def parse_asf(path: Path, text: str) -> AsfFile:
    """Parse ``.asf`` text; malformed input raises :class:`InputError` naming the line."""
    lines = _Lines(text, path)
    if not lines.items:
        raise InputError(path, None, "empty file")
    units: dict = {}
    version = name = None
    doc: list[str] = []
    root_order: list[str] | None = None
    root_axis = "XYZ"
    position = np.zeros(3)
    orientation = np.zeros(3)
    bones: dict[str, Bone] = {}
    parent: dict[str, str] | None = None
    section = None
    while lines.peek() is not None:
        line, text_line = lines.next("a section")
        key, *words = text_line.split()
        if key.startswith(":"):
            section = key[1:].lower()
            if section == "version":
                version = " ".join(words)
            elif section == "name":
                name = " ".join(words)
            elif section == "hierarchy":
                parent = _read_hierarchy(lines, bones)
            elif section not in ("units", "documentation", "root", "bonedata", "skin"):
                raise lines.error(line, f"unknown section {key!r}")
            continue
        low = key.lower()
        if section == "units":
            if low == "angle":
                if not words or words[0].lower() not in ("deg", "rad", "degree", "degrees", "radian", "radians"):
                    raise lines.error(line, f"angle unit must be deg or rad, found {' '.join(words)!r}")
                units["angle"] = words[0].lower()
            else:
                units[low] = float(_numbers(lines, line, words, 1, f"units {low}")[0])
                if units[low] <= 0:
                    raise lines.error(line, f"units {low} must be positive")
        elif section == "documentation":
            doc.append(text_line)
        elif section == "root":
            if low == "order":
                root_order = [w.upper() for w in words]
                if not root_order or any(w not in ("TX", "TY", "TZ", "RX", "RY", "RZ") for w in root_order) \
                        or len(set(root_order)) != len(root_order):
                    raise lines.error(line, f"bad root order {' '.join(words)!r}")
            elif low == "axis":
                root_axis = _order(lines, line, words[0] if words else "", "the root axis order")
            elif low == "position":
                position = _numbers(lines, line, words, 3, "root position")
            elif low == "orientation":
                orientation = _numbers(lines, line, words, 3, "root orientation")
            else:
                raise lines.error(line, f"unexpected {key!r} in :root")
        elif section == "bonedata":
            if low != "begin":
                raise lines.error(line, f"expected 'begin' of a bone, found {key!r}")
            bone = _read_bone(lines, line)
            if bone.name in bones or bone.name == "root":
                raise lines.error(line, f"duplicate bone name {bone.name!r}")
            bones[bone.name] = bone
        elif section == "skin":
            continue
        else:
            raise lines.error(line, f"unexpected {key!r} outside a section")
    if root_order is None:
        raise InputError(path, None, "no ':root' section with an 'order' line")
    if parent is None:
        raise InputError(path, None, "no ':hierarchy' section")
    if any(d in ("tx", "ty", "tz", "l") for b in bones.values() for d in b.dof):
        bone = next(b for b in bones.values() if any(d in ("tx", "ty", "tz", "l") for d in b.dof))
        raise UnusableInputError(path, f"line {bone.line}: bone {bone.name!r} has translation or length dofs, "
                                 "which are not supported")
    order = _topological(path, bones, parent)
    return AsfFile(path, version, name, units, "\n".join(doc), root_order, root_axis, position, orientation,
                   bones, parent, order)
