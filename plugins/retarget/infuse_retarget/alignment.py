"""Default-pose alignment: the rotation that turns each mapped bone of a pose onto the canonical T-pose.

For a pose (global joint positions, usually the rest), :func:`align` gives every mapped canonical
joint ``c`` a world rotation ``A(c)`` such that the bone from ``c`` to its mapped children, turned
by ``A(c)``, points like the same bone of the canonical T-pose (:mod:`infuse.canonical`). As in the
paper it works recursively from the base: the base is matched as a whole frame (left from hip to
hip, up along the spine), then each joint starts from its mapped parent's rotation and adds the
shortest swing that lines its bone up, using the mean of its children's directions at branching
joints. Starting from the parent keeps bone roll anatomical (a bent knee straightens about its
hinge, a lowered arm rises about the body's forward axis); at a branching joint whose children
spread (fingers, neck and clavicles) the spread sets the roll exactly. Zero-length bones keep the
parent's rotation.

Some files keep an arbitrary rest (Bandai's lies along X with the real pose in the clip); a pose
whose legs and spine are far from upright after the base is matched is not a usable default pose,
and :func:`reference_frame` picks the most upright frame of a clip instead.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.canonical import canonical_joint

from .rig import canonical_children, canonical_parent

#: Joints tried, in order, for the top of the spine when building the body frame.
SPINE_TOPS = ("spine3", "spine4", "spine5", "skullbase", "spine2", "spine1")
#: Bones (joint, child) that must be near their canonical direction in a usable default pose.
UPRIGHT_BONES = (("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"))
#: Largest angle (degrees) between an upright bone and its canonical direction in a usable pose.
UPRIGHT_LIMIT_DEG = 50.0
#: Least spread (difference of unit directions) between two children of a joint that fixes its roll.
SPREAD = 0.2


def canonical_position(name: str) -> np.ndarray:
    return np.asarray(canonical_joint(name).position, dtype=np.float64)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _frame(left: np.ndarray, up: np.ndarray) -> np.ndarray:
    """(..., 3, 3) orthonormal frames with columns (left, up, forward), up kept exactly."""
    y = _unit(up)
    x = _unit(left - np.sum(left * y, axis=-1, keepdims=True) * y)
    z = np.cross(x, y)
    return np.stack((x, y, z), axis=-1)


def body_points(index: dict[str, int]) -> tuple[str, str, str]:
    """(left, right, top) canonical names that define the body frame of a mapping."""
    if "l_hip" in index and "r_hip" in index:
        left, right = "l_hip", "r_hip"
    elif "l_shoulder" in index and "r_shoulder" in index:
        left, right = "l_shoulder", "r_shoulder"
    else:
        raise KeyError("neither both hips nor both shoulders are mapped")
    top = next((n for n in SPINE_TOPS if n in index), None)
    if top is None:
        raise KeyError("no spine, neck or head joint is mapped")
    return left, right, top


def base_alignment(index: dict[str, int], positions: np.ndarray) -> np.ndarray:
    """(..., 4) rotation taking the body frame of ``positions`` (..., J, 3) to the canonical one."""
    left, right, top = body_points(index)
    pose = _frame(positions[..., index[left], :] - positions[..., index[right], :],
                  positions[..., index[top], :] - positions[..., index["base"], :])
    canon = _frame(canonical_position(left) - canonical_position(right), canonical_position(top) - canonical_position("base"))
    return quat.from_matrix(canon @ np.swapaxes(pose, -1, -2))


def align(index: dict[str, int], positions: np.ndarray) -> dict[str, np.ndarray]:
    """Canonical name -> (4,) world rotation aligning that bone of the pose ``positions`` (J, 3).

    ``index`` maps canonical names (table order, ``base`` included) to joint indices.
    """
    out = {"base": base_alignment(index, positions)}
    kids = canonical_children(index)
    scale = max(float(np.ptp(positions[list(index.values())], axis=0).max()), 1e-9)
    for name in index:
        if name == "base":
            continue
        parent = canonical_parent(name, index)
        carried = out[parent if parent is not None else "base"]
        here = positions[index[name]]
        pose_dirs, canon_dirs = [], []
        for child in kids[name]:
            v = positions[index[child]] - here
            if np.linalg.norm(v) > 1e-4 * scale:  # a zero-length bone has no direction
                pose_dirs.append(_unit(v))
                canon_dirs.append(_unit(canonical_position(child) - canonical_position(name)))
        out[name] = _bone_alignment(carried, np.array(pose_dirs).reshape(-1, 3), np.array(canon_dirs).reshape(-1, 3))
    return out


def _bone_alignment(carried: np.ndarray, pose_dirs: np.ndarray, canon_dirs: np.ndarray) -> np.ndarray:
    """Alignment of one joint from its children's unit directions in the pose and the T-pose.

    The mean direction is matched by the shortest swing from the parent's rotation ``carried``;
    where the children spread (a hand's fingers, a chest's clavicles) the line between the two
    children furthest apart fixes the roll as well.
    """
    u = pose_dirs.sum(axis=0)
    t = canon_dirs.sum(axis=0)
    if np.linalg.norm(u) < 1e-6 or np.linalg.norm(t) < 1e-6:
        return carried
    swing = quat.normalize(quat.multiply(quat.between(quat.rotate(carried, u), t), carried))
    if len(pose_dirs) < 2:
        return swing
    gaps = np.linalg.norm(canon_dirs[:, None] - canon_dirs[None], axis=-1)
    i, j = np.unravel_index(int(np.argmax(gaps)), gaps.shape)  # the two children furthest apart
    pose_side = pose_dirs[i] - pose_dirs[j]
    canon_side = canon_dirs[i] - canon_dirs[j]
    pose_side = pose_side - np.dot(pose_side, _unit(u)) * _unit(u)
    canon_side = canon_side - np.dot(canon_side, _unit(t)) * _unit(t)
    if np.linalg.norm(pose_side) < SPREAD or np.linalg.norm(canon_side) < SPREAD:
        return swing
    pose = _frame(pose_side, u)
    canon = _frame(canon_side, t)
    return quat.from_matrix(canon @ pose.T)


def upright_error(index: dict[str, int], positions: np.ndarray) -> np.ndarray:
    """(...,) worst angle in degrees between a leg bone of ``positions`` (..., J, 3), body frame
    matched, and its canonical direction (0 for a T-pose; about 180 for a rest lying along X)."""
    a = base_alignment(index, positions)
    worst = np.zeros(positions.shape[:-2])
    for p, c in UPRIGHT_BONES:
        if p not in index or c not in index:
            continue
        v = quat.rotate(a, positions[..., index[c], :] - positions[..., index[p], :])
        t = canonical_position(c) - canonical_position(p)
        cos = np.sum(_unit(v) * _unit(t), axis=-1)
        worst = np.maximum(worst, np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return worst


def reference_frame(index: dict[str, int], frame_positions: np.ndarray) -> int:
    """The frame of (F, J, 3) global positions whose legs are nearest their canonical directions."""
    return int(np.argmin(upright_error(index, frame_positions)))
