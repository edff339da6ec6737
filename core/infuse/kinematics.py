"""Forward kinematics, vectorized over frames and over all joints of one depth at a time.

Global rotation of joint j: G_j = G_parent * L_j. Global position: P_j = P_parent + G_parent · t_j,
with t_j the joint's local translation (metres) and quaternions (x, y, z, w).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from . import quaternions as quat
from .motion import Motion
from .skeleton import Skeleton


def forward_kinematics(
    skeleton: Skeleton,
    local_rotations: np.ndarray,
    root_translations: np.ndarray,
    joint_translations: np.ndarray | None = None,
    *,
    joint_major: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (F, J, 4) and positions (F, J, 3) for every frame at once.

    ``local_rotations`` is (F, J, 4); ``root_translations`` (F, 3) is joint 0's local translation;
    ``joint_translations`` (F, J, 3), if given, replaces the rest offsets of the other joints.
    Roots other than joint 0 keep their rest translation unless ``joint_translations`` is given.
    With ``joint_major`` the results come in the internal layout, (J, 4, F) and (J, 3, F): one
    joint's components over all frames are contiguous rows (no final transpose).
    """
    local_rotations = np.asarray(local_rotations, dtype=np.float64)
    frames = local_rotations.shape[0]
    j = skeleton.num_joints
    # Work joint-major and component-major, (J, 4, F): a joint's x, y, z, w over all frames are
    # contiguous rows, so gathering a depth level's parents copies whole blocks and every product
    # below runs on long contiguous vectors.
    lr = np.ascontiguousarray(local_rotations.transpose(1, 2, 0))
    if joint_translations is None:
        tr = skeleton.rest_translations[:, :, None]  # (J, 3, 1), broadcast over frames
    else:
        tr = np.ascontiguousarray(np.asarray(joint_translations, dtype=np.float64).transpose(1, 2, 0))
    g_rot = np.empty((j, 4, frames))
    g_pos = np.empty((j, 3, frames))
    levels = skeleton.levels
    roots = levels[0]
    g_rot[roots] = lr[roots]
    g_pos[roots] = tr[roots]
    g_pos[0] = np.asarray(root_translations, dtype=np.float64).T
    parents = skeleton.parents
    for idx in levels[1:]:
        par = parents[idx]
        q = g_rot[par]
        x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
        b = lr[idx]
        bx, by, bz, bw = b[:, 0], b[:, 1], b[:, 2], b[:, 3]
        out = np.empty((len(idx), 4, frames))
        out[:, 0] = w * bx + x * bw + y * bz - z * by
        out[:, 1] = w * by - x * bz + y * bw + z * bx
        out[:, 2] = w * bz + x * by - y * bx + z * bw
        out[:, 3] = w * bw - x * bx - y * by - z * bz
        g_rot[idx] = out
        # Parent rotation applied to the offset v: v + w c + u x c, with c = 2 (u x v).
        t = tr[idx]
        vx, vy, vz = t[:, 0], t[:, 1], t[:, 2]
        cx = 2.0 * (y * vz - z * vy)
        cy = 2.0 * (z * vx - x * vz)
        cz = 2.0 * (x * vy - y * vx)
        p = g_pos[par]
        pos = np.empty((len(idx), 3, frames))
        pos[:, 0] = p[:, 0] + vx + w * cx + (y * cz - z * cy)
        pos[:, 1] = p[:, 1] + vy + w * cy + (z * cx - x * cz)
        pos[:, 2] = p[:, 2] + vz + w * cz + (x * cy - y * cx)
        g_pos[idx] = pos
    if joint_major:
        return g_rot, g_pos
    return np.ascontiguousarray(g_rot.transpose(2, 0, 1)), np.ascontiguousarray(g_pos.transpose(2, 0, 1))


def motion_fk(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """:func:`forward_kinematics` of a :class:`Motion`."""
    return forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)


def batch_fk(motions: Sequence[Motion]) -> list[tuple[np.ndarray, np.ndarray]]:
    """FK of many clips sharing one skeleton, computed as one batch of concatenated frames."""
    if not motions:
        return []
    skeleton = motions[0].skeleton
    if any(m.skeleton is not skeleton for m in motions):
        raise ValueError("batch_fk needs clips that share one Skeleton object")
    rots = np.concatenate([m.local_rotations for m in motions])
    roots = np.concatenate([m.root_translations for m in motions])
    jt = None
    if any(m.joint_translations is not None for m in motions):
        jt = np.concatenate([m.local_translations() for m in motions])
    g_rot, g_pos = forward_kinematics(skeleton, rots, roots, jt)
    bounds = np.cumsum([0] + [m.num_frames for m in motions])
    return [(g_rot[a:b], g_pos[a:b]) for a, b in zip(bounds[:-1], bounds[1:])]


def end_site_positions(skeleton: Skeleton, global_rotations: np.ndarray, global_positions: np.ndarray) -> np.ndarray:
    """(F, E, 3) global positions of the skeleton's end sites, from FK results."""
    p = skeleton.end_site_parents
    return global_positions[:, p] + quat.rotate(global_rotations[:, p], skeleton.end_site_offsets)
