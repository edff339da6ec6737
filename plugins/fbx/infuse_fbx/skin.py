"""FBX skins: the clusters binding a mesh geometry's control points to bone models.

A ``Deformer`` of class ``Skin`` hangs under the geometry; under it, each ``SubDeformer`` of class
``Cluster`` is linked to one bone model (connection ``OO`` bone -> cluster) and holds ``Indexes``
(control points), ``Weights``, ``TransformLink`` (the bone's global matrix at bind time) and
``Transform`` (the geometry's bind matrix in the bone's frame: ``TransformLink⁻¹ · M``, with ``M``
the mesh model's global matrix at bind time, as Blender's importer and the FBX SDK read it).
Matrices are 16 doubles, column by column. In the file, a point ``x`` of the geometry (after the
model's geometric transform) follows its bone ``j`` as ``W_j · Transform · x``, ``W_j`` the
bone's global matrix.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .document import Document, FbxObject
from .geometry import GeometryError

#: Influences kept per control point (the largest, renormalized), as in glTF.
MAX_INFLUENCES = 4


@dataclass
class Cluster:
    """One bone's hold on the control points: ``model`` (index into the model list), ``points`` (n,),
    ``weights`` (n,), ``transform`` (geometry -> bone at bind time) and ``link`` (the bone's bind matrix)."""

    model: int
    points: np.ndarray
    weights: np.ndarray
    transform: np.ndarray
    link: np.ndarray

    @property
    def mesh_bind(self) -> np.ndarray:
        """The mesh's global matrix at bind time, as this cluster records it."""
        return self.link @ self.transform


def matrix(doc: Document, obj: FbxObject, name: str) -> np.ndarray | None:
    """A cluster's 4x4 matrix record ``name`` (stored column by column), or ``None`` when absent."""
    rec = obj.node.find(name)
    if rec is None or not rec.props:
        return None
    value = rec.props[0]
    if not isinstance(value, np.ndarray) or value.size != 16 or value.dtype.kind not in "iuf":
        raise GeometryError(f"cluster {obj.name!r}: {name} is not 16 numbers")
    out = value.astype(np.float64).reshape(4, 4).T
    if not np.all(np.isfinite(out)) or abs(np.linalg.det(out[:3, :3])) < 1e-18:
        raise GeometryError(f"cluster {obj.name!r}: {name} is not an invertible finite matrix")
    return out


def clusters(doc: Document, skin: FbxObject, model_index: dict[int, int], world: np.ndarray,
             mesh_world: np.ndarray, num_points: int) -> list[Cluster]:
    """The clusters of ``skin`` that move at least one control point.

    ``model_index``: model id -> index into ``world`` (N, 4, 4), the models' rest global matrices.
    A cluster without its matrices binds the mesh where it stands at rest (``mesh_world``).
    """
    out = []
    for obj, _ in doc.children_of(skin.id, "Deformer"):
        if obj.subclass != "Cluster":
            continue
        bones = [m for m, _ in doc.children_of(obj.id, "Model") if m.id in model_index]
        index_rec, weight_rec = obj.node.find("Indexes"), obj.node.find("Weights")
        if not bones or index_rec is None or weight_rec is None:
            continue  # binds nothing (exporters write a cluster for every bone)
        points, weights = index_rec.props[0] if index_rec.props else None, weight_rec.props[0] if weight_rec.props else None
        if not isinstance(points, np.ndarray) or not isinstance(weights, np.ndarray) or len(points) != len(weights) \
                or points.dtype.kind not in "iu" or weights.dtype.kind not in "iuf":
            raise GeometryError(f"cluster {obj.name!r}: Indexes and Weights are not arrays of one length")
        points, weights = points.astype(np.int64), weights.astype(np.float64)
        if len(points) and (points.min() < 0 or points.max() >= num_points):
            raise GeometryError(f"cluster {obj.name!r} names control point {int(points.max())} of {num_points}")
        if not np.all(np.isfinite(weights)):
            raise GeometryError(f"cluster {obj.name!r}: a weight is not finite")
        model = model_index[bones[0].id]
        link = matrix(doc, obj, "TransformLink")
        transform = matrix(doc, obj, "Transform")
        if link is None:
            link = world[model]
        if transform is None:
            transform = np.linalg.inv(link) @ mesh_world
        keep = weights > 0
        if np.any(keep):
            out.append(Cluster(model, points[keep], weights[keep], transform, link))
    return out


def influences(clusters: list[Cluster], num_points: int) -> tuple[np.ndarray, np.ndarray]:
    """(V, K) cluster indices and weights of every control point: its :data:`MAX_INFLUENCES` largest
    weights, rows normalized to sum 1; a point no cluster moves has all weights 0."""
    if not clusters:
        return np.zeros((num_points, 1), dtype=np.int64), np.zeros((num_points, 1))
    points = np.concatenate([c.points for c in clusters])
    weights = np.concatenate([c.weights for c in clusters])
    owner = np.repeat(np.arange(len(clusters)), [len(c.points) for c in clusters])
    order = np.lexsort((-weights, points))  # by point, largest weight first
    points, weights, owner = points[order], weights[order], owner[order]
    rank = np.arange(len(points)) - np.searchsorted(points, points, side="left")
    k = int(min(MAX_INFLUENCES, rank.max() + 1))
    keep = rank < k
    joints = np.zeros((num_points, k), dtype=np.int64)
    out = np.zeros((num_points, k))
    joints[points[keep], rank[keep]] = owner[keep]
    out[points[keep], rank[keep]] = weights[keep]
    total = out.sum(axis=1, keepdims=True)
    return joints, np.where(total > 0, out / np.where(total > 0, total, 1.0), 0.0)
