"""FBX mesh geometry: control points, polygons cut into triangle fans, and layer elements.

A ``Geometry`` of class ``Mesh`` holds ``Vertices`` (control points, x y z flattened) and
``PolygonVertexIndex``: control point indices, the last of each polygon stored bitwise negated
(``-1 - i``). Each slot of that list is a *polygon vertex*. Per-vertex data live in
``LayerElement*`` records: a ``MappingInformationType`` (``ByPolygonVertex``, ``ByVertice`` /
``ByControlPoint``, ``ByPolygon``, ``AllSame``) says what the values attach to, and a
``ReferenceInformationType`` (``Direct``, or ``IndexToDirect`` with an index array) how they are
looked up. Polygons wind counter-clockwise seen from the front, as glTF's triangles do.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse.mesh import area_normals

from .binary import Node


class GeometryError(ValueError):
    """A geometry that cannot be used; the message says why (it becomes a reader warning)."""


@dataclass
class Polygons:
    """The polygons of one mesh geometry.

    - ``points``: (V, 3) float64 control points, file units, geometry space.
    - ``corner_points``: (N,) control point of each polygon vertex; ``corner_polygon``: (N,) its polygon.
    - ``triangles``: (T, 3) polygon-vertex indices, fans from each polygon's first corner.
    """

    points: np.ndarray
    corner_points: np.ndarray
    corner_polygon: np.ndarray
    triangles: np.ndarray

    @property
    def num_polygons(self) -> int:
        return int(self.corner_polygon[-1]) + 1 if len(self.corner_polygon) else 0


def array(node: Node, name: str, required: bool = True) -> np.ndarray | None:
    """The numeric array child ``name`` of ``node`` (``None`` when absent and not required)."""
    rec = node.find(name)
    if rec is None or not rec.props:
        if required:
            raise GeometryError(f"has no {name}")
        return None
    value = rec.props[0]
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "iuf":
        raise GeometryError(f"{name} is not a numeric array")
    return value


def polygons(node: Node) -> Polygons:
    """The control points and triangulated polygons of a ``Geometry`` record."""
    raw = array(node, "Vertices").astype(np.float64)
    if raw.size % 3 or not np.all(np.isfinite(raw)):
        raise GeometryError(f"Vertices holds {raw.size} numbers, not finite x y z triples")
    points = raw.reshape(-1, 3)
    index = array(node, "PolygonVertexIndex")
    if index.dtype.kind == "f":
        raise GeometryError("PolygonVertexIndex is not an integer array")
    if not len(index):
        raise GeometryError("has no polygons")
    index = index.astype(np.int64)
    ends = index < 0
    if not ends[-1]:
        raise GeometryError("PolygonVertexIndex does not end a polygon (its last index is not negative)")
    corner_points = np.where(ends, ~index, index)
    if corner_points.max() >= len(points):
        raise GeometryError(f"PolygonVertexIndex names control point {int(corner_points.max())} of {len(points)}")
    corner_polygon = np.cumsum(ends) - ends
    starts = np.concatenate(([0], np.nonzero(ends)[0][:-1] + 1))
    first = starts[corner_polygon]
    # Corner i (not its polygon's first or last) makes the fan triangle (first, i, i + 1).
    middle = np.nonzero((np.arange(len(index)) > first) & ~ends)[0]
    triangles = np.stack([first[middle], middle, middle + 1], axis=1)
    return Polygons(points, corner_points, corner_polygon, triangles)


def layer(node: Node, name: str) -> Node | None:
    """The first layer element ``name`` (``LayerElementNormal``...) of a geometry: the one layer 0 uses."""
    elements = node.find_all(name)
    if not elements:
        return None
    return min(elements, key=lambda e: e.props[0] if e.props and isinstance(e.props[0], int) else 0)


def _text(node: Node, name: str, default: str) -> str:
    rec = node.find(name)
    return str(rec.props[0]) if rec is not None and rec.props else default


def corner_values(element: Node, values_name: str, index_name: str, width: int, polys: Polygons) -> np.ndarray:
    """(N, width) values of a layer element at every polygon vertex (see the module doc for the mappings)."""
    values = array(element, values_name).astype(np.float64)
    if values.size % width or not np.all(np.isfinite(values)):
        raise GeometryError(f"{element.name} {values_name} is not finite groups of {width}")
    values = values.reshape(-1, width)
    mapping = _text(element, "MappingInformationType", "ByPolygonVertex")
    reference = _text(element, "ReferenceInformationType", "Direct")
    n = len(polys.corner_points)
    if mapping == "ByPolygonVertex":
        slot = np.arange(n)
    elif mapping in ("ByVertice", "ByVertex", "ByControlPoint"):
        slot = polys.corner_points
    elif mapping == "ByPolygon":
        slot = polys.corner_polygon
    elif mapping == "AllSame":
        slot = np.zeros(n, dtype=np.int64)
    else:
        raise GeometryError(f"{element.name} maps {mapping}, which infuse does not read")
    if reference in ("IndexToDirect", "Index"):
        index = array(element, index_name).astype(np.int64)
        if len(index) <= slot.max(initial=-1):
            raise GeometryError(f"{element.name} {index_name} holds {len(index)} indices, too few for {mapping}")
        slot = index[slot]
    elif reference != "Direct":
        raise GeometryError(f"{element.name} references {reference}, which infuse does not read")
    if slot.size and (slot.min() < 0 or slot.max() >= len(values)):
        raise GeometryError(f"{element.name} names value {int(slot.max())} of {len(values)}")
    return values[slot]


def polygon_materials(node: Node, polys: Polygons) -> np.ndarray:
    """(P,) material slot of each polygon (0 when the geometry has no material layer)."""
    element = layer(node, "LayerElementMaterial")
    if element is None:
        return np.zeros(polys.num_polygons, dtype=np.int64)
    index = array(element, "Materials").astype(np.int64)
    mapping = _text(element, "MappingInformationType", "AllSame")
    if mapping == "AllSame" or len(index) == 1:
        if not len(index):
            raise GeometryError("LayerElementMaterial holds no material index")
        return np.full(polys.num_polygons, index[0])
    if mapping != "ByPolygon":
        raise GeometryError(f"LayerElementMaterial maps {mapping}, which infuse does not read")
    if len(index) < polys.num_polygons:
        raise GeometryError(f"LayerElementMaterial holds {len(index)} indices for {polys.num_polygons} polygons")
    return index[: polys.num_polygons]


def smooth_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(V, 3) unit area-weighted normals of the faces around each point (``triangles`` index ``points``)."""
    out = area_normals(points, triangles)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(length > 1e-30, out / np.maximum(length, 1e-30), [0.0, 1.0, 0.0])
