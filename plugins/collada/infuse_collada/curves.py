"""Sampling COLLADA animation curves at many times at once.

A curve has K keys: times (K,) in seconds, values (K, S), one interpolation name per key that
applies to the segment starting there (``STEP``, ``LINEAR``, ``BEZIER``, ``HERMITE``; other
names are sampled linearly), and for ``BEZIER``/``HERMITE`` in/out tangents. Bezier tangents are
2D control points (time, value) per component, (K, 2S), or values only, (K, S), in which case
their times sit at a third of the segment. Before the first and after the last key the curve
holds its end value.

Everything is vectorized over sample times, and :func:`sample_all` solves the Bezier time
parameter of every curve in one batch.
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


def sample_all(curves: list[Curve], t: np.ndarray) -> list[np.ndarray]:
    """Values (F, S) of each curve at times ``t`` (F,)."""
    t = np.asarray(t, dtype=np.float64)
    outs, problems = [], []
    for curve in curves:
        out, problem = _straight(curve, t)
        outs.append(out)
        if problem is not None:
            problems.append((out, problem))
    if problems:
        # One bisection for every 2D-Bezier segment of every curve.
        a, b, c, d, x = (np.concatenate([p[k].ravel() for _, p in problems]) for k in range(5))
        s_all = _solve_parameter(a, b, c, d, x)
        start = 0
        for out, p in problems:
            size = p[0].size
            p[-1](out, s_all[start:start + size].reshape(p[0].shape))
            start += size
    return outs


def _straight(curve: Curve, t: np.ndarray):
    """Samples with STEP/LINEAR/HERMITE/1D-Bezier segments done; 2D-Bezier ones returned as a problem.

    The problem is (t0, c0t, c1t, t1, x) arrays plus a function that fills ``out`` from the solved
    curve parameter.
    """
    times, values = curve.times, curve.values
    if len(times) == 1:
        return np.broadcast_to(values[0], (len(t), values.shape[1])).copy(), None
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    tc = np.clip(t, times[0], times[-1])
    t0, t1 = times[seg], times[seg + 1]
    dt = t1 - t0
    u = np.where(dt > 0, (tc - t0) / np.where(dt > 0, dt, 1.0), 0.0)[:, None]
    v0, v1 = values[seg], values[seg + 1]
    out = v0 + u * (v1 - v0)
    kind = curve.interpolation[seg]
    out = np.where((kind == "STEP")[:, None], v0, out)
    out = np.where((t >= times[-1])[:, None], values[-1], out)
    curved = ((kind == "BEZIER") | (kind == "HERMITE")) & (t < times[-1])
    if not np.any(curved) or curve.in_tangents is None or curve.out_tangents is None:
        return out, None
    rows = np.nonzero(curved)[0]
    s_dim = values.shape[1]
    sg, uu = seg[rows], np.broadcast_to(u[rows], (len(rows), s_dim))
    p0, p1 = values[sg], values[sg + 1]
    out_t, in_t = curve.out_tangents[sg], curve.in_tangents[sg + 1]
    two_d = out_t.shape[1] == 2 * s_dim
    c0v, c1v = (out_t[:, 1::2], in_t[:, 1::2]) if two_d else (out_t, in_t)
    hermite = (kind[rows] == "HERMITE")[:, None]
    # Hermite: tangents are slopes over the segment and the parameter is the normalized time.
    h = ((2 * uu**3 - 3 * uu**2 + 1) * p0 + (uu**3 - 2 * uu**2 + uu) * c0v
         + (-2 * uu**3 + 3 * uu**2) * p1 + (uu**3 - uu**2) * c1v)
    if not two_d:
        out[rows] = np.where(hermite, h, _cubic(p0, c0v, c1v, p1, uu))
        return out, None
    a = np.broadcast_to(times[sg][:, None], p0.shape)
    d = np.broadcast_to(times[sg + 1][:, None], p0.shape)
    lo, hi = np.minimum(a, d), np.maximum(a, d)
    b, c = np.clip(out_t[:, 0::2], lo, hi), np.clip(in_t[:, 0::2], lo, hi)
    x = np.broadcast_to(tc[rows][:, None], p0.shape)

    def fill(target, s):
        target[rows] = np.where(hermite, h, _cubic(p0, c0v, c1v, p1, s))

    return out, (np.ascontiguousarray(a), b, c, np.ascontiguousarray(d), np.ascontiguousarray(x), fill)


def _cubic(a, b, c, d, s):
    r = 1.0 - s
    return r * r * (r * a + 3.0 * s * b) + s * s * (3.0 * r * c + s * d)


def _solve_parameter(a, b, c, d, x, iterations: int = 32) -> np.ndarray:
    """The s in [0, 1] with cubic(a, b, c, d, s) = x, by bisection (control times kept monotonic)."""
    # Power-basis coefficients, evaluated by Horner's rule in the loop.
    k3, k2, k1, k0 = d - 3.0 * c + 3.0 * b - a, 3.0 * (c - 2.0 * b + a), 3.0 * (b - a), a - x
    lo = np.zeros_like(x)
    hi = np.ones_like(x)
    increasing = d >= a
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        below = ((((k3 * mid + k2) * mid + k1) * mid + k0) < 0.0) == increasing
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)
