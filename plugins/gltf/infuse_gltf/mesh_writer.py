"""Core :class:`~infuse.mesh.SkinnedMesh` surfaces as new glTF meshes, skins and materials.

Used by the writer for a document it builds from the skeleton (an asset not read from glTF). The
joint nodes there hold the skeleton's rest pose in the core frame (metres, +Y up, +Z forward) with
no node above them but an identity one, so a joint's world matrix is the core's rigid rest
transform ``G`` and glTF's skinning ``W_j · IBM_j`` is the core's ``G @ inverse_bind[b]``: the
inverse bind matrices are the mesh's ``inverse_bind`` as they are (column-major in the buffer), and
the positions its bind-pose positions. Each surface becomes:

- one mesh with one triangle primitive: ``POSITION`` (with min/max), ``NORMAL`` (unit length; a
  zero normal is written as +Y), ``indices`` (``UNSIGNED_SHORT``, ``UNSIGNED_INT`` above 65535
  vertices);
- ``JOINTS_n``/``WEIGHTS_n``, four influences per set, as many sets as a vertex has non-zero
  influences (strongest first): joints ``UNSIGNED_BYTE`` (``UNSIGNED_SHORT`` above 256 bones),
  weights float summing to 1; a bone named twice for one vertex is named once with the summed
  weight, a zero weight names bone 0 (glTF's rules);
- a material: ``pbrMetallicRoughness.baseColorFactor`` = ``base_color`` (not metallic),
  ``doubleSided``; with per-vertex ``colors``, ``COLOR_0`` = ``colors / base_color`` so that a
  reader multiplying the two gets ``colors`` back (a white factor and ``COLOR_0`` = ``colors`` when
  the colours are not within the base colour);
- morph ``targets`` (``POSITION`` offsets with min/max) named in ``mesh.extras.targetNames``;
- one root node (no transform, as glTF asks of skinned mesh nodes) naming the mesh and a skin
  whose ``joints`` are the nodes of ``bind_joints``. Surfaces with the same bones share a skin.

A surface without triangles draws nothing and is left out.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from infuse.errors import UsageError
from infuse.mesh import SkinnedMesh

FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
#: Most vertices whose indices fit UNSIGNED_SHORT (65535 itself is the primitive restart value).
SHORT_INDEX_VERTICES = 65535


def add_meshes(doc: dict, bin_writer, meshes: Sequence[SkinnedMesh], joint_nodes: Sequence[int]) -> list[int]:
    """Append ``meshes`` to ``doc`` (data through ``bin_writer``, see the module doc); ``joint_nodes``:
    node index of each skeleton joint. Returns the new mesh nodes, to list as scene roots."""
    joint_nodes = np.asarray(joint_nodes, dtype=np.int64)
    skins: dict[tuple[bytes, bytes], int] = {}
    added = []
    for mesh in meshes:
        if mesh.num_triangles == 0:
            continue
        if mesh.bind_joints.size and mesh.bind_joints.max() >= len(joint_nodes):
            raise UsageError(f"mesh {mesh.name!r} is bound to joints the skeleton does not have "
                             f"(joint {int(mesh.bind_joints.max())} of {len(joint_nodes)}): it belongs to another skeleton")
        key = (mesh.bind_joints.tobytes(), mesh.inverse_bind.tobytes())
        if key not in skins:
            skins[key] = _skin(doc, bin_writer, mesh, joint_nodes)
        nodes = doc.setdefault("nodes", [])
        nodes.append({"name": mesh.name, "mesh": _mesh(doc, bin_writer, mesh), "skin": skins[key]})
        added.append(len(nodes) - 1)
    return added


def _skin(doc: dict, bin_writer, mesh: SkinnedMesh, joint_nodes: np.ndarray) -> int:
    ibm = np.swapaxes(mesh.inverse_bind, 1, 2).reshape(-1, 16).astype(np.float32)  # column-major
    view = bin_writer.view(ibm)
    skin = {"joints": [int(n) for n in joint_nodes[mesh.bind_joints]],
            "inverseBindMatrices": bin_writer.accessor(view, 0, len(ibm), "MAT4")}
    skins = doc.setdefault("skins", [])
    skins.append(skin)
    return len(skins) - 1


def _attribute(bin_writer, data: np.ndarray, kind: str, component: int = FLOAT, bounds: bool = False) -> int:
    view = bin_writer.view(data, target=ARRAY_BUFFER)
    return bin_writer.accessor(view, 0, len(data), kind, data if bounds else None, component=component)


def _mesh(doc: dict, bin_writer, mesh: SkinnedMesh) -> int:
    attributes = {"POSITION": _attribute(bin_writer, mesh.positions, "VEC3", bounds=True),
                  "NORMAL": _attribute(bin_writer, unit_normals(mesh.normals), "VEC3")}
    joints, weights = influence_sets(mesh.joints, mesh.weights)
    joint_type = (np.uint8, UNSIGNED_BYTE) if len(mesh.bind_joints) <= 256 else (np.uint16, UNSIGNED_SHORT)
    for k in range(joints.shape[1] // 4):
        cols = slice(4 * k, 4 * k + 4)
        attributes[f"JOINTS_{k}"] = _attribute(bin_writer, joints[:, cols].astype(joint_type[0]), "VEC4", joint_type[1])
        attributes[f"WEIGHTS_{k}"] = _attribute(bin_writer, weights[:, cols], "VEC4")
    factor, vertex_colors = color_factors(mesh)
    if vertex_colors is not None:
        attributes["COLOR_0"] = _attribute(bin_writer, vertex_colors, "VEC4")
    index_type = (np.uint16, UNSIGNED_SHORT) if mesh.num_vertices <= SHORT_INDEX_VERTICES else (np.uint32, UNSIGNED_INT)
    indices = mesh.triangles.reshape(-1).astype(index_type[0])
    view = bin_writer.view(indices, target=ELEMENT_ARRAY_BUFFER)
    primitive = {"attributes": attributes, "indices": bin_writer.accessor(view, 0, len(indices), "SCALAR", component=index_type[1]),
                 "material": _material(doc, mesh, factor), "mode": 4}
    out = {"name": mesh.name, "primitives": [primitive]}
    if mesh.morph_names:
        primitive["targets"] = [{"POSITION": _attribute(bin_writer, offsets, "VEC3", bounds=True)}
                                for offsets in mesh.morph_positions]
        out["extras"] = {"targetNames": list(mesh.morph_names)}
    meshes = doc.setdefault("meshes", [])
    meshes.append(out)
    return len(meshes) - 1


def _material(doc: dict, mesh: SkinnedMesh, factor: np.ndarray) -> int:
    materials = doc.setdefault("materials", [])
    materials.append({"name": mesh.name, "doubleSided": bool(mesh.double_sided),
                      "pbrMetallicRoughness": {"baseColorFactor": [float(c) for c in factor], "metallicFactor": 0.0}})
    return len(materials) - 1


def unit_normals(normals: np.ndarray) -> np.ndarray:
    """(V, 3) float32 unit normals; a (near) zero normal becomes +Y, which glTF accepts."""
    n = np.asarray(normals, dtype=np.float64)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    ok = length[:, 0] > 1e-6
    out = np.where(ok[:, None], n / np.where(ok[:, None], length, 1.0), [0.0, 1.0, 0.0])
    return out.astype(np.float32)


def influence_sets(joints: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bone indices (V, 4n) int64 and float32 weights (V, 4n) as glTF wants them (see the module doc)."""
    j = np.array(joints, dtype=np.int64)
    w = np.maximum(np.asarray(weights, dtype=np.float64), 0.0)
    for a in range(j.shape[1]):  # a handful of columns: pairs of columns, not vertices
        for b in range(a + 1, j.shape[1]):
            same = (j[:, b] == j[:, a]) & (w[:, b] > 0)
            w[same, a] += w[same, b]
            w[same, b] = 0.0
    order = np.argsort(-w, axis=1, kind="stable")
    j, w = np.take_along_axis(j, order, axis=1), np.take_along_axis(w, order, axis=1)
    used = max(int((w > 0).sum(axis=1).max(initial=0)), 1)
    width = -(-used // 4) * 4
    j = np.pad(j[:, :used], ((0, 0), (0, width - used)))
    w = np.pad(w[:, :used], ((0, 0), (0, width - used)))
    total = w.sum(axis=1)
    w[total <= 0, 0] = 1.0  # no weight at all: the vertex follows its first bone
    w /= np.maximum(w.sum(axis=1, keepdims=True), 1e-30)
    j[w <= 0] = 0
    out = w.astype(np.float32)
    # float32 rounding leaves sums a few ulps off 1: the strongest weight takes the rest
    out[:, 0] = (1.0 - out[:, 1:].astype(np.float64).sum(axis=1)).astype(np.float32)
    return j, out


def color_factors(mesh: SkinnedMesh) -> tuple[np.ndarray, np.ndarray | None]:
    """The material's base colour factor (4,) and ``COLOR_0`` (V, 4) float32 (``None`` without
    per-vertex colours), their product being the mesh's colours (see the module doc)."""
    base = mesh.base_color.astype(np.float64)
    if mesh.colors is None:
        return base, None
    colors = np.clip(mesh.colors.astype(np.float64), 0.0, 1.0)
    positive = base > 0
    ratio = np.where(positive, colors / np.where(positive, base, 1.0), 0.0)
    if np.all(ratio <= 1.0 + 1e-6) and np.all(colors[:, ~positive] == 0):
        return base, np.clip(ratio, 0.0, 1.0).astype(np.float32)
    return np.ones(4), colors.astype(np.float32)
