"""Sampling COLLADA animation curves at many times at once.

A curve has K keys: times (K,) in seconds, values (K, S), one interpolation name per key that
applies to the segment starting there (``STEP``, ``LINEAR``, ``BEZIER``, ``HERMITE``; other
names are sampled linearly), and for ``BEZIER``/``HERMITE`` in/out tangents. Bezier tangents are
2D control points (time, value) per component, (K, 2S), or values only, (K, S), in which case
their times sit at a third of the segment. Before the first and after the last key the curve
holds its end value. Everything is vectorized over the sample times.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Curve:
    times: np.ndarray
    values: np.ndarray
    interpolation: np.ndarray
    in_tangents: np.ndarray | None = None
    out_tangents: np.ndarray | None = None


def sample(curve: Curve, t: np.ndarray) -> np.ndarray:
    """Values (F, S) of ``curve`` at times ``t`` (F,)."""
    times, values = curve.times, curve.values
    t = np.asarray(t, dtype=np.float64)
    if len(times) == 1:
        return np.broadcast_to(values[0], (len(t), values.shape[1])).copy()
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    tc = np.clip(t, times[0], times[-1])
    t0, t1 = times[seg], times[seg + 1]
    dt = t1 - t0
    u = np.where(dt > 0, (tc - t0) / np.where(dt > 0, dt, 1.0), 0.0)[:, None]
    v0, v1 = values[seg], values[seg + 1]
    out = v0 + u * (v1 - v0)
    kind = curve.interpolation[seg]
    out = np.where((kind == "STEP")[:, None], v0, out)
    curved = (kind == "BEZIER") | (kind == "HERMITE")
    if np.any(curved) and curve.in_tangents is not None and curve.out_tangents is not None:
        rows = np.nonzero(curved)[0]
        smooth = _bezier(curve, seg[rows], tc[rows], u[rows], kind[rows] == "HERMITE")
        out[rows] = smooth
    return np.where((t >= times[-1])[:, None], values[-1], out)


def _bezier(curve: Curve, seg: np.ndarray, t: np.ndarray, u: np.ndarray, hermite: np.ndarray) -> np.ndarray:
    s_dim = curve.values.shape[1]
    p0, p1 = curve.values[seg], curve.values[seg + 1]
    out_t, in_t = curve.out_tangents[seg], curve.in_tangents[seg + 1]
    if out_t.shape[1] == 2 * s_dim:
        # 2D control points: solve x(s) = t for the curve parameter s, then evaluate y(s).
        t0 = curve.times[seg][:, None]
        t1 = curve.times[seg + 1][:, None]
        c0t = np.clip(out_t[:, 0::2], np.minimum(t0, t1), np.maximum(t0, t1))
        c1t = np.clip(in_t[:, 0::2], np.minimum(t0, t1), np.maximum(t0, t1))
        c0v, c1v = out_t[:, 1::2], in_t[:, 1::2]
        s = _solve_parameter(t0, c0t, c1t, t1, np.broadcast_to(t[:, None], c0t.shape))
    else:
        c0v, c1v = out_t, in_t
        s = np.broadcast_to(u, p0.shape)
    bez = _cubic(p0, c0v, c1v, p1, s)
    # Hermite: tangents are slopes over the segment, s is the normalized time.
    uu = np.broadcast_to(u, p0.shape)
    h = ((2 * uu**3 - 3 * uu**2 + 1) * p0 + (uu**3 - 2 * uu**2 + uu) * c0v
         + (-2 * uu**3 + 3 * uu**2) * p1 + (uu**3 - uu**2) * c1v)
    return np.where(hermite[:, None], h, bez)


def _cubic(a, b, c, d, s):
    r = 1.0 - s
    return r**3 * a + 3 * r**2 * s * b + 3 * r * s**2 * c + s**3 * d


def _solve_parameter(a, b, c, d, x, iterations: int = 40) -> np.ndarray:
    """The s in [0, 1] with cubic(a, b, c, d, s) = x, by bisection (monotonic control times)."""
    lo = np.zeros(np.broadcast_shapes(np.shape(a), np.shape(x)))
    hi = np.ones_like(lo)
    increasing = np.broadcast_to(d >= a, lo.shape)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        below = (_cubic(a, b, c, d, mid) < x) == increasing
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)
