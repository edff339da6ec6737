"""A z-buffered triangle rasterizer in numpy: no per-triangle or per-pixel Python loop.

Pixels are (x right, y down); pixel (i, j) covers [i, i + 1) x [j, j + 1) and is sampled at its
centre. Triangles are grouped by the size of their screen bounding box (rounded up to powers of
two), and each group tests all its candidate pixels against all its triangles in one array
operation with barycentric coordinates. The nearest fragment per pixel wins through one
``np.maximum.at`` on a key that packs the quantized depth above the triangle index.

Depth is "nearness": larger is nearer the eye. It must vary linearly across the screen inside a
triangle (camera-space nearness for an orthographic view, ``1 / distance`` for a perspective one).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Candidate pixels tested in one array operation at most (bounds memory).
CHUNK = 1 << 21
#: Depth levels of the z-buffer key.
DEPTH_LEVELS = (1 << 30) - 1
#: Slack on the barycentric tests, so edges shared by two triangles leave no crack.
EDGE_EPS = 1e-5


@dataclass
class Fragments:
    """The visible surface: for each covered pixel, its flat index ``y * width + x``, the triangle
    drawn there and that triangle's barycentric coordinates at the pixel centre (P, 3)."""

    index: np.ndarray
    triangle: np.ndarray
    barycentric: np.ndarray


class _Setup:
    """The triangles that may cover a pixel centre: their clipped bounding boxes (first pixel
    ``bx, by``, size ``bw, bh``) and the affine functions of the pixel offset (ox, oy) from the
    box's first pixel centre that give their barycentric coordinates ``l1, l2`` (and depth):
    ``l = c + a * ox + b * oy``."""

    def __init__(self, pixels: np.ndarray, triangles: np.ndarray, width: int, height: int, depth: np.ndarray | None = None):
        x = pixels[:, 0][triangles]  # (T, 3)
        y = pixels[:, 1][triangles]
        xa, xb, xc, ya, yb, yc = x[:, 0], x[:, 1], x[:, 2], y[:, 0], y[:, 1], y[:, 2]
        x0 = np.maximum(np.ceil(np.minimum(np.minimum(xa, xb), xc) - 0.5), 0)
        x1 = np.minimum(np.floor(np.maximum(np.maximum(xa, xb), xc) - 0.5), width - 1)
        y0 = np.maximum(np.ceil(np.minimum(np.minimum(ya, yb), yc) - 0.5), 0)
        y1 = np.minimum(np.floor(np.maximum(np.maximum(ya, yb), yc) - 0.5), height - 1)
        e1x, e1y, e2x, e2y = xb - xa, yb - ya, xc - xa, yc - ya
        det = e1x * e2y - e1y * e2x
        keep = (x1 >= x0) & (y1 >= y0) & (np.abs(det) > 1e-12) & np.isfinite(det)
        self.index = idx = np.flatnonzero(keep)
        inv = 1.0 / det[idx]
        # (l1, l2) = M^-1 (p - p0) with M = [e1 e2]
        a1, b1 = e2y[idx] * inv, -e2x[idx] * inv
        a2, b2 = -e1y[idx] * inv, e1x[idx] * inv
        self.bx, self.by = x0[idx].astype(np.int64), y0[idx].astype(np.int64)
        self.bw = (x1 - x0)[idx].astype(np.int64) + 1
        self.bh = (y1 - y0)[idx].astype(np.int64) + 1
        dx, dy = x0[idx] + 0.5 - xa[idx], y0[idx] + 0.5 - ya[idx]
        self.l1 = np.stack([a1 * dx + b1 * dy, a1, b1], axis=1).astype(np.float32)  # (n, 3): c, a, b
        self.l2 = np.stack([a2 * dx + b2 * dy, a2, b2], axis=1).astype(np.float32)
        if depth is not None:  # depth is affine in the pixel offset too: z0 + l1 (z1 - z0) + l2 (z2 - z0)
            z = depth[triangles[idx]]
            dz1, dz2 = z[:, 1] - z[:, 0], z[:, 2] - z[:, 0]
            self.z = np.stack([z[:, 0] + self.l1[:, 0] * dz1 + self.l2[:, 0] * dz2,
                               a1 * dz1 + a2 * dz2, b1 * dz1 + b2 * dz2], axis=1)

    def fragments(self, width: int, height: int):
        """Yield ``(rows, ox, oy)``: for each pixel centre inside a triangle, the triangle's row in
        this setup and the pixel's offset from the triangle's first pixel; one group at a time."""
        if not len(self.index):
            return
        lw = np.ceil(np.log2(self.bw)).astype(np.int64)
        lh = np.ceil(np.log2(self.bh)).astype(np.int64)
        key = lw * 64 + lh
        order = np.argsort(key, kind="stable")
        bounds = np.flatnonzero(np.diff(key[order])) + 1
        for group in np.split(order, bounds):
            gw, gh = 1 << int(lw[group[0]]), 1 << int(lh[group[0]])
            ox = np.tile(np.arange(gw, dtype=np.float32), gh)
            oy = np.repeat(np.arange(gh, dtype=np.float32), gw)
            step = max(CHUNK // (gw * gh), 1)
            for s in range(0, len(group), step):
                g = group[s:s + step]
                c1, a1, b1 = (self.l1[g, k, None] for k in range(3))
                c2, a2, b2 = (self.l2[g, k, None] for k in range(3))
                l1 = c1 + a1 * ox + b1 * oy
                l2 = c2 + a2 * ox + b2 * oy
                inside = (l1 >= -EDGE_EPS) & (l2 >= -EDGE_EPS) & (l1 + l2 <= 1.0 + EDGE_EPS)
                flat = np.flatnonzero(inside)
                rows, cols = g[flat // (gw * gh)], flat % (gw * gh)
                fx, fy = cols % gw, cols // gw
                # a box clipped at the right or bottom edge lets the power-of-two grid run off the image
                on = (self.bx[rows] + fx < width) & (self.by[rows] + fy < height)
                if not on.all():
                    rows, fx, fy = rows[on], fx[on], fy[on]
                yield rows, fx, fy

    def flat(self, rows: np.ndarray, fx: np.ndarray, fy: np.ndarray, width: int) -> np.ndarray:
        return (self.by[rows] + fy) * width + self.bx[rows] + fx


def rasterize(pixels: np.ndarray, depth: np.ndarray, triangles: np.ndarray, size: tuple[int, int]) -> Fragments:
    """The nearest triangle at every pixel centre of a ``size`` = (width, height) image.

    ``pixels`` (V, 2) vertex positions in pixels, ``depth`` (V,) nearness (larger wins, linear
    across the screen), ``triangles`` (T, 3) vertex indices (either winding).
    """
    width, height = int(size[0]), int(size[1])
    pixels = np.asarray(pixels, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    empty = Fragments(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3), np.float32))
    if not len(triangles):
        return empty
    setup = _Setup(pixels, triangles, width, height, depth)
    if not len(setup.index):
        return empty
    lo, hi = float(depth.min()), float(depth.max())
    scale = DEPTH_LEVELS / (hi - lo) if hi > lo else 0.0
    buffer = np.full(width * height, -1, dtype=np.int64)
    for rows, fx, fy in setup.fragments(width, height):
        zc = setup.z[rows]
        near = zc[:, 0] + zc[:, 1] * fx + zc[:, 2] * fy
        level = np.clip(np.rint((near - lo) * scale), 0, DEPTH_LEVELS).astype(np.int64)
        np.maximum.at(buffer, setup.flat(rows, fx, fy, width), (level << 32) | rows)
    covered = np.flatnonzero(buffer >= 0)
    rows = buffer[covered] & 0xFFFFFFFF
    # barycentrics of the winners at their pixel centres
    fx = (covered % width - setup.bx[rows]).astype(np.float32)
    fy = (covered // width - setup.by[rows]).astype(np.float32)
    l1, l2 = (np.clip(c[:, 0] + c[:, 1] * fx + c[:, 2] * fy, 0.0, 1.0) for c in (setup.l1[rows], setup.l2[rows]))
    over = np.maximum(l1 + l2, 1.0)
    l1, l2 = l1 / over, l2 / over
    bary = np.stack([1.0 - l1 - l2, l1, l2], axis=1)
    return Fragments(covered, setup.index[rows], bary)


def coverage(pixels: np.ndarray, triangles: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(height, width) bool: the pixel centres any triangle covers (a silhouette, e.g. a shadow)."""
    width, height = int(size[0]), int(size[1])
    mask = np.zeros(width * height, dtype=bool)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(triangles):
        setup = _Setup(np.asarray(pixels, dtype=np.float64), triangles, width, height)
        for rows, fx, fy in setup.fragments(width, height):
            mask[setup.flat(rows, fx, fy, width)] = True
    return mask.reshape(height, width)
