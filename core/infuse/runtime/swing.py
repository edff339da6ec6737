"""Rotations in a joint's *aligned frame*: heading, pitch and roll as a character would name them.

A joint's aligned frame is the joint's own frame turned so that, in the rest pose, its axes are the
character's: +X its left, +Y up, +Z forward (see :class:`~infuse.runtime.rig.Rig`). An offset in that
frame means the same on every skeleton, whatever axes the joints were built with.

- heading: radians about +Y, positive turns the forward axis to the character's left;
- pitch: radians, positive tilts the forward axis up;
- roll: radians about the (turned) forward axis, positive lifts the left side.

``swing(h, p, r) = R_Y(h) R_X(-p) R_Z(r)`` maps +Z to the direction (cos p sin h, sin p, cos p cos h).
Quaternions are (x, y, z, w); everything is vectorized over leading axes.
"""
from __future__ import annotations

import numpy as np

from .. import quaternions as quat


def swing(heading, pitch, roll=0.0) -> np.ndarray:
    """Quaternions (..., 4) of heading, then pitch, then roll, in radians (see the module doc)."""
    h = 0.5 * np.asarray(heading, dtype=np.float64)
    p = -0.5 * np.asarray(pitch, dtype=np.float64)
    if np.ndim(roll) == 0 and roll == 0.0:  # no roll: cos 1, sin 0 in the products below
        if h.shape != p.shape:
            h, p = np.broadcast_arrays(h, p)
        ch, sh, cp, sp = np.cos(h), np.sin(h), np.cos(p), np.sin(p)
        return np.stack((ch * sp, sh * cp, -(sh * sp), ch * cp), axis=-1)
    r = 0.5 * np.asarray(roll, dtype=np.float64)
    if not h.shape == p.shape == r.shape:
        h, p, r = np.broadcast_arrays(h, p, r)
    ch, sh, cp, sp, cr, sr = np.cos(h), np.sin(h), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    # (0, sh, 0, ch) * (sp, 0, 0, cp) * (0, 0, sr, cr), multiplied out.
    x = ch * sp * cr + sh * cp * sr
    y = sh * cp * cr - ch * sp * sr
    z = ch * cp * sr - sh * sp * cr
    w = ch * cp * cr + sh * sp * sr
    return np.stack((x, y, z, w), axis=-1)


def direction_angles(direction) -> tuple[np.ndarray, np.ndarray]:
    """(heading, pitch) in radians of direction vectors (..., 3) given in an aligned frame."""
    d = np.asarray(direction, dtype=np.float64)
    horizontal = np.hypot(d[..., 0], d[..., 2])
    return np.arctan2(d[..., 0], d[..., 2]), np.arctan2(d[..., 1], horizontal)


def swing_angles(q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(heading, pitch, roll) in radians of quaternions (..., 4), the inverse of :func:`swing`."""
    q = np.asarray(q, dtype=np.float64)
    forward = quat.rotate(q, np.array([0.0, 0.0, 1.0]))
    heading, pitch = direction_angles(forward)
    twist = quat.multiply(quat.conjugate(swing(heading, pitch)), q)  # a rotation about +Z only
    roll = 2.0 * np.arctan2(twist[..., 2], twist[..., 3])
    roll = (roll + np.pi) % (2.0 * np.pi) - np.pi
    return heading, pitch, roll


def ellipse_scale(heading, pitch, heading_limit, up_limit, down_limit) -> np.ndarray:
    """How far (heading, pitch) lies in the elliptical limit: 1 on the border, > 1 outside.

    Limits are radians; pitch uses ``up_limit`` when positive and ``down_limit`` when negative.
    A zero limit allows no rotation about that axis.
    """
    heading = np.asarray(heading, dtype=np.float64)
    pitch = np.asarray(pitch, dtype=np.float64)
    vertical = np.where(pitch >= 0.0, up_limit, down_limit)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(heading == 0.0, 0.0, heading / np.where(heading_limit > 0, heading_limit, 0.0))
        b = np.where(pitch == 0.0, 0.0, pitch / np.where(vertical > 0, vertical, 0.0))
    return np.sqrt(a * a + b * b)


def clamp_ellipse(heading, pitch, heading_limit, up_limit, down_limit) -> tuple[np.ndarray, np.ndarray]:
    """(heading, pitch) scaled toward zero onto the elliptical limit when outside it (radians)."""
    heading = np.asarray(heading, dtype=np.float64)
    pitch = np.asarray(pitch, dtype=np.float64)
    heading = np.where(np.asarray(heading_limit) > 0, heading, 0.0)
    pitch = np.where(np.where(pitch >= 0.0, up_limit, down_limit) > 0, pitch, 0.0)
    scale = ellipse_scale(heading, pitch, heading_limit, up_limit, down_limit)
    factor = np.where(scale > 1.0, 1.0 / np.maximum(scale, 1e-12), 1.0)
    return heading * factor, pitch * factor


class EllipseClamp:
    """:func:`clamp_ellipse` with fixed limits (radians; arrays broadcasting against the angles): what
    depends only on them is worked out once. With every limit above zero (no axis locked, no division
    by zero) it skips the locking and the guards, to the same results."""

    def __init__(self, heading_limit, up_limit, down_limit):
        self.limits = tuple(np.asarray(x, dtype=np.float64) for x in (heading_limit, up_limit, down_limit))
        self.open = all(bool((limit > 0).all()) for limit in self.limits)

    def __call__(self, heading: np.ndarray, pitch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(heading, pitch) scaled toward zero onto the elliptical limit when outside it."""
        if not self.open:
            return clamp_ellipse(heading, pitch, *self.limits)
        heading_limit, up_limit, down_limit = self.limits
        a, b = heading / heading_limit, pitch / np.where(pitch >= 0.0, up_limit, down_limit)
        scale = np.sqrt(a * a + b * b)
        factor = np.where(scale > 1.0, 1.0 / np.maximum(scale, 1e-12), 1.0)
        return heading * factor, pitch * factor


#: The aligned-frame axis each of heading, pitch and roll turns about, with its sign (see :func:`swing`).
SWING_AXES = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def local_axes(aligned, axes) -> np.ndarray:
    """Axes (..., 3) of aligned frames ``A`` (..., 4) in their joints' own frames (``A a``)."""
    return quat.rotate(aligned, np.asarray(axes, dtype=np.float64))


def local_turns(axes, angles) -> np.ndarray:
    """Local rotation offsets (..., K, 4) turning joints by ``angles`` (..., K) radians about their
    local ``axes`` (K, 3) (unit; see :func:`local_axes`): the same as :func:`local_offsets` of a
    :func:`swing` with one angle, where the whole turn is about one axis."""
    half = 0.5 * np.asarray(angles, dtype=np.float64)
    out = np.empty(half.shape + (4,))
    out[..., :3] = np.sin(half)[..., None] * axes
    out[..., 3] = np.cos(half)
    return out


def local_offsets(aligned, offsets) -> np.ndarray:
    """Local rotation offsets ``A Δ A⁻¹`` (..., 4) from offsets ``Δ`` (..., 4) in aligned frames ``A``.

    Post-multiplied onto a joint's local rotation (``L · A Δ A⁻¹``) they turn everything below the
    joint by ``Δ`` as seen in the joint's aligned frame. (``A Δ A⁻¹`` is ``Δ`` with its axis turned by
    ``A``: the same angle, so the scalar part stays.)
    """
    aligned = np.asarray(aligned, dtype=np.float64)
    offsets = np.asarray(offsets, dtype=np.float64)
    out = np.empty(np.broadcast_shapes(aligned.shape, offsets.shape))
    out[..., :3] = quat.rotate(aligned, offsets[..., :3])
    out[..., 3] = offsets[..., 3]
    return out
