"""The FBX object graph: objects by id, their properties (with the file's templates), connections.

Objects live under ``Objects``; each has an int64 id, a ``name\\x00\\x01class`` name and a
subclass (``LimbNode``, ``Null``, ``Mesh``...). ``Properties70`` holds ``P`` records
(name, type, label, flags, values...) listing only what differs from the template of the
object type in ``Definitions``. ``Connections`` holds ``C`` records: ``OO`` child parent, or
``OP`` child parent property.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from infuse.errors import InputError

from .binary import Node


@dataclass
class FbxObject:
    """One object: ``kind`` (Model, Deformer...), ``subclass`` (LimbNode...), ``name`` and its properties."""

    id: int
    kind: str
    subclass: str
    name: str
    props: dict[str, list]
    node: Node


@dataclass
class Connection:
    child: int
    parent: int
    property: str | None = None


@dataclass
class Document:
    path: Path
    version: int
    root: Node
    objects: dict[int, FbxObject] = field(default_factory=dict)
    by_parent: dict[int, list[Connection]] = field(default_factory=dict)
    by_child: dict[int, list[Connection]] = field(default_factory=dict)

    def error(self, node: Node | None, problem: str) -> InputError:
        if node is None:
            return InputError(self.path, None, problem)
        return InputError(self.path, f"{'line' if node.line else 'byte'} {node.offset} ({node.name})", problem)

    def settings(self) -> dict[str, list]:
        """``GlobalSettings`` properties (UpAxis, UnitScaleFactor, TimeMode...)."""
        gs = self.root.find("GlobalSettings")
        return properties(self, gs.find("Properties70")) if gs is not None else {}

    def children_of(self, parent: int, kind: str | None = None, prop: str | None = None) -> list[tuple[FbxObject, str | None]]:
        """Objects connected under ``parent`` (optionally of ``kind``), with the connection's property."""
        out = []
        for c in self.by_parent.get(parent, ()):
            if c.child in self.objects:
                obj = self.objects[c.child]
                if (kind is None or obj.kind == kind) and (prop is None or c.property == prop):
                    out.append((obj, c.property))
        return out

    def parents_of(self, child: int, kind: str | None = None) -> list[tuple[FbxObject, str | None]]:
        out = []
        for c in self.by_child.get(child, ()):
            if c.parent in self.objects:
                obj = self.objects[c.parent]
                if kind is None or obj.kind == kind:
                    out.append((obj, c.property))
        return out


def build(path: Path, version: int, root: Node) -> Document:
    """The object graph of a parsed FBX tree."""
    doc = Document(path, version, root)
    objects = root.find("Objects")
    if objects is None:
        raise doc.error(root, "no Objects section")
    templates = _templates(doc)
    for node in objects.children:
        if len(node.props) < 3 or not isinstance(node.props[0], int) or not isinstance(node.props[1], str):
            raise doc.error(node, "object record needs an integer id, a name and a class")
        name = node.props[1].split("\x00\x01")[0]
        if "::" in name and "\x00\x01" not in node.props[1]:
            name = name.split("::", 1)[1]  # ASCII style "Model::name"
        own = properties(doc, node.find("Properties70"))
        props = dict(templates.get(node.name, {}))
        props.update(own)
        if node.props[0] in doc.objects:
            raise doc.error(node, f"duplicate object id {node.props[0]}")
        doc.objects[node.props[0]] = FbxObject(node.props[0], node.name, str(node.props[2]), name, props, node)
    section = root.find("Connections")
    for c in section.children if section is not None else []:
        if c.name != "C":
            continue
        if len(c.props) < 3 or not isinstance(c.props[1], int) or not isinstance(c.props[2], int):
            raise doc.error(c, "connection needs a type and two integer ids")
        prop = c.props[3] if c.props[0] == "OP" and len(c.props) > 3 else None
        conn = Connection(c.props[1], c.props[2], prop)
        doc.by_parent.setdefault(conn.parent, []).append(conn)
        doc.by_child.setdefault(conn.child, []).append(conn)
    return doc


def properties(doc: Document, p70: Node | None) -> dict[str, list]:
    """``P`` records of a Properties70 block: name -> values (after name, type, label, flags)."""
    out: dict[str, list] = {}
    if p70 is None:
        return out
    for p in p70.children:
        if p.name != "P":
            continue
        if len(p.props) < 4 or not isinstance(p.props[0], str):
            raise doc.error(p, "property record needs a name, a type, a label and flags")
        out[p.props[0]] = p.props[4:]
    return out


def _templates(doc: Document) -> dict[str, dict[str, list]]:
    out: dict[str, dict[str, list]] = {}
    definitions = doc.root.find("Definitions")
    for ot in definitions.find_all("ObjectType") if definitions is not None else []:
        for template in ot.find_all("PropertyTemplate"):
            if ot.props and isinstance(ot.props[0], str):
                out.setdefault(ot.props[0], {}).update(properties(doc, template.find("Properties70")))
    return out


def vector(doc: Document, obj: FbxObject, name: str, default) -> np.ndarray:
    """A 3-vector property, finite, or ``default``."""
    values = obj.props.get(name)
    if values is None:
        return np.array(default, dtype=np.float64)
    if len(values) != 3 or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        raise doc.error(obj.node, f"{obj.kind} {obj.name!r}: property {name!r} is not three numbers")
    out = np.array(values, dtype=np.float64)
    if not np.all(np.isfinite(out)):
        raise doc.error(obj.node, f"{obj.kind} {obj.name!r}: property {name!r} is not finite")
    return out


def number(doc: Document, props: dict[str, list], name: str, default: float, owner: Node | None = None) -> float:
    """A scalar property (int, float or bool), finite, or ``default``."""
    values = props.get(name)
    if not values:
        return default
    value = values[0]
    if not isinstance(value, (int, float)):
        raise doc.error(owner, f"property {name!r} is not a number")
    if not np.isfinite(value):
        raise doc.error(owner, f"property {name!r} is not finite")
    return float(value)
