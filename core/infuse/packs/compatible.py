"""Locomotion blend weights that never mix in examples travelling against the request.

A pack's tessellation may put a request between examples that travel opposite ways: Bandai dataset-1
feminine has no idle, so it starts at 0.75 m/s straight ahead, which its triangles make 87% of its
0.95 m/s walk and 13% of its walk back (the edge between them passes between its diagonal walks). The
walk back's legs swing the other way, and blended in they flatten the steps: the heel comes down
early and skids. Here a request travelling in a direction (velocity along and across the facing, m/s)
is blended from the examples that do not travel against it (their velocity at most a degree past
square to it; an idle, not travelling, never does) whenever those reach it, at the turn rate nearest
the request's that they show (the rest is spun at the root); elsewhere the tessellation's own weights
stand. :meth:`CompatibleBlend.slowest` says how slowly they reach each direction, for a pack without an
idle to walk slower than that by slowing its blend there.
"""
from __future__ import annotations

import numpy as np

from .coverage import Hull, speed_limits
from .tessellation import Tessellation

#: An example travels against a direction when the cosine between its velocity and it is below this
#: (a degree past square): a strafe exactly across the facing stays with a walk forward or back.
AGAINST_COS = -0.02
#: Examples slower than this (m/s) do not travel (an idle) and go with every request.
STILL_M_S = 1e-3
#: How many sets of directions :meth:`CompatibleBlend.slowest` keeps its answer for (all let go when full).
SLOWEST_KEPT = 256


class CompatibleBlend:
    """Weights over a locomotion :class:`~.tessellation.Tessellation` (coordinates forward speed, lateral
    speed, turn rate) from the examples that do not travel against each request."""

    def __init__(self, tessellation: Tessellation, resolution=None):
        self.t = tessellation
        self.resolution = resolution
        self._subsets: dict[bytes, tuple[np.ndarray, Tessellation, Hull] | None] = {}
        self._hull: Hull | None = None
        self._slowest: dict[bytes, np.ndarray] = {}
        v = tessellation.points[:, :2]
        speed = np.linalg.norm(v, axis=1)
        # (2, N) each example's direction of travel (a unit vector; zeros for the still ones), for a
        # first look at which examples may travel against a request (:meth:`weights`).
        self._headings = np.where(speed > STILL_M_S, v.T / np.maximum(speed, 1e-12), 0.0)
        # What :meth:`against` reads of the examples: velocities along and across (N,), speeds (N,) (at
        # least 1e-12) and which ones travel (N,).
        self._along, self._across = v[:, 0].copy(), v[:, 1].copy()
        self._speeds, self._travel = np.maximum(speed, 1e-12), speed > STILL_M_S

    def against(self, direction) -> np.ndarray:
        """(Q, N) flags of the examples travelling against each of (Q,) ``direction`` radians (+ left)."""
        d = np.atleast_1d(np.asarray(direction, dtype=np.float64))
        cos = (np.cos(d)[:, None] * self._along + np.sin(d)[:, None] * self._across) / self._speeds
        return (cos < AGAINST_COS) & self._travel

    def _subset(self, against: np.ndarray):
        """(kept example indices, their tessellation, its hull) for a row of :meth:`against` flags, or None
        when nothing is left out or too little is kept to span anything."""
        key = against.tobytes()
        if key not in self._subsets:
            keep = np.nonzero(~against)[0]
            if not against.any() or not keep.size:
                self._subsets[key] = None
            else:
                sub = Tessellation.build(self.t.coordinates, [self.t.labels[i] for i in keep], self.t.points[keep],
                                         resolution=self.resolution)
                self._subsets[key] = (keep, sub, Hull(sub))
        return self._subsets[key]

    def weights(self, query, weights: np.ndarray) -> np.ndarray:
        """(Q, N) blend weights for (Q, 3) ``query`` points from the tessellation's own ``weights`` (Q, N):
        where those mix in an example travelling against the request and the others reach its velocity
        (as nearly as the tessellation's own weights do), the others' weights."""
        q = query if isinstance(query, np.ndarray) and query.ndim == 2 and query.dtype == np.float64 else \
            np.atleast_2d(np.asarray(query, dtype=np.float64))
        v = q[:, :2]
        speed = np.sqrt(np.add.reduce(v * v, axis=1))  # np.linalg.norm's arithmetic, without its checks
        # A first look (cosines to the examples' headings, within 1e-9 of :meth:`against`'s): requests
        # that mix in no example near against them keep their weights as they are.
        near = (v @ self._headings < (AGAINST_COS + 1e-9) * speed[:, None]) & (weights > 0.0)
        out = np.array(weights, dtype=np.float64)
        if not near.any():
            return out
        moving = np.flatnonzero((speed > STILL_M_S) & near.any(axis=1))
        if not moving.size:
            return out
        against = self.against(np.arctan2(q[moving, 1], q[moving, 0]))
        mixed = (out[moving] * against).sum(axis=1) > 0.0
        rows, against = moving[mixed], against[mixed]
        if not rows.size:
            return out
        scale = self.t.scale[:2]
        reached = np.linalg.norm((out[rows] @ self.t.points - q[rows])[:, :2] / scale, axis=1)
        for key, group in _alike(against):
            found = self._subset(key)
            if found is None:
                continue
            keep, sub, hull = found
            at = q[rows[group]].copy()
            at[:, 2] = hull.nearest_turns(at[:, :2], at[:, 2])[0]
            w = np.clip(sub.weights(at)[0], 0.0, None)
            w /= np.maximum(w.sum(axis=1, keepdims=True), 1e-12)
            gap = np.linalg.norm((w @ self.t.points[keep] - q[rows[group]])[:, :2] / scale, axis=1)
            good = gap <= reached[group] + 1e-6
            taken = rows[group][good]
            out[taken] = 0.0
            out[taken[:, None], keep[None]] = w[good]
        return out

    def slowest(self, direction) -> np.ndarray:
        """(Q,) the slowest speed (m/s) at which the examples not travelling against each of (Q,)
        ``direction`` radians reach it (0 with an idle among them; NaN where they do not reach it). Kept by
        the directions asked (a walk asks for the same block after block while it speeds up or slows down)."""
        d = np.atleast_1d(np.asarray(direction, dtype=np.float64))
        key = d.tobytes()
        kept = self._slowest.get(key)
        if kept is None:
            if len(self._slowest) >= SLOWEST_KEPT:
                self._slowest.clear()
            kept = self._slowest[key] = self._slowest_of(d)
        return kept.copy()

    def _slowest_of(self, d: np.ndarray) -> np.ndarray:
        """:meth:`slowest` of (Q,) directions ``d`` (radians), worked out."""
        against = self.against(d)
        out = np.full(len(d), np.nan)
        for key, group in _alike(against):
            found = self._subset(key)
            if found is None:
                self._hull = self._hull or Hull(self.t)
                tess, hull = self.t, self._hull
            else:
                tess, hull = found[1], found[2]
            top, low = speed_limits(tess, d[group], hull=hull)
            out[group] = np.where(top > 0.0, low, np.nan)
        return out


def _alike(flags: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The distinct rows of (Q, N) ``flags``, each with the indices (ascending) of the rows equal to it, in
    the order they first come (as ``np.unique(flags, axis=0)`` groups them, for less: a few rows at a time)."""
    found: dict[bytes, list[int]] = {}
    for i, row in enumerate(flags):
        found.setdefault(row.tobytes(), []).append(i)
    return [(flags[rows[0]], np.array(rows)) for rows in found.values()]
