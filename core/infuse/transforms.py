"""4x4 transform matrices: how readers of scene-graph formats (COLLADA, FBX, Ogre) reach the core model.

Those formats give each node a local matrix, possibly with scale, shear-free pivots and non-joint
parents. Readers compose them into global matrices, change the frame (units, up axis) once on the
globals, then keep only the joints: :func:`rigid_locals` turns global joint frames into the local
rotations and translations of :class:`~infuse.skeleton.Skeleton` and :class:`~infuse.motion.Motion`.
Scale is folded into translations (global positions stay exact), so the core needs no scale.

Matrices act on column vectors, translation in the last column: ``p' = M @ [p, 1]``.
Shapes: ``(..., 4, 4)`` with any leading axes (frames, nodes). Quaternions are (x, y, z, w).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from . import conventions
from .errors import InputError
from . import quaternions as quat
from .motion import Motion
from .skeleton import Skeleton


def compose(translations: np.ndarray, rotations: np.ndarray, scales: np.ndarray | None = None) -> np.ndarray:
    """``T · R · S`` matrices (..., 4, 4) from translations (..., 3), quaternions (..., 4), scales (..., 3)."""
    translations = np.asarray(translations, dtype=np.float64)
    rotations = np.asarray(rotations, dtype=np.float64)
    shape = np.broadcast_shapes(translations.shape[:-1], rotations.shape[:-1])
    out = np.zeros(shape + (4, 4))
    rot = quat.to_matrix(np.broadcast_to(rotations, shape + (4,)))
    if scales is not None:
        rot = rot * np.asarray(scales, dtype=np.float64)[..., None, :]
    out[..., :3, :3] = rot
    out[..., :3, 3] = translations
    out[..., 3, 3] = 1.0
    return out


def decompose(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Translations (..., 3), rotations (..., 4) and scales (..., 3) of affine matrices (..., 4, 4).

    The rotation is the nearest one to the 3x3 block (polar decomposition, so shear or
    non-uniform scale under rotation give the best rigid fit); a mirroring block yields a
    negative scale on one axis.
    """
    m = np.asarray(matrices, dtype=np.float64)
    block = m[..., :3, :3]
    # T·R·S blocks have orthogonal columns: dividing by their lengths gives R exactly. Only blocks
    # with shear (non-uniform scale under a rotated child) need the slower polar decomposition.
    det = np.einsum("...i,...i->...", block[..., :, 0], np.cross(block[..., :, 1], block[..., :, 2]))
    lengths = np.linalg.norm(block, axis=-2)
    lengths[..., 2] *= np.where(det < 0.0, -1.0, 1.0)
    safe = np.where(np.abs(lengths) > 1e-12, lengths, 1.0)
    rot = block / safe[..., None, :]
    skew = np.abs(np.swapaxes(rot, -1, -2) @ rot - np.eye(3)).max(axis=(-1, -2)) > 1e-6
    skew &= np.all(np.isfinite(block), axis=(-1, -2))  # non-finite blocks stay NaN for the callers' checks
    if np.any(skew):
        u, _, vt = np.linalg.svd(block[skew])
        flip = np.linalg.det(u @ vt) < 0.0
        u[flip, :, 2] *= -1.0
        rot[skew] = u @ vt
    scales = np.einsum("...ji,...ji->...i", rot, block)  # diagonal of R^T M, signed
    return m[..., :3, 3].copy(), quat.normalize(quat.from_matrix(rot)), scales


def global_matrices(parents: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Global matrices (F, N, 4, 4) from local ones, parents (N,) in topological order (-1 for roots).

    Vectorized over frames and over all nodes of one depth at a time.
    """
    parents = np.asarray(parents, dtype=np.int64)
    out = np.array(local, dtype=np.float64, copy=True)
    depth = np.zeros(len(parents), dtype=np.int64)
    for i, p in enumerate(parents):
        if p >= 0:
            depth[i] = depth[p] + 1
    for level in range(1, int(depth.max(initial=0)) + 1):
        idx = np.nonzero(depth == level)[0]
        out[..., idx, :, :] = out[..., parents[idx], :, :] @ out[..., idx, :, :]
    return out


def frame_change(scale: float, up_axis: str) -> np.ndarray:
    """The 4x4 matrix taking a file's coordinates (``scale`` metres per unit, ``up_axis`` up) to the core frame."""
    out = np.eye(4)
    out[:3, :3] = quat.to_matrix(conventions.UP_AXIS_ROTATIONS[up_axis]) * float(scale)
    return out


def rigid_locals(parents: np.ndarray, global_mats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations (..., J, 4) and translations (..., J, 3) of joints from their global matrices.

    ``parents`` (J,) indexes the joint set itself (-1: a root, whose local values are global).
    Each joint's frame is the rigid part of its global matrix; its translation is its global
    position seen from the parent joint's rigid frame, so scale and folded-away non-joint nodes
    end up in the translations and FK reproduces every global joint position exactly.
    """
    parents = np.asarray(parents, dtype=np.int64)
    pos, rot, _ = decompose(global_mats)
    has_parent = parents >= 0
    par = np.where(has_parent, parents, 0)
    par_rot = np.where(has_parent[:, None], rot[..., par, :], quat.IDENTITY)
    par_pos = np.where(has_parent[:, None], pos[..., par, :], 0.0)
    inv = quat.conjugate(par_rot)
    local_rot = quat.normalize(quat.multiply(inv, rot))
    local_trans = quat.rotate(inv, pos - par_pos)
    return local_rot, local_trans


def nearest_joint_parents(node_parents, joints, return_folded: bool = False):
    """Parent of each joint within ``joints`` (node indices): its nearest ancestor that is a joint, -1 for none.

    ``node_parents[n]`` is the parent node of node ``n`` (-1 for a scene root); intermediate non-joint
    nodes are skipped. With ``return_folded``, returns ``(parents, folded)``: ``folded`` holds the
    skipped nodes, sorted, i.e. every non-joint ancestor of a joint (nodes whose transforms the
    joints absorb, whose animation still moves them).
    """
    position = {n: j for j, n in enumerate(joints)}
    nearest: dict[int, int] = {}  # skipped node -> position of its nearest joint ancestor (-1: none)
    out = np.full(len(joints), -1, dtype=np.int64)
    for j, n in enumerate(joints):
        path = []
        p = node_parents[n]
        while p >= 0 and p not in position and p not in nearest:
            path.append(p)
            p = node_parents[p]
        found = -1 if p < 0 else position[p] if p in position else nearest[p]
        nearest.update(dict.fromkeys(path, found))
        out[j] = found
    if return_folded:
        return out, np.array(sorted(nearest), dtype=np.int64)
    return out


def require_finite(names, global_mats: np.ndarray, where: str = "rest pose") -> None:
    """Raise :class:`InputError` naming the first joint whose matrix (..., J, 4, 4) is not finite.

    Finite but huge file values can overflow once multiplied down a hierarchy; the file is named
    by :func:`infuse.fileio.load`.
    """
    bad = ~np.all(np.isfinite(global_mats), axis=(-1, -2))
    if np.any(bad):
        index = np.argwhere(bad)[0]
        frame = f" frame {index[0]}" if len(index) > 1 else ""
        raise InputError(None, f"{where}{frame} joint {names[index[-1]]!r}", "transform is not finite (values too large?)")


def skeleton_from_globals(names, parents, global_mats: np.ndarray) -> Skeleton:
    """A :class:`Skeleton` whose rest pose puts each joint at its global matrix (J, 4, 4), core frame."""
    require_finite(list(names), global_mats)
    rot, trans = rigid_locals(parents, global_mats)
    return Skeleton(names, parents, trans, quat.canonical_sign(rot))


def motion_from_globals(skeleton: Skeleton, fps: float, global_mats: np.ndarray, name: str = "",
                        tolerance: float = 1e-7) -> Motion:
    """A :class:`Motion` reproducing joint global matrices (F, J, 4, 4) given in the core frame.

    ``joint_translations`` is kept only when some joint other than the first root moves away
    from its rest offset by more than ``tolerance`` metres (animated translation or scale).
    """
    return sampled_motion(skeleton, fps, len(global_mats), lambda a, b: global_mats[a:b], name, tolerance)


def sampled_motion(skeleton: Skeleton, fps: float, frames: int, globals_between: Callable[[int, int], np.ndarray],
                   name: str = "", tolerance: float = 1e-7, chunk: int = 1024) -> Motion:
    """Like :func:`motion_from_globals`, asking ``globals_between(start, stop)`` for the (stop - start,
    J, 4, 4) core-frame globals of a few frames at a time, so long clips need little extra memory."""
    j = skeleton.num_joints
    rot, trans = np.empty((frames, j, 4)), np.empty((frames, j, 3))
    for a in range(0, frames, chunk):
        b = min(frames, a + chunk)
        mats = globals_between(a, b)
        require_finite(skeleton.names, mats, f"motion {name!r}")
        rot[a:b], trans[a:b] = rigid_locals(skeleton.parents, mats)
    rot = quat.make_continuous(rot, axis=0)
    moved = np.abs(trans[:, 1:] - skeleton.rest_translations[1:]).max(initial=0.0) > tolerance
    return Motion(skeleton, fps, rot, trans[:, 0], trans if moved else None, name=name)
