"""The visual scene as a flat node list: parents, transform stacks, and which nodes are joints.

A node's local matrix is the product of its transform elements in document order
(``<translate>``, ``<rotate>`` in degrees, ``<scale>``, ``<matrix>`` row-major, ``<lookat>``).
Joints are nodes with ``type="JOINT"`` plus every node a skin controller names; other nodes
are kept so their transforms can be folded into the joints below them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UnusableInputError

from .document import Document, place

#: Number of values of each supported transform element.
TRANSFORM_SIZES = {"translate": 3, "rotate": 4, "scale": 3, "matrix": 16, "lookat": 9}

#: Largest scene graph read (after expanding ``<instance_node>``), against reference explosions.
MAX_NODES = 100_000

#: Member names a channel may target inside a transform element (``node/sid.ANGLE``).
MEMBERS = {"X": 0, "Y": 1, "Z": 2, "ANGLE": 3}


@dataclass
class Transform:
    """One transform element: ``kind`` (a key of :data:`TRANSFORM_SIZES`), its ``sid`` and its values."""

    kind: str
    sid: str | None
    values: np.ndarray


@dataclass
class SceneNode:
    """A ``<node>`` of the visual scene; ``parent`` indexes the node list (-1 for roots)."""

    id: str | None
    sid: str | None
    name: str
    parent: int
    typed_joint: bool
    transforms: list[Transform] = field(default_factory=list)


def visual_scene(doc: Document):
    """The ``<visual_scene>`` the document instantiates (or its first one)."""
    inst = doc.root.find("scene/instance_visual_scene")
    if inst is not None:
        return doc.resolve(inst.get("url"), inst)
    scene = doc.root.find("library_visual_scenes/visual_scene")
    if scene is None:
        raise doc.error(doc.root, "no <visual_scene>: the file has no scene graph")
    return scene


def flatten(doc: Document, scene) -> tuple[list[SceneNode], list]:
    """Every node under ``scene`` in depth-first order (parents first), with the matching elements.

    ``<instance_node>`` references are followed; a reference back into its own ancestry is a
    cycle and raises :class:`InputError`.
    """
    nodes: list[SceneNode] = []
    elements: list = []
    stack: list[tuple[Any, int, tuple[Any, ...]]] = [(el, -1, ()) for el in reversed(scene.findall("node"))]
    while stack:
        el, parent, ancestry = stack.pop()
        if any(el is a for a in ancestry):
            raise doc.error(el, "node hierarchy has a cycle (through <instance_node>)")
        if len(nodes) >= MAX_NODES:
            raise doc.error(el, f"more than {MAX_NODES} nodes once <instance_node> references are expanded")
        index = len(nodes)
        nodes.append(SceneNode(el.get("id"), el.get("sid"), el.get("name") or el.get("id") or el.get("sid") or f"node{index}",
                               parent, el.get("type") == "JOINT", _transforms(doc, el)))
        elements.append(el)
        ancestry = ancestry + (el,)
        children = list(el.findall("node"))
        children += [doc.resolve(inst.get("url"), inst) for inst in el.findall("instance_node")]
        for child in reversed(children):
            if child.tag != "node":
                raise doc.error(child, f"<instance_node> points to <{child.tag}>, expected <node>")
            stack.append((child, index, ancestry))
    return nodes, elements


def _transforms(doc: Document, el) -> list[Transform]:
    out = []
    for child in el:
        if child.tag in TRANSFORM_SIZES:
            out.append(Transform(child.tag, child.get("sid"), doc.floats(child, TRANSFORM_SIZES[child.tag])))
        elif child.tag == "skew":
            raise UnusableInputError(doc.path, f"{place(child)}: <skew> transforms are not supported")
    return out


def transform_matrices(kind: str, values: np.ndarray) -> np.ndarray:
    """Matrices (F, 4, 4) of one transform element from its values (F, k), vectorized over frames."""
    values = np.asarray(values, dtype=np.float64)
    out = np.broadcast_to(np.eye(4), values.shape[:1] + (4, 4)).copy()
    if kind == "translate":
        out[:, :3, 3] = values
    elif kind == "scale":
        out[:, [0, 1, 2], [0, 1, 2]] = values
    elif kind == "rotate":
        axis = values[:, :3]
        norm = np.linalg.norm(axis, axis=-1, keepdims=True)
        unit = np.where(norm > 1e-12, axis / np.where(norm > 1e-12, norm, 1.0), [1.0, 0.0, 0.0])
        out[:, :3, :3] = quat.to_matrix(quat.from_axis_angle(unit, np.radians(values[:, 3])))
    elif kind == "matrix":
        out[:] = values.reshape(-1, 4, 4)
    elif kind == "lookat":
        eye, target, up = values[:, 0:3], values[:, 3:6], values[:, 6:9]
        z = _unit(eye - target)
        x = _unit(np.cross(up, z))
        out[:, :3, 0], out[:, :3, 1], out[:, :3, 2], out[:, :3, 3] = x, np.cross(z, x), z, eye
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def local_matrices(nodes: list[SceneNode], animated: dict[tuple[int, int], np.ndarray] | None = None,
                   frames: int = 1) -> np.ndarray:
    """Local matrices (F, N, 4, 4) of every node.

    ``animated`` maps (node index, transform index) to per-frame values (F, k) that replace the
    element's static values; other elements keep their static values on every frame.
    """
    animated = animated or {}
    out = np.broadcast_to(np.eye(4), (frames, len(nodes), 4, 4)).copy()
    for n, node in enumerate(nodes):
        for t, tr in enumerate(node.transforms):
            values = animated.get((n, t))
            if values is None:
                out[:, n] = out[:, n] @ transform_matrices(tr.kind, tr.values[None])[0]
            else:
                out[:, n] = out[:, n] @ transform_matrices(tr.kind, values)
    return out


def joint_indices(doc: Document, nodes: list[SceneNode], elements: list) -> list[int]:
    """Indices of the joint nodes: typed joints and every node a skin instanced in the scene names, in node order."""
    chosen = {i for i, node in enumerate(nodes) if node.typed_joint}
    index_of = {id(el): i for i, el in enumerate(elements)}
    for inst in (i for el in elements for i in el.findall("instance_controller")):
        controller = doc.resolve(inst.get("url"), inst)
        joints_input = controller.find("skin/joints/input[@semantic='JOINT']")
        if joints_input is None:
            continue
        names = doc.source(joints_input.get("source"), joints_input, numeric=False).ravel()
        roots = [doc.resolve(s.text and s.text.strip(), s) for s in inst.findall("skeleton")]
        for name in names:
            found = find_joint(nodes, elements, index_of, roots, str(name))
            if found is None:
                raise doc.error(controller, f"skin names joint {str(name)[:60]!r}, which is not a node of the scene")
            chosen.add(found)
    return sorted(chosen)


def find_joint(nodes, elements, index_of, roots, name: str) -> int | None:
    """A skin's joint reference: a sid under the ``<skeleton>`` roots, else a sid, id or name anywhere."""
    for root in roots:
        if root.get("sid") == name and id(root) in index_of:
            return index_of[id(root)]
        for el in root.iter("node"):
            if el.get("sid") == name and id(el) in index_of:
                return index_of[id(el)]
    for attr in ("sid", "id", "name"):
        for i, node in enumerate(nodes):
            if getattr(node, attr) == name:
                return i
    return None


def unique_names(nodes: list[SceneNode], joints: list[int]) -> list[str]:
    """Joint names (node ``name``, else id, else sid), made unique with the id or a ``#k`` suffix."""
    names = [nodes[n].name for n in joints]
    counts: dict[str, int] = {}
    for name in names:
        counts[name] = counts.get(name, 0) + 1
    seen: set[str] = set()
    out = []
    for n, name in zip(joints, names):
        node_id = nodes[n].id
        if counts[name] > 1 and node_id and node_id not in counts:
            name = node_id
        base, k = name, 1
        while name in seen:
            k += 1
            name = f"{base}#{k}"
        seen.add(name)
        out.append(name)
    return out
