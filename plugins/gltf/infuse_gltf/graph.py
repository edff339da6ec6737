"""The node graph: parents, local TRS of every node, global matrices, and similarity transforms.

glTF nodes carry ``translation`` (metres), ``rotation`` (x, y, z, w) and ``scale``, or a column-major
``matrix``; a node's transform is T · R · S in its parent's frame. :func:`node_graph` checks the
hierarchy (indices in range, one parent per node, no cycles) and :func:`node_rest_trs` decomposes
matrices into TRS. Uniform-scale transforms are handled exactly as similarities ``(t, q, s)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import limits, quaternions as quat
from infuse.errors import InputError

from .accessors import check_index


@dataclass(frozen=True)
class NodeGraph:
    """``parent`` (N,) node index of each node's parent, -1 for scene roots; ``children`` per node;
    ``order``: every node with its parent before it."""

    parent: np.ndarray
    children: tuple[tuple[int, ...], ...]
    order: tuple[int, ...]

    def ancestors(self, node: int) -> list[int]:
        """Ancestors of ``node``, nearest first."""
        out = []
        k = int(self.parent[node])
        while k >= 0:
            out.append(k)
            k = int(self.parent[k])
        return out


def node_graph(nodes: list, file) -> NodeGraph:
    """Check ``nodes[*].children`` and return the hierarchy; raises :class:`InputError` on a bad index, a
    node listed as the child of two nodes, or a cycle."""
    n = len(nodes)
    parent = np.full(n, -1, dtype=np.int64)
    children: list[tuple[int, ...]] = []
    for i, node in enumerate(nodes):
        if not isinstance(node, dict):
            raise InputError(file, f"nodes[{i}]", "is not an object")
        kids = node.get("children", [])
        if not isinstance(kids, list):
            raise InputError(file, f"nodes[{i}].children", "is not an array")
        for c in kids:
            check_index(file, f"nodes[{i}].children", c, n, "node")
            if c == i:
                raise InputError(file, f"nodes[{i}]", "lists itself as a child (cycle in the node graph)")
            if parent[c] >= 0:
                raise InputError(file, f"nodes[{c}]", f"has two parents (nodes[{parent[c]}] and nodes[{i}])")
            parent[c] = i
        children.append(tuple(kids))
    # Each node has at most one parent now, so a cycle is a loop of parents with no root above it.
    order: list[int] = []
    seen = np.zeros(n, dtype=bool)
    stack = [i for i in range(n) if parent[i] < 0][::-1]
    while stack:
        i = stack.pop()
        seen[i] = True
        order.append(i)
        stack.extend(reversed(children[i]))
    if not seen.all():
        bad = int(np.nonzero(~seen)[0][0])
        raise InputError(file, f"nodes[{bad}]", "is part of a cycle in the node graph")
    depth = np.zeros(n, dtype=np.int64)
    for i in order:
        if parent[i] >= 0:
            depth[i] = depth[parent[i]] + 1
    if n and depth.max() > limits.MAX_DEPTH:
        deepest = int(np.argmax(depth))
        limits.check(file, f"nodes[{deepest}]", "node depth", int(depth[deepest]), "MAX_DEPTH")
    return NodeGraph(parent, tuple(children), tuple(order))


def _vector(file, place: str, value, size: int, default) -> np.ndarray:
    if value is None:
        return np.array(default, dtype=np.float64)
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(file, place, f"is not an array of {size} numbers") from None
    if arr.shape != (size,):
        raise InputError(file, place, f"has {arr.size} values, expected {size}")
    if not np.all(np.isfinite(arr)):
        raise InputError(file, place, "is not finite (NaN or infinity)")
    return arr


def node_rest_trs(nodes: list, file) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest translation (N,3), rotation (N,4, x,y,z,w, unit) and scale (N,3) of every node.

    A ``matrix`` is decomposed into T · R · S; a mirroring matrix (negative determinant) becomes a
    negative x scale.
    """
    n = len(nodes)
    t = np.zeros((n, 3))
    r = np.tile(quat.IDENTITY, (n, 1))
    s = np.ones((n, 3))
    for i, node in enumerate(nodes):
        place = f"nodes[{i}]"
        if "matrix" in node:
            m = _vector(file, f"{place}.matrix", node["matrix"], 16, None).reshape(4, 4).T  # column-major
            t[i] = m[:3, 3]
            basis = m[:3, :3]
            scale = np.linalg.norm(basis, axis=0)
            if np.any(scale < 1e-12):
                raise InputError(file, f"{place}.matrix", "is singular (a zero scale)")
            if np.linalg.det(basis) < 0:
                scale[0] = -scale[0]
            r[i] = quat.from_matrix(basis / scale)
            s[i] = scale
            continue
        t[i] = _vector(file, f"{place}.translation", node.get("translation"), 3, (0.0, 0.0, 0.0))
        q = _vector(file, f"{place}.rotation", node.get("rotation"), 4, quat.IDENTITY)
        norm = np.linalg.norm(q)
        if norm < 1e-6:
            raise InputError(file, f"{place}.rotation", "is a zero quaternion")
        r[i] = q / norm
        s[i] = _vector(file, f"{place}.scale", node.get("scale"), 3, (1.0, 1.0, 1.0))
    return t, r, s


def trs_matrices(t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """4x4 matrices T · R · S (column vectors) for (...,3), (...,4), (...,3) inputs."""
    shape = t.shape[:-1]
    m = np.zeros(shape + (4, 4))
    m[..., :3, :3] = quat.to_matrix(r) * s[..., None, :]
    m[..., :3, 3] = t
    m[..., 3, 3] = 1.0
    return m


def global_matrices(graph: NodeGraph, local: np.ndarray) -> np.ndarray:
    """World matrices (N,4,4) of every node from local matrices (N,4,4)."""
    world = np.array(local)
    for i in graph.order:
        p = graph.parent[i]
        if p >= 0:
            world[i] = world[p] @ local[i]
    return world


# -- similarity transforms (t, q, s): x -> t + s * rotate(q, x), vectorized over leading axes ------
def compose(a: tuple, b: tuple) -> tuple:
    """``a ∘ b`` (apply ``b`` first) for similarities ``(t (...,3), q (...,4), s (...))``."""
    ta, qa, sa = a
    tb, qb, sb = b
    sa = np.asarray(sa, dtype=np.float64)
    return ta + sa[..., None] * quat.rotate(qa, tb), quat.multiply(qa, qb), sa * np.asarray(sb, dtype=np.float64)


def invert(a: tuple) -> tuple:
    """The inverse similarity of ``(t, q, s)``."""
    t, q, s = a
    qi = quat.conjugate(q)
    si = 1.0 / np.asarray(s, dtype=np.float64)
    return -si[..., None] * quat.rotate(qi, t), qi, si


IDENTITY_SIM = (np.zeros(3), quat.IDENTITY, np.float64(1.0))
