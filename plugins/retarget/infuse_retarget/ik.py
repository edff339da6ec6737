"""Jacobian pseudo-inverse IK for limbs, every frame at once.

The paper's update, ``ΔΘ = J⁺Δx + (I − J⁺J)Δz``, solved damped (``J⁺ = Jᵀ(JJᵀ + λ²I)⁻¹``) and
warm-started, with the transferred pose as the null-space target ``z``: the limb moves only as much
as the goal needs and otherwise stays as transferred. Arrays are component-major over frames,
(3, F) vectors and (4, F) quaternions (see :mod:`.cq`); each iteration is a handful of numpy
operations on all frames, with no per-frame loop.

A limb is two bones: root joint ``R`` (hip, shoulder; 3 rotational degrees of freedom about world
axes) and middle joint ``M`` (knee, elbow; a hinge about an axis given per frame) driving the end
``E`` (ankle, wrist). :func:`aim` then turns the end joint (3 degrees of freedom) to bring the next
point (the ball of the foot) to its goal, with the transferred orientation as its null-space target.
Results are world rotations to apply to the limb's segments.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import cq

#: Residual (metres) below which a goal counts as met; iterations stop once every frame is there.
TOLERANCE = 1e-5
#: Largest rotation (radians) of one IK iteration: the linearization holds for small steps only.
MAX_STEP = 0.4
#: Margin (metres) inside a limb's reach for a goal to count as reachable.
REACH_MARGIN = 5e-4


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


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(cq.norm(v), 1e-12)


@dataclass
class LimbSolution:
    """World rotations (4, F) for the segments of a limb, and how close the end came.

    ``root``: applied to everything below the root joint; ``middle``: applied, instead, to
    everything below the middle joint (it includes ``root``); ``end_position`` (3, F) where the
    end joint ends up; ``residual`` (F,) its distance from the goal, metres; ``reachable`` (F,)
    whether the goal lay inside the limb's reach by at least :data:`REACH_MARGIN`.
    """

    root: np.ndarray
    middle: np.ndarray
    end_position: np.ndarray
    residual: np.ndarray
    reachable: np.ndarray


def hinge_axes(root: np.ndarray, middle: np.ndarray, end: np.ndarray, reference_axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge axes (3, F) and flexion angles (F,) of a two-bone limb.

    A clearly bent limb bends about its own plane's normal; a nearly straight one about
    ``reference_axis`` (3, F) (the canonical hinge carried by the joint's motion), made
    perpendicular to the upper bone; in between the two are blended. The normal's sign follows the
    reference, so flexion is positive for a limb bent the natural way.
    """
    u = _unit(middle - root)
    v = _unit(end - middle)
    n = cq.cross(u, v)
    sin_bend = cq.norm(n)
    ref = _unit(reference_axis - cq.dot(reference_axis, u) * u)
    n = np.where(cq.dot(n, ref) < 0.0, -n, n) / np.maximum(sin_bend, 1e-12)
    w = np.clip((sin_bend - 0.03) / 0.07, 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)
    axis = _unit(w * n + (1.0 - w) * ref)
    flexion = np.arctan2(cq.dot(axis, cq.cross(u, v)), cq.dot(u, v))
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
    """Bring the limb end (3, F) to ``goal`` (3, F) by turning the root joint and bending the hinge.

    Positions are world metres of the transferred pose; ``hinge`` (3, F) and ``flexion`` (F,) come
    from :func:`hinge_axes`. ``damping`` is λ as a fraction of the limb length (it fades as the end
    nears the goal, so the null-space pull cannot hold it off). The hinge never straightens past
    ``min_flexion`` radians (no hyperextension), but a limb already straighter is not forced to bend.
    A goal out of reach is moved onto the reachable shell, so the limb stretches toward it.
    """
    upper = middle - root
    lower = end - middle
    a = cq.norm(upper)
    b = cq.norm(lower)
    length = float(np.median(a + b))
    lam2 = (damping * max(length, 1e-9)) ** 2
    theta_min = np.minimum(0.0, min_flexion - flexion)
    # The hinge can reach any flexion from min(flexion, min_flexion) up: the straightest is that
    # bound, or fully straight when the bound lies below zero (a limb bent against its hinge).
    straightest = np.maximum(np.minimum(flexion, min_flexion), 0.0)
    far = np.sqrt(a * a + b * b + 2.0 * a * b * np.cos(straightest)) * (1.0 - 1e-6)
    near = np.abs(a - b) * (1.0 + 1e-6)
    offset = goal - root
    dist = cq.norm(offset)
    reachable = (dist <= far - REACH_MARGIN) & (dist >= near + REACH_MARGIN)
    reach = np.clip(dist, near, far)
    target = root + offset * (reach / np.maximum(dist, 1e-12))
    # Warm start: bend the hinge to the flexion the goal distance needs (law of cosines), so the
    # iterations start away from the straight-limb singularity and mostly turn the root.
    cos_needed = (reach * reach - a * a - b * b) / np.maximum(2.0 * a * b, 1e-12)
    theta = np.maximum(np.arccos(np.clip(cos_needed, -1.0, 1.0)) - flexion, theta_min)
    theta_start = theta.copy()
    q_root = np.zeros((4, len(dist)))
    q_root[3] = 1.0
    for step in range(iterations + 1):
        m_pos = root + cq.rotate(q_root, upper)
        h = cq.rotate(q_root, hinge)
        q_mid = cq.from_axis_angle(h, theta)
        e_pos = m_pos + cq.rotate(cq.mul(q_mid, q_root), lower)
        err = target - e_pos
        err_norm = cq.norm(err)
        if step == iterations or err_norm.max() < TOLERANCE:
            break
        r = e_pos - root
        j_hinge = cq.cross(h, e_pos - m_pos)
        fade = np.clip(err_norm / (0.05 * max(length, 1e-9)), 1e-3, 1.0)
        gram = _cross_gram(r, lam2 * fade) + j_hinge[:, None, :] * j_hinge[None, :, :]
        dz_rot = -nullspace_gain * cq.log(q_root)
        dz_hinge = -nullspace_gain * (theta - theta_start)  # the goal distance fixes the bend
        # One solve gives both terms: J⁺(e - J dz) + dz = J⁺e + (I - J⁺J) dz.
        y = solve_sym3(gram, err - cq.cross(dz_rot, r) - j_hinge * dz_hinge)
        d_rot = cq.cross(r, y) + dz_rot
        d_hinge = cq.dot(j_hinge, y) + dz_hinge
        cap = np.minimum(1.0, MAX_STEP / np.maximum(np.maximum(cq.norm(d_rot), np.abs(d_hinge)), 1e-12))
        q_root = cq.normalize(cq.mul(cq.exp(d_rot * cap), q_root))
        theta = np.maximum(theta + d_hinge * cap, theta_min)
    return LimbSolution(q_root, cq.mul(q_mid, q_root), e_pos, cq.norm(goal - e_pos), reachable)


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
