"""Skinned meshes in renders: a figure's surfaces posed at its frames, and how they are lit.

:class:`FigureMesh` holds a figure's :class:`~infuse.mesh.SkinnedMesh` surfaces with the global
joint transforms of every frame (core frame: metres, +Y up, +Z forward) and poses them by linear
blend skinning, many frames at once. :func:`shade` lights the visible surface found by
:func:`~infuse.render.raster.rasterize`: Lambert from a key light, a little light from the camera
and some ambient, on the surfaces' linear colours, encoded to sRGB.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from ..mesh import SkinnedMesh, merge
from .raster import Fragments

#: Vertices posed per frame to frame the camera (spread evenly over the surfaces).
FRAMING_SAMPLES = 1500
AMBIENT, KEY, FILL = 0.32, 0.62, 0.22


class FigureMesh:
    """The surfaces of one figure and its joints' global transforms at each of its frames.

    - ``meshes``: the surfaces (bind pose, core frame), bound to the figure's skeleton; they are
      merged into one (:func:`infuse.mesh.merge`) so a frame is skinned in one pass.
    - ``rotations`` (F, J, 4) and ``positions`` (F, J, 3): global joint rotations and positions,
      e.g. from :func:`infuse.kinematics.motion_fk`.
    - ``morph_weights``: {target name: (F,) weight} played on the surfaces that have that target.
    """

    def __init__(self, meshes: Sequence[SkinnedMesh], rotations: np.ndarray, positions: np.ndarray,
                 morph_weights: Mapping[str, np.ndarray] | None = None):
        meshes = [m for m in meshes if m.num_triangles]
        if not meshes:
            raise ValueError("a figure mesh needs at least one surface with triangles")
        self.rotations = np.asarray(rotations, dtype=np.float64)
        self.positions = np.asarray(positions, dtype=np.float64)
        if self.rotations.ndim != 3 or self.positions.shape != self.rotations.shape[:2] + (3,):
            raise ValueError("figure mesh: rotations must be (F, J, 4) and positions (F, J, 3)")
        joints = self.rotations.shape[1]
        if any(m.bind_joints.max() >= joints for m in meshes):
            raise ValueError(f"figure mesh: a surface is bound to a joint beyond the skeleton's {joints}")
        self.num_frames = len(self.rotations)
        targets = {n for m in meshes for n in m.morph_names}
        morph_weights = morph_weights or {}
        moved = [n for n in morph_weights if n in targets and np.any(np.asarray(morph_weights[n]) != 0)]
        self.mesh = merge(meshes, "figure", moved)
        self.weights = None
        if moved:
            self.weights = np.zeros((self.num_frames, len(moved)), dtype=np.float32)
            for k, name in enumerate(moved):
                track = np.asarray(morph_weights[name], dtype=np.float32).reshape(-1)
                n = min(len(track), self.num_frames)
                self.weights[:n, k] = track[:n]
                self.weights[n:, k] = track[n - 1]  # held after a track that ends early
        self.triangles = self.mesh.triangles.astype(np.int64)
        self.colors = np.ascontiguousarray(self.mesh.vertex_colors()[:, :3])
        total = self.mesh.num_vertices
        self._samples = np.unique(np.linspace(0, total - 1, min(FRAMING_SAMPLES, total)).astype(np.int64))

    @property
    def num_vertices(self) -> int:
        return self.mesh.num_vertices

    def pose(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions and normals (n, V, 3) float32 of every vertex at figure frames ``frames`` (n,)."""
        frames = np.asarray(frames, dtype=np.int64)
        weights = None if self.weights is None else self.weights[frames]
        return self.mesh.skin(self.rotations[frames], self.positions[frames], weights)

    def sample_points(self, frames: np.ndarray) -> np.ndarray:
        """(n, S, 3) a fixed spread of vertices posed at ``frames``: enough to frame the camera."""
        frames = np.asarray(frames, dtype=np.int64)
        weights = None if self.weights is None else self.weights[frames]
        return self.mesh.skin(self.rotations[frames], self.positions[frames], weights, self._samples)[0].astype(np.float64)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Linear 0..1 -> sRGB-encoded 0..1 (the exact piecewise curve)."""
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


#: Linear value quantized to 1/4095 -> sRGB byte: the encoding as one table look-up.
_SRGB_BYTES = np.rint(linear_to_srgb(np.arange(4096) / 4095.0) * 255.0).astype(np.uint8)


def shade(fragments: Fragments, triangles: np.ndarray, normals: np.ndarray, colors: np.ndarray,
          facing: np.ndarray, to_light: np.ndarray, to_camera: np.ndarray) -> np.ndarray:
    """(P, 3) uint8 sRGB colours of the fragments.

    ``normals`` (V, 3) and ``colors`` (V, 3, linear) are interpolated across each triangle;
    ``facing`` (T,) bool says which triangles show their front (a back face is lit as seen from
    behind); ``to_light`` and ``to_camera`` are unit directions (core frame).
    """
    corners = triangles[fragments.triangle].T  # (3, P)
    bary = fragments.barycentric.astype(np.float32, copy=False)
    w0, w1, w2 = bary[:, 0, None], bary[:, 1, None], bary[:, 2, None]
    n = normals[corners[0]] * w0 + normals[corners[1]] * w1 + normals[corners[2]] * w2
    albedo = colors[corners[0]] * w0 + colors[corners[1]] * w1 + colors[corners[2]] * w2
    # the lights see the side of the surface the camera sees: flip the normals of back faces
    sign = np.where(facing[fragments.triangle], 1.0, -1.0).astype(np.float32) / np.maximum(np.linalg.norm(n, axis=1), 1e-12)
    key = np.clip(n @ to_light.astype(np.float32) * sign, 0.0, None)
    fill = np.clip(n @ to_camera.astype(np.float32) * sign, 0.0, None)
    light = AMBIENT + KEY * key + FILL * fill
    level = np.minimum(albedo * light[:, None] * 4095.0 + 0.5, 4095.0).astype(np.int32)
    return _SRGB_BYTES[level]
