"""Jacobian pseudo-inverse IK for limbs, every frame at once.

The paper's update, ``ΔΘ = J⁺Δx + (I − J⁺J)Δz``, solved damped (``J⁺ = Jᵀ(JJᵀ + λ²I)⁻¹``) and
warm-started from the transferred pose, which is also the null-space target ``z``: the limb moves
only as much as the goal needs and otherwise stays as transferred. Arrays are (F, ...) over frames,
and each iteration is a handful of numpy operations on all frames; there is no per-frame loop.

A limb is two bones, root joint ``R`` (hip, shoulder; 3 rotational degrees of freedom, world axes)
and middle joint ``M`` (knee, elbow; a hinge about an axis given per frame) driving the end ``E``
(ankle, wrist). A second stage turns the end joint (3 degrees of freedom) to bring the next point
(the ball of the foot) to its goal, with the transferred orientation as its null-space target.
Results are world rotations to apply to the limb's segments.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat

#: Residual (metres) below which a goal counts as met; iterations stop once every frame is there.
TOLERANCE = 1e-5
#: Largest rotation (radians) of one IK iteration.
MAX_STEP = 0.4


def solve_sym3(m: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve (F, 3, 3) symmetric positive-definite systems ``m x = b`` (F, 3) by the adjugate."""
    a, d, f = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    bb, c, e = m[:, 0, 1], m[:, 0, 2], m[:, 1, 2]
    c00 = d * f - e * e
    c01 = c * e - bb * f
    c02 = bb * e - c * d
    c11 = a * f - c * c
    c12 = bb * c - a * e
    c22 = a * d - bb * bb
    det = a * c00 + bb * c01 + c * c02
    x0 = c00 * b[:, 0] + c01 * b[:, 1] + c02 * b[:, 2]
    x1 = c01 * b[:, 0] + c11 * b[:, 1] + c12 * b[:, 2]
    x2 = c02 * b[:, 0] + c12 * b[:, 1] + c22 * b[:, 2]
    return np.stack((x0, x1, x2), axis=1) / det[:, None]


def _cross_gram(r: np.ndarray, damping2) -> np.ndarray:
    """(F, 3, 3) ``J Jᵀ + λ²I`` for J = -[r]x (a rotation about a point moving the point r away):
    ``|r|² I - r rᵀ + λ² I``."""
    m = -r[:, :, None] * r[:, None, :]
    diag = np.sum(r * r, axis=1) + np.reshape(damping2, (-1,))
    m[:, 0, 0] += diag
    m[:, 1, 1] += diag
    m[:, 2, 2] += diag
    return m


def _exp(omega: np.ndarray) -> np.ndarray:
    """Unit quaternions (F, 4) of rotation vectors (F, 3) (small or not)."""
    angle = np.linalg.norm(omega, axis=1)
    half = 0.5 * angle
    k = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-300), 0.5)
    return np.concatenate((omega * k[:, None], np.cos(half)[:, None]), axis=1)


def _log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (F, 3) of unit quaternions (F, 4), angle in [0, pi]."""
    q = quat.canonical_sign(q)
    s = np.linalg.norm(q[:, :3], axis=1)
    angle = 2.0 * np.arctan2(s, q[:, 3])
    k = np.where(s > 1e-12, angle / np.maximum(s, 1e-300), 2.0)
    return q[:, :3] * k[:, None]


@dataclass
class LimbSolution:
    """World rotations (F, 4) for the segments of a limb, and how close the end came.

    ``root``: applied to everything below the root joint; ``middle``: applied, after ``root``, to
    everything below the middle joint; ``end_position`` (F, 3) where the end joint ends up;
    ``residual`` (F,) its distance from the goal, metres.
    """

    root: np.ndarray
    middle: np.ndarray
    end_position: np.ndarray
    residual: np.ndarray


def hinge_axes(root: np.ndarray, middle: np.ndarray, end: np.ndarray, reference_axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge axes (F, 3) and flexion angles (F,) of a two-bone limb.

    A clearly bent limb bends about its own plane's normal; a nearly straight one about
    ``reference_axis`` (F, 3) (the canonical hinge carried by the joint's motion), made
    perpendicular to the upper bone; in between the two are blended. The normal's sign follows the
    reference, so flexion is positive for a limb bent the natural way.
    """
    u = middle - root
    v = end - middle
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)
    vn = v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)
    n = np.cross(u, vn)
    sin_bend = np.linalg.norm(n, axis=1)
    ref = reference_axis - np.sum(reference_axis * u, axis=1, keepdims=True) * u
    ref /= np.maximum(np.linalg.norm(ref, axis=1, keepdims=True), 1e-12)
    n = np.where((np.sum(n * ref, axis=1) < 0.0)[:, None], -n, n)
    n /= np.maximum(sin_bend, 1e-12)[:, None]
    w = np.clip((sin_bend - 0.03) / 0.07, 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)
    axis = w[:, None] * n + (1.0 - w[:, None]) * ref
    axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-12)
    flexion = np.arctan2(np.sum(axis * np.cross(u, vn), axis=1), np.sum(u * vn, axis=1))
    return axis, flexion


def solve_limb(
    root: np.ndarray,
    middle: np.ndarray,
    end: np.ndarray,
    goal: np.ndarray,
    hinge: np.ndarray,
    flexion: np.ndarray,
    *,
    iterations: int = 12,
    damping: float = 0.01,
    nullspace_gain: float = 0.5,
    min_flexion: float = np.radians(1.0),
) -> LimbSolution:
    """Bring the limb end (F, 3) to ``goal`` (F, 3) by turning the root joint and bending the hinge.

    Positions are world metres of the transferred pose; ``hinge`` (F, 3) and ``flexion`` (F,) come
    from :func:`hinge_axes`. ``damping`` is λ as a fraction of the limb length. The hinge never
    straightens past ``min_flexion`` radians (no hyperextension), but a limb already straighter
    than that is not forced to bend.
    """
    upper = middle - root
    lower = end - middle
    a = np.linalg.norm(upper, axis=1)
    b = np.linalg.norm(lower, axis=1)
    length = float(np.median(a + b))
    lam2 = (damping * max(length, 1e-9)) ** 2
    q_root = quat.identity((len(root),))
    theta_min = np.minimum(0.0, min_flexion - flexion)
    # A goal out of reach is moved onto the reachable shell: the limb stretches toward it instead
    # of swinging about a singular, straight pose.
    straightest = np.minimum(flexion, min_flexion)
    far = np.sqrt(a * a + b * b + 2.0 * a * b * np.cos(straightest)) * (1.0 - 1e-6)
    near = np.abs(a - b) * (1.0 + 1e-6)
    offset = goal - root
    dist = np.linalg.norm(offset, axis=1)
    reachable_goal = root + offset * (np.clip(dist, near, far) / np.maximum(dist, 1e-12))[:, None]
    # Warm start: bend the hinge to the flexion the goal distance needs (law of cosines), so the
    # iterations start away from the straight-limb singularity and only have to turn the root.
    cos_needed = (np.clip(dist, near, far) ** 2 - a * a - b * b) / np.maximum(2.0 * a * b, 1e-12)
    theta = np.maximum(np.arccos(np.clip(cos_needed, -1.0, 1.0)) - flexion, theta_min)
    theta_start = theta.copy()
    for step in range(iterations + 1):
        m_pos = root + quat.rotate(q_root, upper)
        h = quat.rotate(q_root, hinge)
        q_mid = quat.from_axis_angle(h, theta)
        e_pos = m_pos + quat.rotate(quat.multiply(q_mid, q_root), lower)
        err = reachable_goal - e_pos
        if step == iterations or np.linalg.norm(err, axis=1).max() < TOLERANCE:
            break
        r = e_pos - root
        j_hinge = np.cross(h, e_pos - m_pos)
        # Damping fades as the goal nears, so the null-space pull does not hold the end off it.
        fade = np.clip(np.linalg.norm(err, axis=1) / (0.05 * max(length, 1e-9)), 1e-3, 1.0)
        gram = _cross_gram(r, lam2 * fade[:, None]) + j_hinge[:, :, None] * j_hinge[:, None, :]
        dz_rot = -nullspace_gain * _log(q_root)
        dz_hinge = -nullspace_gain * (theta - theta_start)  # the goal distance fixes the bend
        # One solve gives both terms: J⁺(e - J dz) + dz = J⁺e + (I - J⁺J) dz.
        j_dz = np.cross(dz_rot, r) + j_hinge * dz_hinge[:, None]
        y = solve_sym3(gram, err - j_dz)
        d_rot = np.cross(r, y) + dz_rot
        d_hinge = np.sum(j_hinge * y, axis=1) + dz_hinge
        # Linearization holds for small steps only: cap each step at MAX_STEP radians.
        size = np.maximum(np.linalg.norm(d_rot, axis=1), np.abs(d_hinge))
        cap = np.minimum(1.0, MAX_STEP / np.maximum(size, 1e-12))
        d_rot *= cap[:, None]
        d_hinge *= cap
        q_root = quat.normalize(quat.multiply(_exp(d_rot), q_root))
        theta = np.maximum(theta + d_hinge, theta_min)
    return LimbSolution(q_root, quat.multiply(q_mid, q_root), e_pos, np.linalg.norm(goal - e_pos, axis=1))


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
    """Turn ``point`` (F, 3) about ``pivot`` (F, 3) toward ``goal`` (F, 3).

    ``pull`` (F, 4) is the world rotation already applied to this segment since the transferred
    pose; the null-space term turns it back (the roll about the pivot-point axis stays as
    transferred). Returns the world rotation (F, 4) to apply and the new point (F, 3).
    """
    offset = point - pivot
    length = float(np.median(np.linalg.norm(offset, axis=1)))
    lam2 = (damping * max(length, 1e-9)) ** 2
    q = quat.identity((len(pivot),))
    for _ in range(iterations):
        r = quat.rotate(q, offset)
        err = goal - (pivot + r)
        dz = -nullspace_gain * _log(quat.multiply(q, pull))
        y = solve_sym3(_cross_gram(r, lam2), err - np.cross(dz, r))
        q = quat.normalize(quat.multiply(_exp(np.cross(r, y) + dz), q))
    return q, pivot + quat.rotate(q, offset)
