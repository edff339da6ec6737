"""Turning a foot onto its ball's goal by Jacobian pseudo-inverse IK, every frame at once.

The legs themselves are solved by the core's two-bone IK (:func:`infuse.runtime.limb_ik.turn_limb`);
:func:`aim` then turns the end joint (3 degrees of freedom) to bring the next point (the ball of the
foot) to its goal with the paper's update, ``ΔΘ = J⁺Δx + (I − J⁺J)Δz``, solved damped
(``J⁺ = Jᵀ(JJᵀ + λ²I)⁻¹``), the transferred orientation as its null-space target ``z``: the foot
keeps its transferred roll about the ankle-to-ball axis. Arrays are component-major over frames,
(3, F) vectors and (4, F) quaternions (see :mod:`.cq`). The result is a world rotation to apply to
the foot's segment.
"""
from __future__ import annotations

import numpy as np

from . import cq

def solve_sym3(m: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve symmetric positive-definite systems ``m x = b``, m (3, 3, F), b (3, F), by the adjugate."""
    a, d, f = m[0, 0], m[1, 1], m[2, 2]
    bb, c, e = m[0, 1], m[0, 2], m[1, 2]
    c00 = d * f - e * e
    c01 = c * e - bb * f
    c02 = bb * e - c * d
    c11 = a * f - c * c
    c12 = bb * c - a * e
    c22 = a * d - bb * bb
    inv_det = 1.0 / (a * c00 + bb * c01 + c * c02)
    out = np.empty_like(b)
    out[0] = (c00 * b[0] + c01 * b[1] + c02 * b[2]) * inv_det
    out[1] = (c01 * b[0] + c11 * b[1] + c12 * b[2]) * inv_det
    out[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) * inv_det
    return out


def _cross_gram(r: np.ndarray, damping2) -> np.ndarray:
    """(3, 3, F) ``J Jᵀ + λ²I`` for J = -[r]x (turning about a point moves a point r away from it):
    ``|r|² I - r rᵀ + λ² I``."""
    m = -r[:, None, :] * r[None, :, :]
    diag = cq.dot(r, r) + damping2
    m[0, 0] += diag
    m[1, 1] += diag
    m[2, 2] += diag
    return m


def aim(
    pivot: np.ndarray,
    point: np.ndarray,
    goal: np.ndarray,
    pull: np.ndarray,
    *,
    iterations: int = 4,
    damping: float = 0.01,
    nullspace_gain: float = 0.5,
) -> tuple[np.ndarray, np.ndarray]:
    """Turn ``point`` (3, F) about ``pivot`` (3, F) toward ``goal`` (3, F).

    ``pull`` (4, F) is the world rotation already applied to this segment since the transferred
    pose; the null-space term turns it back, so the roll about the pivot-point axis stays as
    transferred. Returns the world rotation (4, F) to apply and the new point (3, F).
    """
    offset = point - pivot
    length = float(np.median(cq.norm(offset)))
    lam2 = (damping * max(length, 1e-9)) ** 2
    q = np.zeros((4, offset.shape[1]))
    q[3] = 1.0
    for _ in range(iterations):
        r = cq.rotate(q, offset)
        err = goal - (pivot + r)
        dz = -nullspace_gain * cq.log(cq.mul(q, pull))
        y = solve_sym3(_cross_gram(r, lam2), err - cq.cross(dz, r))
        q = cq.normalize(cq.mul(cq.exp(cq.cross(r, y) + dz), q))
    return q, pivot + cq.rotate(q, offset)
