"""COLLADA ``<mesh>`` geometry as triangles of indexed corners, vectorized over every polygon.

A primitive (``<triangles>``, ``<polylist>``, ``<polygons>``, ``<trifans>``, ``<tristrips>``) lists
for each polygon corner one index per input, at the input's ``offset``. Polygons and fans are split
into fans ``(c0, ck, ck+1)``, strips into alternately turned triangles, so every triangle keeps
the polygon's winding (counter-clockwise seen from the front, as in the core). ``<ph>`` polygons
keep their outline; their holes are left open. Lines are not surfaces and are left out.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .document import Document

#: Primitive elements that hold surfaces.
SURFACES = ("triangles", "polylist", "polygons", "trifans", "tristrips")


@dataclass
class Input:
    """One indexed input of a primitive: its ``<source>`` URL, the element naming it (for messages),
    its set number, and the source index of each corner of each triangle, (T, 3)."""

    url: str
    element: object
    set: int | None
    indices: np.ndarray


@dataclass
class Primitive:
    """The triangles of one primitive: the material symbol it names and its inputs by semantic.

    ``positions`` (T, 3) indexes the geometry's positions (the ``VERTEX`` input); ``normals`` is the
    primitive's own ``NORMAL`` input, if any; ``texcoords`` its ``TEXCOORD`` inputs in file order.
    """

    material: str | None
    positions: np.ndarray
    normals: Input | None
    texcoords: list[Input]


@dataclass
class Geometry:
    """A ``<geometry>``'s ``<mesh>``: positions (P, 3) in file units, per-position normals when the
    ``<vertices>`` element has them (P, 3), and the surface primitives."""

    name: str
    positions: np.ndarray
    normals: np.ndarray | None
    primitives: list[Primitive]


def read_geometry(doc: Document, element) -> Geometry | None:
    """The mesh of ``<geometry>`` ``element``; ``None`` when it holds no ``<mesh>`` (splines, B-reps,
    convex hulls). Malformed arrays raise :class:`~infuse.errors.InputError`."""
    mesh = element.find("mesh")
    if mesh is None:
        return None
    vertices = mesh.find("vertices")
    if vertices is None:
        raise doc.error(mesh, "mesh has no <vertices>")
    semantic = {i.get("semantic"): i for i in vertices.findall("input")}
    if "POSITION" not in semantic:
        raise doc.error(vertices, "<vertices> has no POSITION input")
    positions = _vectors(doc, semantic["POSITION"], 3)
    normals = None
    if "NORMAL" in semantic:
        normals = _vectors(doc, semantic["NORMAL"], 3)
        if len(normals) != len(positions):
            raise doc.error(semantic["NORMAL"], f"{len(normals)} normals for {len(positions)} positions")
    primitives = [_primitive(doc, el, vertices.get("id"), len(positions)) for el in mesh if el.tag in SURFACES]
    name = element.get("name") or element.get("id") or "geometry"
    return Geometry(name, positions, normals, [p for p in primitives if p is not None])


def _vectors(doc: Document, input_element, width: int) -> np.ndarray:
    values = doc.source(input_element.get("source"), input_element)
    if values.shape[1] < width:
        raise doc.error(input_element, f"source {input_element.get('source')!r} has {values.shape[1]} values per item, expected {width}")
    return values[:, :width]


def _primitive(doc: Document, el, vertices_id: str | None, num_positions: int) -> Primitive | None:
    inputs = el.findall("input")
    if not inputs:
        raise doc.error(el, "primitive has no inputs")
    offsets = []
    for i in inputs:
        raw = i.get("offset", "0")
        if not raw.isdigit():
            raise doc.error(i, f"offset={raw!r} is not a non-negative integer")
        offsets.append(int(raw))
    stride = max(offsets) + 1
    corners, triangles = _corners(doc, el, stride)
    found: dict[str, Input] = {}
    texcoords: list[Input] = []
    for i, offset in zip(inputs, offsets):
        name = i.get("semantic")
        if name not in ("VERTEX", "NORMAL", "TEXCOORD"):
            continue
        raw_set = i.get("set")
        item = Input(i.get("source") or "", i, int(raw_set) if raw_set and raw_set.isdigit() else None,
                     corners[:, offset][triangles])
        if name == "TEXCOORD":
            texcoords.append(item)
        else:
            found.setdefault(name, item)
    if "VERTEX" not in found:
        raise doc.error(el, "primitive has no VERTEX input")
    if vertices_id is not None and found["VERTEX"].url != f"#{vertices_id}":
        raise doc.error(found["VERTEX"].element, f"VERTEX input points to {found['VERTEX'].url!r}, not this mesh's <vertices>")
    positions = found["VERTEX"].indices
    if positions.size and (positions.min() < 0 or positions.max() >= num_positions):
        raise doc.error(el, f"a vertex index is out of range (there are {num_positions} positions)")
    return Primitive(el.get("material"), positions, found.get("NORMAL"), texcoords)


def _corners(doc: Document, el, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """Corner index tuples (C, stride) and the corners of each triangle (T, 3)."""
    if el.tag == "triangles":
        p = _indices(doc, el.findall("p"))
        sizes = None
    elif el.tag == "polylist":
        vcount = el.find("vcount")
        sizes = doc.ints(vcount) if vcount is not None else np.zeros(0, dtype=np.int64)
        p = _indices(doc, el.findall("p"))
        if np.any(sizes < 0):
            raise doc.error(vcount, "a polygon has a negative corner count")
    else:  # one <p> per polygon, fan or strip; <ph> holds its outline in <p> and holes in <h>
        parts = el.findall("p") + [ph.find("p") for ph in el.findall("ph") if ph.find("p") is not None]
        lists = [doc.ints(p) for p in parts]
        p = np.concatenate(lists) if lists else np.zeros(0, dtype=np.int64)
        sizes = np.array([len(x) // stride for x in lists], dtype=np.int64)
        if any(len(x) % stride for x in lists):
            raise doc.error(el, f"a <p> holds a number of indices that is not a multiple of the {stride} inputs")
    if p.size % stride:
        raise doc.error(el, f"<p> holds {p.size} indices, not a multiple of the {stride} inputs")
    corners = p.reshape(-1, stride)
    if sizes is None:
        return corners, np.arange(len(corners) // 3 * 3).reshape(-1, 3)
    if int(sizes.sum()) != len(corners):
        raise doc.error(el, f"the polygons have {int(sizes.sum())} corners, <p> holds {len(corners)}")
    return corners, (strips if el.tag == "tristrips" else fans)(sizes)


def _indices(doc: Document, parts: list) -> np.ndarray:
    lists = [doc.ints(p) for p in parts]
    return np.concatenate(lists) if lists else np.zeros(0, dtype=np.int64)


def fans(sizes: np.ndarray) -> np.ndarray:
    """(T, 3) corner indices splitting consecutive polygons of ``sizes`` corners into fans."""
    starts = np.cumsum(sizes) - sizes
    count = np.maximum(sizes - 2, 0)
    poly = np.repeat(np.arange(len(sizes)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count) + 1
    first = starts[poly]
    return np.stack([first, first + k, first + k + 1], axis=1)


def strips(sizes: np.ndarray) -> np.ndarray:
    """(T, 3) corner indices of consecutive triangle strips of ``sizes`` corners (every other one turned)."""
    starts = np.cumsum(sizes) - sizes
    count = np.maximum(sizes - 2, 0)
    strip = np.repeat(np.arange(len(sizes)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    a = starts[strip] + k
    odd = k % 2 == 1
    return np.stack([a, np.where(odd, a + 2, a + 1), np.where(odd, a + 1, a + 2)], axis=1)
