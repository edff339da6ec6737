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
) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (F, J, 4) and positions (F, J, 3) for every frame at once.

    ``local_rotations`` is (F, J, 4); ``root_translations`` (F, 3) is joint 0's local translation;
    ``joint_translations`` (F, J, 3), if given, replaces the rest offsets of the other joints.
    Roots other than joint 0 keep their rest translation unless ``joint_translations`` is given.
    """
    local_rotations = np.asarray(local_rotations, dtype=np.float64)
    frames = local_rotations.shape[0]
    j = skeleton.num_joints
    if joint_translations is None:
        trans = np.broadcast_to(skeleton.rest_translations, (frames, j, 3)).copy()
    else:
        trans = np.array(joint_translations, dtype=np.float64)
    trans[:, 0] = root_translations
    g_rot = np.empty((frames, j, 4))
    g_pos = np.empty((frames, j, 3))
    levels = skeleton.levels
    roots = levels[0]
    g_rot[:, roots] = local_rotations[:, roots]
    g_pos[:, roots] = trans[:, roots]
    parents = skeleton.parents
    for idx in levels[1:]:
        par_rot = g_rot[:, parents[idx]]
        g_rot[:, idx] = quat.multiply(par_rot, local_rotations[:, idx])
        g_pos[:, idx] = g_pos[:, parents[idx]] + quat.rotate(par_rot, trans[:, idx])
    return g_rot, g_pos


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
