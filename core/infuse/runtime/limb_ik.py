"""Two-joint limb IK on a character's own joints, vectorized over frames (legs for planted feet,
arms for reaches).

The limb is three joints a (hip, shoulder), b (knee, elbow), c (ankle, wrist) anywhere in the
hierarchy (twist joints between them are carried along). The interior angles at a and b are set by
the law of cosines so that c lands at the goal, the bend staying in the limb's current plane (or
toward ``pole`` when the limb is straight), and the end joint keeps its global rotation. Positions
are metres in the character's own frame; quaternions (x, y, z, w).
"""
from __future__ import annotations

import numpy as np

from .. import quaternions as quat
from .pose import chain_fk


# Small vector helpers over (F, 3) arrays: numpy's generic cross and norm cost more than the arithmetic.
_NEXT, _AFTER = [1, 2, 0], [2, 0, 1]


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", u, v)


def _norm(v: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(v, v))


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., _NEXT] * v[..., _AFTER] - u[..., _AFTER] * v[..., _NEXT]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(_norm(v), 1e-12)[..., None]


def _arccos(cosine: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(cosine, -1.0, 1.0))


def solve_limb(skeleton, local_rotations: np.ndarray, root_translations: np.ndarray, joint_translations,
               joints, goal: np.ndarray, weight=None, pole: np.ndarray | None = None,
               keep_end: bool = True) -> np.ndarray:
    """Rotate joints a and b of ``joints`` so that c reaches ``goal`` (F, 3); writes ``local_rotations``
    (F, J, 4) in place and returns the distance (F,) left to the goal (0 when within reach).

    ``weight`` (F,) in [0, 1] blends from the current pose to the solved one; ``pole`` (F, 3) or (3,)
    is the bend direction used when the limb is straight.

    Several limbs that do not hang from one another (left and right legs) are solved in one call
    with ``joints`` a sequence of K (a, b, c) triples: ``goal`` (F, K, 3), ``weight`` (F,) or (F, K),
    ``pole`` (3,), (F, 3) or (F, K, 3); the distances are then (F, K).
    """
    several = np.ndim(joints) == 2
    limbs = np.array(joints if several else [joints], dtype=np.int64).reshape(-1, 3)  # (K, 3)
    T = np.asarray(goal, dtype=np.float64)
    parents = skeleton.parents[limbs[:, 0]]
    hung = parents >= 0
    if hung.any() and not hung.all():  # a's parent rotation only where it has one: solved apart
        return np.stack([solve_limb(skeleton, local_rotations, root_translations, joint_translations, tuple(limb),
                                    T[:, k], _column(weight, k, 2), _column(pole, k, 3), keep_end)
                         for k, limb in enumerate(limbs)], axis=1)
    # Each limb's own chain FK (a few joints each): a solve of several gives each limb exactly what
    # solving it alone would. Arrays keep a limb axis only when there are several.
    chains = [chain_fk(skeleton, local_rotations, root_translations, joint_translations,
                       list(limb) + ([int(parent)] if hung.all() else [])) for limb, parent in zip(limbs, parents)]
    g_rot, g_pos = (np.stack(r, axis=1) for r in zip(*chains)) if several else chains[0]
    parent_rot = g_rot[..., 3, :] if hung.all() else None
    g_rot, g_pos = g_rot[..., :3, :], g_pos[..., :3, :]
    A, B, C = g_pos[..., 0, :], g_pos[..., 1, :], g_pos[..., 2, :]
    ab, cb, ca, ta = B - A, C - B, C - A, T - A
    lab, lcb, lca, lta = _norm(ab), _norm(cb), _norm(ca), _norm(ta)
    lat = np.clip(lta, np.abs(lab - lcb) + 1e-6, (lab + lcb) * (1.0 - 1e-6))
    u_ab, u_cb, u_ca, u_ta = (v / np.maximum(n, 1e-12)[..., None] for v, n in ((ab, lab), (cb, lcb), (ca, lca), (ta, lta)))
    ac_ab_0 = _arccos(_dot(u_ca, u_ab))
    ba_bc_0 = _arccos(-_dot(u_ab, u_cb))  # the angle at b, between b->a and b->c
    ac_at_0 = _arccos(_dot(u_ca, u_ta))
    ac_ab_1 = _arccos((lcb ** 2 - lab ** 2 - lat ** 2) / (-2.0 * lab * lat))
    ba_bc_1 = _arccos((lat ** 2 - lab ** 2 - lcb ** 2) / (-2.0 * lab * lcb))
    axis1 = _cross(ca, ta)
    small = _norm(axis1) < 1e-12
    axis0 = _cross(ca, ab)
    flat = _norm(axis0) < 1e-6 * np.maximum(lab * lcb, 1e-12)
    if flat.any():  # a straight limb bends toward the pole, else toward the goal
        if pole is not None:
            pole = np.asarray(pole, dtype=np.float64)
            fallback = _cross(ca, np.broadcast_to(pole[:, None] if several and pole.ndim == 2 else pole, A.shape))
        else:
            other = _cross(ca, np.array([0.0, 1.0, 0.0]))
            fallback = np.where(small[..., None], other, axis1)
        axis0 = np.where(flat[..., None], fallback, axis0)
    axis0 = _unit(axis0)
    axis1 = _unit(np.where(small[..., None], axis0, axis1))
    ga_inv = quat.conjugate(g_rot[..., 0, :])
    gb_inv = quat.conjugate(g_rot[..., 1, :])
    r0 = quat.from_axis_angle(quat.rotate(ga_inv, axis0), ac_ab_1 - ac_ab_0)
    r1 = quat.from_axis_angle(quat.rotate(gb_inv, axis0), ba_bc_1 - ba_bc_0)
    r2 = quat.from_axis_angle(quat.rotate(ga_inv, axis1), ac_at_0)
    columns = limbs if several else limbs[0]
    old = local_rotations[:, columns[..., :2]]  # (F, [K,] 2, 4), a copy
    new_a = quat.multiply(old[..., 0, :], quat.multiply(r0, r2))
    new_b = quat.multiply(old[..., 1, :], r1)
    if weight is not None:  # both joints in one interpolation
        w = np.clip(np.asarray(weight, dtype=np.float64), 0.0, 1.0)
        w = w[:, None] if several and w.ndim == 1 else w
        new_a, new_b = np.moveaxis(quat.slerp(old, np.stack((new_a, new_b), axis=-2), w[..., None]), -2, 0)
    local_rotations[:, columns[..., 0]] = new_a
    local_rotations[:, columns[..., 1]] = new_b
    # Down from a's parent (which did not move) to c again: c's new parent rotation and position.
    rotation = new_a if parent_rot is None else quat.multiply(parent_rot, new_a)
    paths = [_path_below(skeleton, a, c) for a, _, c in limbs]
    if not several:
        position, rotation = _down(skeleton, local_rotations, joint_translations, paths[0], A, rotation)
    elif len({len(p) for p in paths}) == 1:  # all limbs step down together
        position, rotation = _down(skeleton, local_rotations, joint_translations, np.array(paths).T, A, rotation)
    else:
        ends = [_down(skeleton, local_rotations, joint_translations, p, A[:, i], rotation[:, i])
                for i, p in enumerate(paths)]
        position = np.stack([e[0] for e in ends], axis=1)
        rotation = np.stack([e[1] for e in ends], axis=1)
    if keep_end:
        local_rotations[:, columns[..., 2]] = quat.multiply(quat.conjugate(rotation), g_rot[..., 2, :])
    return _norm(position - T)


def _down(skeleton, local_rotations, joint_translations, steps, position, rotation):
    """Positions (F, [K,] 3) of the limbs' ends and their parents' global rotations (F, [K,] 4),
    stepping down ``steps`` (S, [K]) joints from the positions and global rotations above them."""
    for i, js in enumerate(steps):
        offset = skeleton.rest_translations[js] if joint_translations is None else joint_translations[:, js]
        position = position + quat.rotate(rotation, offset)
        if i < len(steps) - 1:
            rotation = quat.multiply(rotation, local_rotations[:, js])
    return position, rotation


def _column(values, k: int, ndim: int):
    """Limb ``k``'s part of a per-limb argument: None, shared by every limb, or ``ndim``-dimensional
    with the limb axis second."""
    if values is None:
        return None
    values = np.asarray(values, dtype=np.float64)
    return values[:, k] if values.ndim == ndim else values


def _path_below(skeleton, top: int, bottom: int) -> list[int]:
    """The joints from just below ``top`` down to ``bottom`` (a descendant of ``top``), in order."""
    path = []
    j = int(bottom)
    while j != top:
        if j < 0:
            raise ValueError(f"joint {bottom} is not below joint {top}")
        path.append(j)
        j = int(skeleton.parents[j])
    return path[::-1]
