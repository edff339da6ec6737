"""Skinned meshes in the core frame, and linear blend skinning vectorized over frames and vertices.

A :class:`SkinnedMesh` is one drawable triangle surface (one material) bound to a skeleton.
Conventions, stated once:

- Positions are metres in the core frame (right-handed, +Y up, +Z the character's forward, +X its
  left), in the **bind pose**: the pose the mesh was modelled in.
- Triangles list vertex indices counter-clockwise when seen from the surface's front (glTF's rule).
- A vertex follows bone ``b`` (``bind_joints[b]`` is a skeleton joint index) through the matrix
  ``G @ inverse_bind[b]``, with ``G`` the joint's global rigid transform from forward kinematics
  (its global rotation and position, see :func:`infuse.kinematics.forward_kinematics`). So
  ``inverse_bind`` takes a bind-pose point into the joint's frame, and any unit scale of the file is
  already in it. Skinning blends those matrices with each vertex's weights.
- Colours are linear RGBA in 0..1 (glTF's base colour factors are linear; sRGB textures are
  converted when sampled).
- Morph targets are position offsets (metres, bind pose) added before skinning, weighted 0..1.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from . import quaternions as quat


def _array(value, dtype, shape: tuple, what: str, name: str) -> np.ndarray:
    out = np.array(value, dtype=dtype, copy=True)
    if out.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, out.shape)):
        raise ValueError(f"mesh {name!r}: {what} has shape {out.shape}, expected {shape}")
    if out.dtype.kind == "f" and not np.all(np.isfinite(out)):
        raise ValueError(f"mesh {name!r}: {what} holds NaN or infinity")
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class SkinnedMesh:
    """One triangle surface bound to skeleton joints (see the module doc for the conventions).

    - ``positions``: (V, 3) float32, metres, bind pose; ``normals``: (V, 3) float32 unit vectors.
    - ``triangles``: (T, 3) int32 vertex indices, counter-clockwise seen from the front.
    - ``joints``: (V, K) int32 indices into ``bind_joints``; ``weights``: (V, K) float32, rows sum to 1.
    - ``bind_joints``: (B,) int64 skeleton joint index of each bone; ``inverse_bind``: (B, 4, 4) float64.
    - ``base_color``: (4,) linear RGBA of the material; ``colors``: (V, 4) linear RGBA per vertex
      (the base colour texture sampled at the vertex, times the base colour) or ``None``.
    - ``double_sided``: the material shows both faces.
    - ``morph_names``: M target names; ``morph_positions``: (M, V, 3) float32 offsets, metres.
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    bind_joints: np.ndarray
    inverse_bind: np.ndarray
    base_color: np.ndarray = field(default_factory=lambda: np.array([0.8, 0.8, 0.8, 1.0]))
    colors: np.ndarray | None = None
    double_sided: bool = False
    morph_names: tuple[str, ...] = ()
    morph_positions: np.ndarray | None = None

    def __post_init__(self):
        name = self.name
        put = lambda key, value: object.__setattr__(self, key, value)  # noqa: E731 - frozen dataclass
        put("positions", _array(self.positions, np.float32, (None, 3), "positions", name))
        v = len(self.positions)
        put("normals", _array(self.normals, np.float32, (v, 3), "normals", name))
        put("triangles", _array(self.triangles, np.int32, (None, 3), "triangles", name))
        if self.triangles.size and (self.triangles.min() < 0 or self.triangles.max() >= v):
            raise ValueError(f"mesh {name!r}: a triangle names a vertex out of range (there are {v})")
        put("bind_joints", _array(self.bind_joints, np.int64, (None,), "bind_joints", name))
        b = len(self.bind_joints)
        put("inverse_bind", _array(self.inverse_bind, np.float64, (b, 4, 4), "inverse_bind", name))
        put("joints", _array(self.joints, np.int32, (v, None), "joints", name))
        put("weights", _array(self.weights, np.float32, self.joints.shape, "weights", name))
        if self.joints.size and (self.joints.min() < 0 or self.joints.max() >= b):
            raise ValueError(f"mesh {name!r}: a vertex names a bone out of range (there are {b})")
        put("base_color", _array(self.base_color, np.float32, (4,), "base_color", name))
        if self.colors is not None:
            put("colors", _array(self.colors, np.float32, (v, 4), "colors", name))
        put("morph_names", tuple(str(n) for n in self.morph_names))
        if self.morph_positions is not None:
            shape = (len(self.morph_names), v, 3)
            put("morph_positions", _array(self.morph_positions, np.float32, shape, "morph_positions", name))
        elif self.morph_names:
            raise ValueError(f"mesh {name!r}: morph_names without morph_positions")

    @property
    def num_vertices(self) -> int:
        return len(self.positions)

    @property
    def num_triangles(self) -> int:
        return len(self.triangles)

    def vertex_colors(self) -> np.ndarray:
        """(V, 4) linear RGBA of every vertex: ``colors``, else the base colour."""
        if self.colors is not None:
            return self.colors
        return np.broadcast_to(self.base_color, (self.num_vertices, 4))

    def skin(self, global_rotations: np.ndarray, global_positions: np.ndarray,
             morph_weights: np.ndarray | None = None, vertices: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Posed positions and normals, (F, V, 3) float32 each, for every frame at once.

        ``global_rotations`` (F, J, 4) and ``global_positions`` (F, J, 3) are the skeleton's FK
        results (core frame, metres); ``morph_weights`` (F, M) weights of ``morph_names``;
        ``vertices``: indices of the vertices to pose (default all), e.g. a sample for framing.
        """
        matrices = skinning_matrices(self, global_rotations, global_positions)  # (F, B, 3, 4)
        frames = len(matrices)
        sel = slice(None) if vertices is None else np.asarray(vertices)
        joints, weights = self.joints[sel], self.weights[sel]
        flat = matrices.reshape(frames, -1, 12)
        blend = np.zeros((frames, len(joints), 12), dtype=np.float32)
        for k in range(joints.shape[1]):  # a handful of influences per vertex, not a loop over vertices
            w = weights[:, k]
            if np.any(w):
                blend += w[:, None] * flat[:, joints[:, k]]
        affine = blend.reshape(frames, -1, 3, 4)
        rest = self.positions[sel]
        if morph_weights is not None and self.morph_positions is not None and np.any(morph_weights):
            mw = np.asarray(morph_weights, dtype=np.float32).reshape(frames, -1)
            rest = rest + np.einsum("fm,mvc->fvc", mw, self.morph_positions[:, sel], optimize=True)
            positions = np.einsum("fvij,fvj->fvi", affine[..., :3], rest) + affine[..., 3]
        else:
            positions = np.einsum("fvij,vj->fvi", affine[..., :3], rest) + affine[..., 3]
        normals = np.einsum("fvij,vj->fvi", affine[..., :3], self.normals[sel])
        normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-12)
        return positions, normals


def area_normals(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(P, 3) unnormalized normals of ``positions`` (P, 3): the sum of the faces around each point, each
    weighted by its area (``triangles`` (T, 3) index ``positions``, counter-clockwise from the front)."""
    positions = np.asarray(positions, dtype=np.float64)
    p = positions[triangles]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    corners = np.asarray(triangles).reshape(-1)
    repeated = np.repeat(face, 3, axis=0)
    return np.stack([np.bincount(corners, repeated[:, c], minlength=len(positions)) for c in range(3)], axis=1)


def rigid_matrices(global_rotations: np.ndarray, global_positions: np.ndarray) -> np.ndarray:
    """(..., 4, 4) matrices of rigid transforms from rotations (..., 4) and positions (..., 3)."""
    rot = np.asarray(global_rotations, dtype=np.float64)
    out = np.zeros(rot.shape[:-1] + (4, 4))
    out[..., :3, :3] = quat.to_matrix(rot)
    out[..., :3, 3] = global_positions
    out[..., 3, 3] = 1.0
    return out


def skinning_matrices(mesh: SkinnedMesh, global_rotations: np.ndarray, global_positions: np.ndarray) -> np.ndarray:
    """(F, B, 3, 4) float32: bind pose -> posed, per bone of ``mesh`` and frame (``G @ inverse_bind``)."""
    rot = np.asarray(global_rotations, dtype=np.float64)
    pos = np.asarray(global_positions, dtype=np.float64)
    if rot.ndim == 2:
        rot, pos = rot[None], pos[None]
    g = rigid_matrices(rot[:, mesh.bind_joints], pos[:, mesh.bind_joints])
    return np.matmul(g, mesh.inverse_bind)[..., :3, :].astype(np.float32)



def merge(meshes: Sequence[SkinnedMesh], name: str = "merged", morph_names: Sequence[str] | None = None) -> SkinnedMesh:
    """One surface holding all of ``meshes`` (bound to the same skeleton), so they are skinned in one pass.

    Colours become per vertex; bones that two surfaces share (same joint, same inverse bind matrix)
    are stored once; ``double_sided`` is True when any surface is. ``morph_names``: the targets to
    keep (default: every target of any surface; a surface without one does not move with it).
    """
    meshes = list(meshes)
    if not meshes:
        raise ValueError("merge needs at least one mesh")
    offsets = np.cumsum([0] + [m.num_vertices for m in meshes])
    keys: dict[tuple, int] = {}
    bone_joints: list[int] = []
    bone_matrices: list[np.ndarray] = []
    joint_maps: list[np.ndarray] = []
    for m in meshes:
        table = np.empty(len(m.bind_joints), dtype=np.int32)
        for b, (j, ib) in enumerate(zip(m.bind_joints, m.inverse_bind)):
            key = (int(j), ib.tobytes())
            if key not in keys:
                keys[key] = len(bone_joints)
                bone_joints.append(int(j))
                bone_matrices.append(ib)
            table[b] = keys[key]
        joint_maps.append(table)
    k = max(m.joints.shape[1] for m in meshes)
    joints = np.zeros((int(offsets[-1]), k), dtype=np.int32)
    weights = np.zeros((int(offsets[-1]), k), dtype=np.float32)
    for m, table, a in zip(meshes, joint_maps, offsets):
        joints[a:a + m.num_vertices, :m.joints.shape[1]] = table[m.joints]
        weights[a:a + m.num_vertices, :m.joints.shape[1]] = m.weights
    if morph_names is None:
        morph_names = list(dict.fromkeys(n for m in meshes for n in m.morph_names))
    morph_names = tuple(morph_names)
    morph_positions = None
    if morph_names:
        morph_positions = np.zeros((len(morph_names), int(offsets[-1]), 3), dtype=np.float32)
        row = {n: i for i, n in enumerate(morph_names)}
        for m, a in zip(meshes, offsets):
            for i, n in enumerate(m.morph_names):
                if n in row and m.morph_positions is not None:
                    morph_positions[row[n], a:a + m.num_vertices] = m.morph_positions[i]
    return SkinnedMesh(
        name, np.concatenate([m.positions for m in meshes]), np.concatenate([m.normals for m in meshes]),
        np.concatenate([m.triangles + a for m, a in zip(meshes, offsets)]), joints, weights,
        np.array(bone_joints, dtype=np.int64), np.array(bone_matrices).reshape(-1, 4, 4),
        base_color=np.ones(4), colors=np.concatenate([m.vertex_colors() for m in meshes]),
        double_sided=any(m.double_sided for m in meshes), morph_names=morph_names, morph_positions=morph_positions)


def sole_points(meshes: Sequence[SkinnedMesh], global_rotations: np.ndarray, global_positions: np.ndarray,
                joints: Sequence[int], frame_joint: int, forward: np.ndarray) -> np.ndarray | None:
    """(2, 3) the heel and the tip of the surface carried by ``joints`` (a foot: its ankle and what
    hangs below), as offsets in the frame of ``frame_joint`` (metres, like an end site's); ``None``
    when no vertex of ``meshes`` is carried by them.

    A vertex is carried by ``joints`` when they hold at least half of its weight. The surface is
    posed by the skeleton's global ``global_rotations`` (J, 4) and ``global_positions`` (J, 3), a
    standing pose, and boxed along ``forward`` (3,), the foot's horizontal heading: the sole is the
    lowest vertex, the tip the box's front at the sole's height, the heel its back, both midway
    across the foot.
    """
    rot = np.asarray(global_rotations, dtype=np.float64)
    pos = np.asarray(global_positions, dtype=np.float64)
    carrying = np.zeros(len(rot), dtype=bool)
    carrying[list(joints)] = True
    posed = []
    for mesh in meshes:
        share = np.sum(np.where(carrying[mesh.bind_joints[mesh.joints]], mesh.weights, 0.0), axis=1)
        vertices = np.nonzero(share >= 0.5)[0]
        if len(vertices):
            posed.append(mesh.skin(rot[None], pos[None], vertices=vertices)[0][0].astype(np.float64))
    if not posed:
        return None
    points = np.concatenate(posed)
    ahead = np.array([forward[0], 0.0, forward[2]], dtype=np.float64)
    ahead /= max(float(np.linalg.norm(ahead)), 1e-12)
    across = np.cross(np.array([0.0, 1.0, 0.0]), ahead)
    along, side = points @ ahead, points @ across
    middle = 0.5 * (side.min() + side.max()) * across
    sole = points[:, 1].min() * np.array([0.0, 1.0, 0.0])
    ends = np.stack([along.min() * ahead, along.max() * ahead]) + middle + sole
    return quat.rotate(quat.conjugate(rot[frame_joint])[None], ends - pos[frame_joint])
