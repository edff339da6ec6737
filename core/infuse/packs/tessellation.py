"""An automatic tessellation of a parameter space and barycentric blend weights inside it.

Example points (one per clip, in a few named coordinates such as forward speed, lateral speed and
turn rate) are normalized by their range, reduced to the dimensions they actually span (0 to 3,
from their singular values), and tessellated: sorted segments in 1D, scipy's Delaunay (Qhull) in 2D
and 3D. A query point gets the barycentric weights of the simplex containing it; a point outside the
hull gets those of the nearest point of the hull, and is reported as outside. Nothing is typed by hand.
"""
from __future__ import annotations

import operator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


#: Examples closer than this in the normalized, reduced space stand at one point and share its weight.
SAME_POINT = 1e-9


class Located(NamedTuple):
    """Query points located in a :class:`Tessellation` (:meth:`Tessellation.locate`): their reduced coordinates
    ``y`` (Q, d), barycentric coordinates ``bary`` (S, d+1, Q) in every simplex, (S, Q) flags ``held`` of the
    simplices holding them and (Q,) flags ``inside`` of the points inside the hull."""

    y: np.ndarray
    bary: np.ndarray
    held: np.ndarray
    inside: np.ndarray

    def replaced(self, rows: np.ndarray, other: "Located") -> "Located":
        """These points with those at ``rows`` (K,) replaced by ``other``'s K points (the arrays written in place;
        a new ``inside``)."""
        self.y[rows] = other.y
        self.bary[:, :, rows] = other.bary
        self.held[:, rows] = other.held
        inside = self.inside.copy()
        inside[rows] = other.inside
        return Located(self.y, self.bary, self.held, inside)


@dataclass
class Tessellation:
    """Simplices over example points.

    - ``coordinates``: names of the D coordinates; ``labels``: the N examples (clip names);
    - ``points``: (N, D) example coordinates (units of each coordinate);
    - ``origin`` (D,), ``scale`` (D,), ``basis`` (D, d): the normalized, reduced space
      ``y = ((x - origin) / scale) @ basis`` of dimension d;
    - ``simplices``: (S, d + 1) indices of examples.
    """

    coordinates: tuple[str, ...]
    labels: tuple[str, ...]
    points: np.ndarray
    origin: np.ndarray
    scale: np.ndarray
    basis: np.ndarray
    simplices: np.ndarray

    @classmethod
    def build(cls, coordinates, labels, points, tolerance: float = 1e-6, resolution=None) -> "Tessellation":
        """Tessellate (N, D) ``points``; coordinates, and directions of the space, along which the
        examples do not spread (by less than the coordinates' ``resolution`` (D,), if given, in their
        units) are left out."""
        pts = np.asarray(points, dtype=np.float64).reshape(len(labels), len(coordinates))
        if not len(pts):
            raise ValueError("a tessellation needs at least one example")
        origin = pts.mean(axis=0)
        spread = np.ptp(pts, axis=0)
        spans = spread > (tolerance if resolution is None else np.maximum(np.asarray(resolution, dtype=np.float64), tolerance))
        scale = np.where(spans, spread, 1.0)
        x = np.where(spans, (pts - origin) / scale, 0.0)
        _, sv, vt = np.linalg.svd(x, full_matrices=False) if len(pts) > 1 else (None, np.zeros(0), np.zeros((0, len(coordinates))))
        keep = sv > tolerance * max(float(sv.max(initial=0.0)), 1.0) if len(sv) else np.zeros(0, dtype=bool)
        if resolution is not None and keep.any():
            # A direction counts if the examples spread along it by more than the resolution: the
            # extent of their projections, in resolution units of a unit step along it.
            unit = np.linalg.norm(vt * scale / np.maximum(np.asarray(resolution, dtype=np.float64), tolerance), axis=1)
            keep &= np.ptp(x @ vt.T, axis=0) * unit > 1.0
        chosen = np.nonzero(keep)[0][:3]
        rank = len(chosen)
        basis = vt[chosen].T if rank else np.zeros((len(coordinates), 0))
        y = x @ basis
        if rank == 0:
            simplices = np.zeros((1, 1), dtype=np.int64)
        elif rank == 1:
            order = np.argsort(y[:, 0], kind="stable")
            simplices = np.stack((order[:-1], order[1:]), axis=1)
        else:
            from scipy.spatial import Delaunay, QhullError

            try:
                tri = Delaunay(y)
            except QhullError:
                tri = Delaunay(y, qhull_options="QJ Qbb Qc Qz Q12")
            simplices = tri.simplices
            volume = np.abs(np.linalg.det(y[simplices[:, 1:]] - y[simplices[:, :1]]))
            simplices = simplices[volume > 1e-12]
        return cls(tuple(coordinates), tuple(labels), pts, origin, scale, basis, np.asarray(simplices, dtype=np.int64))

    @property
    def dimension(self) -> int:
        return self.basis.shape[1]

    def reduced(self, query) -> np.ndarray:
        """(Q, d) coordinates of (Q, D) ``query`` points in the normalized, reduced space."""
        q = query if isinstance(query, np.ndarray) and query.ndim == 2 and query.dtype == np.float64 else \
            np.atleast_2d(np.asarray(query, dtype=np.float64))
        return ((q - self.origin) / self.scale) @ self.basis

    def locate(self, query) -> Located:
        """The :class:`Located` (Q, D) ``query`` points: where they lie in the simplices, for :meth:`weights`."""
        y = self.reduced(query)
        if self.dimension == 0:
            return Located(y, np.ones((1, 1, len(y))), np.ones((1, len(y)), dtype=bool), np.ones(len(y), dtype=bool))
        bary, held = self._barycentric(y)
        return Located(y, bary, held, np.logical_or.reduce(held, axis=0))

    def weights(self, query, located: Located | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Blend weights (Q, N) of (Q, D) query points (each row sums to 1) and (Q,) inside-hull flags;
        ``located``: the points as :meth:`locate` gives them (the query is then not read)."""
        y, bary, held, inside = self.locate(query) if located is None else located
        q, n = len(y), len(self.labels)
        out = np.zeros((q, n))
        if self.dimension == 0:
            out[:, self.simplices[0, 0]] = 1.0
            return out, inside
        rows = np.arange(q)
        best = held.argmax(axis=0)  # the first simplex holding the query
        chosen = bary[best, :, rows]  # (Q, d+1)
        if not np.logical_and.reduce(inside):  # the clamped barycentric point nearest to the query, over every simplex
            outside = np.nonzero(~inside)[0]
            clamped = np.maximum(bary[:, :, outside], 0.0)
            clamped /= np.maximum(np.add.reduce(clamped, axis=1, keepdims=True), 1e-12)
            gap = np.swapaxes(self._frames()[0], 1, 2) @ clamped - y[outside].T  # (S, d, O) from the query
            nearest = np.argmin(np.sqrt(np.add.reduce(gap * gap, axis=1)), axis=0)
            best[outside] = nearest
            chosen[outside] = clamped[nearest, :, np.arange(outside.size)]
        out[rows[:, None], self.simplices[best]] = chosen  # a simplex's corners are distinct examples
        share = self._shares()
        return (out if share is None else out @ share), inside

    def contains(self, query) -> np.ndarray:
        """(Q,) flags of (Q, D) query points inside the hull (as :meth:`weights` reports them), without the weights."""
        return self.locate(query).inside

    def _barycentric(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Barycentric coordinates (S, d+1, Q) of reduced points ``y`` (Q, d) in every simplex, and (S, Q)
        flags of the simplices holding them (coordinates >= -1e-9). Simplex-major with the points last:
        each simplex is one small matrix product, and the sums and tests run over whole rows."""
        _, base, inv = self._frames()
        lam = inv @ (y.T[None] - base[:, :, None])  # (S, d, Q)
        bary = np.concatenate((1.0 - np.add.reduce(lam, axis=1, keepdims=True), lam), axis=1)
        return bary, np.logical_and.reduce(bary >= -1e-9, axis=1)

    def _frames(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each simplex's corners (S, d+1, d), first corner (S, d) and inverted edge matrix (S, d, d) in
        the reduced space (computed once: a controller asks for weights every block)."""
        key = (self.points, self.simplices, self.origin, self.scale, self.basis)
        cached = self.__dict__.get("_cached_frames")
        if cached is None or not all(map(operator.is_, cached[0], key)):
            corners = self.reduced(self.points)[self.simplices]            # (S, d+1, d)
            base = corners[:, 0]                                           # (S, d)
            edges = np.swapaxes(corners[:, 1:] - base[:, None], 1, 2)      # (S, d, d)
            cached = (key, corners, base, np.linalg.pinv(edges))
            self.__dict__["_cached_frames"] = cached
        return cached[1], cached[2], cached[3]

    def _shares(self) -> np.ndarray | None:
        """(N, N) matrix spreading a weight evenly over examples at one point (within :data:`SAME_POINT`
        in the reduced space), or None when no two coincide. Qhull keeps one of coinciding points, and
        which one turns on the last bits of their coordinates: spread, their blend does not."""
        key = (self.points, self.origin, self.scale, self.basis)
        cached = self.__dict__.get("_cached_shares")
        if cached is None or not all(map(operator.is_, cached[0], key)):
            y = self.reduced(self.points)
            same = np.linalg.norm(y[:, None] - y[None], axis=-1) <= SAME_POINT
            share = same / same.sum(axis=1, keepdims=True) if same.sum() > len(y) else None
            cached = self.__dict__["_cached_shares"] = (key, share)
        return cached[1]

    def to_dict(self) -> dict:
        return {"coordinates": list(self.coordinates), "labels": list(self.labels), "points": self.points.tolist(),
                "origin": self.origin.tolist(), "scale": self.scale.tolist(), "basis": self.basis.tolist(),
                "simplices": self.simplices.tolist(), "dimension": self.dimension}

    @classmethod
    def from_dict(cls, d: dict) -> "Tessellation":
        dims = len(d["coordinates"])
        return cls(tuple(d["coordinates"]), tuple(d["labels"]), np.asarray(d["points"], dtype=np.float64).reshape(-1, dims),
                   np.asarray(d["origin"], dtype=np.float64), np.asarray(d["scale"], dtype=np.float64),
                   np.asarray(d["basis"], dtype=np.float64).reshape(dims, -1), np.asarray(d["simplices"], dtype=np.int64))

    def describe(self) -> str:
        """One line: dimension, examples, simplices."""
        kind = {0: "a single point", 1: "segments", 2: "triangles", 3: "tetrahedra"}[self.dimension]
        return (f"{self.dimension}D over ({', '.join(self.coordinates)}): {len(self.labels)} examples, "
                f"{len(self.simplices)} {kind}")
