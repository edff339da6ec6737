"""Quaternion and vector maths on component-major arrays, the layout of the retargeting hot path.

Arrays hold components on the second-to-last axis and frames on the last: quaternions are
(..., 4, F) with rows x, y, z, w (scalar last, as everywhere in infuse) and vectors (..., 3, F).
One joint's component over all frames is then a contiguous row, so every operation below runs on
long contiguous vectors, and gathering joints (``a[idx]`` on a (J, 4, F) array) copies whole blocks.
Conventions are those of :mod:`infuse.quaternions`: ``mul(a, b)`` applies ``b`` first.
"""
from __future__ import annotations

import numpy as np


def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` of (..., 4, F) arrays (either may broadcast, e.g. (n, 4, 1))."""
    ax, ay, az, aw = a[..., 0, :], a[..., 1, :], a[..., 2, :], a[..., 3, :]
    bx, by, bz, bw = b[..., 0, :], b[..., 1, :], b[..., 2, :], b[..., 3, :]
    shape = np.broadcast_shapes(a.shape, b.shape)
    out = np.empty(shape)
    out[..., 0, :] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 1, :] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 2, :] = aw * bz + ax * by - ay * bx + az * bw
    out[..., 3, :] = aw * bw - ax * bx - ay * by - az * bz
    return out


def mul_inv(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a⁻¹ * b`` for unit quaternions (..., 4, F): the rotation of ``b`` relative to ``a``."""
    ax, ay, az, aw = a[..., 0, :], a[..., 1, :], a[..., 2, :], a[..., 3, :]
    bx, by, bz, bw = b[..., 0, :], b[..., 1, :], b[..., 2, :], b[..., 3, :]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0, :] = aw * bx - ax * bw - ay * bz + az * by
    out[..., 1, :] = aw * by + ax * bz - ay * bw - az * bx
    out[..., 2, :] = aw * bz - ax * by + ay * bx - az * bw
    out[..., 3, :] = aw * bw + ax * bx + ay * by + az * bz
    return out


def conj(q: np.ndarray) -> np.ndarray:
    """Conjugates (inverses of unit quaternions), (..., 4, F)."""
    out = np.array(q, dtype=np.float64, copy=True)
    out[..., :3, :] *= -1.0
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of (..., 3, F) vectors."""
    ax, ay, az = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    bx, by, bz = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0, :] = ay * bz - az * by
    out[..., 1, :] = az * bx - ax * bz
    out[..., 2, :] = ax * by - ay * bx
    return out


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products (..., F) of (..., 3, F) vectors."""
    return a[..., 0, :] * b[..., 0, :] + a[..., 1, :] * b[..., 1, :] + a[..., 2, :] * b[..., 2, :]


def norm(v: np.ndarray) -> np.ndarray:
    """Lengths (..., F) of (..., 3, F) vectors."""
    return np.sqrt(dot(v, v))


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate (..., 3, F) vectors by (..., 4, F) unit quaternions: v + w t + u x t, t = 2 u x v."""
    u = q[..., :3, :]
    t = cross(u, v)
    t *= 2.0
    return v + q[..., 3:4, :] * t + cross(u, t)


def normalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4, F); a zero quaternion becomes the identity."""
    n = np.sqrt(np.sum(q * q, axis=-2, keepdims=True))
    out = q / np.maximum(n, 1e-12)
    bad = n[..., 0, :] < 1e-12
    if np.any(bad):
        out[..., 3, :] = np.where(bad, 1.0, out[..., 3, :])
    return out


def between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Shortest-arc rotations (..., 4, F) taking directions ``u`` to ``v`` (..., 3, F, any length).

    Opposite directions turn by pi about an axis orthogonal to ``u``.
    """
    nu = norm(u)
    nv = norm(v)
    c = cross(u, v)
    d = dot(u, v)
    out = np.empty(c.shape[:-2] + (4,) + c.shape[-1:])
    out[..., :3, :] = c
    out[..., 3, :] = nu * nv + d
    opposite = out[..., 3, :] <= 1e-9 * np.maximum(nu * nv, 1e-300)
    if np.any(opposite):
        x = np.zeros_like(u)
        x[..., 0, :] = 1.0
        ortho = cross(u, x)
        y = np.zeros_like(u)
        y[..., 1, :] = 1.0
        ortho = np.where((norm(ortho) < 1e-6 * np.maximum(nu, 1e-300))[..., None, :], cross(u, y), ortho)
        out[..., :3, :] = np.where(opposite[..., None, :], ortho, out[..., :3, :])
        out[..., 3, :] = np.where(opposite, 0.0, out[..., 3, :])
    return normalize(out)


def from_axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4, F) from unit axes (..., 3, F) and angles (..., F) in radians."""
    half = 0.5 * angle
    s = np.sin(half)
    angle = np.asarray(angle)
    lead = np.broadcast_shapes(axis.shape[:-2], angle.shape[:-1])
    out = np.empty(lead + (4,) + np.broadcast_shapes(axis.shape[-1:], angle.shape[-1:]))
    out[..., :3, :] = axis * s[..., None, :]
    out[..., 3, :] = np.cos(half)
    return out


def exp(omega: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4, F) of rotation vectors (..., 3, F)."""
    angle = norm(omega)
    half = 0.5 * angle
    k = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-300), 0.5)
    out = np.empty(omega.shape[:-2] + (4,) + omega.shape[-1:])
    out[..., :3, :] = omega * k[..., None, :]
    out[..., 3, :] = np.cos(half)
    return out


def log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3, F), angle in [0, pi], of unit quaternions (..., 4, F)."""
    sign = np.where(q[..., 3, :] < 0.0, -1.0, 1.0)
    v = q[..., :3, :] * sign[..., None, :]
    s = norm(v)
    angle = 2.0 * np.arctan2(s, q[..., 3, :] * sign)
    k = np.where(s > 1e-12, angle / np.maximum(s, 1e-300), 2.0)
    return v * k[..., None, :]


def twist_power(q: np.ndarray, axis: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """``fraction`` (n, 1) of the twist of rotations ``q`` (n, 4, F) about unit axes ``axis`` (n, 3, 1)."""
    sign = np.where(q[..., 3, :] < 0.0, -1.0, 1.0)
    s = dot(q[..., :3, :], axis) * sign
    angle = 2.0 * np.arctan2(s, q[..., 3, :] * sign)
    return from_axis_angle(axis, angle * fraction)


def make_continuous(q: np.ndarray) -> np.ndarray:
    """Flip signs along frames (last axis) so neighbouring quaternions of (..., 4, F) share a hemisphere."""
    d = q[..., 0, 1:] * q[..., 0, :-1]
    for k in (1, 2, 3):
        d += q[..., k, 1:] * q[..., k, :-1]
    flips = np.cumsum(d < 0.0, axis=-1) % 2 == 1
    if not flips.any():
        return q
    out = np.array(q)
    out[..., 1:] *= np.where(flips, -1.0, 1.0)[..., None, :]
    return out
