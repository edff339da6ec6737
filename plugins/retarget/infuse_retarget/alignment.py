"""Default-pose alignment: the rotation that turns each mapped bone of a pose onto the canonical T-pose.

For a default pose (global joint positions), :func:`align` gives every mapped canonical joint ``c``
a world rotation ``A(c)``, the paper's turn of the default pose onto the canonical one. It works
recursively from the base, which is matched as a whole frame (left from hip to hip, up along the
spine). A joint's bones in a default pose carry two things: pose (where a T-pose puts the arms and
an A-pose lowers them) and build (where the rig puts its joints). Only pose is turned away:

- **Limbs** (:data:`SWUNG`: shoulder to fingertips, hip to ankle) point where the pose puts them.
  Each joint starts from its mapped parent's rotation and adds the shortest swing that lines its
  bone up with the canonical bone, using the mean of its children's directions at a branching
  joint. Starting from the parent keeps bone roll anatomical (a bent knee straightens about its
  hinge, a lowered arm rises about the body's forward axis); where the children spread (a hand's
  fingers) the spread sets the roll exactly. A wrist goes by its four fingers' knuckles, not by the
  thumb, whose base sits wherever the build puts it.
- **Trunk, neck, head and shoulder girdle** (:data:`HELD`) are at rest in every default pose
  (upright, looking ahead, shoulders relaxed); their bones point where the build puts the joints:
  how the spine curves, how far the neck leans, where the two clavicle joints sit. Across the
  labelled rigs standing in T- and A-poses alike, the girdle's slope (its first joint to the
  shoulder) spreads over 17° (standard deviation) and does not follow the arms' (correlation 0.1).
  These joints keep their parent's rotation: a motion moves them from the target's own build,
  except for a twist of the chest against the pelvis about the body's up, which is pose
  (:func:`_trunk_twist`): the spine joints below the girdle share the turn that squares the
  shoulder line to the hip line.
  Lining their short bones up one by one turns them from rest by as much as two builds differ:
  SmartBody's Brad, whose clavicle joints dip 36° and then rise 27° where Utah's rise 20° and then
  run flat, had his acromioclavicular turned by 71° and his shoulders raised 4 cm by a Utah walk.
- **Feet** (:data:`FEET`) stand flat; how steeply the ankle looks down at the ball is the build's
  ankle height (from level to 63° below among the labelled rigs). A flat foot is only turned about
  the vertical, to head the canonical way, and its toes follow it.
- **Base**: in a standing rest the world's up is the pose's, so the base is only turned about the
  vertical (:func:`_level`); how far its pelvis-to-chest line leans is build too.

That holds for a default pose that is the rig's standing rest (:func:`standing`). Some files keep
an arbitrary rest (Bandai's lies along X with the real pose in the clip): a pose whose legs and
spine are far from upright once the base is matched is not a usable default pose, and
:func:`reference_frame` picks the most upright frame of a clip instead, which :mod:`.prepare` sets
at rest (the held joints at their mean over the clip, the feet laid flat as they are while planted).
Its base keeps the whole body frame: a clip frame may lean. A rest that does not stand, with no clip
to replace it, has every bone lined up, as in the paper. Zero-length bones have no direction: a
joint whose bones all have zero length keeps its parent's rotation.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.canonical import ALL_NAMES, canonical_joint

from .rig import canonical_children, canonical_parent

#: Joints tried, in order, for the top of the spine when building the body frame.
SPINE_TOPS = ("spine3", "spine4", "spine5", "skullbase", "spine2", "spine1")
#: Bones (joint, child) that must be near their canonical direction in a usable default pose.
UPRIGHT_BONES = (("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"))
#: Largest angle (degrees) between an upright bone and its canonical direction in a usable pose.
UPRIGHT_LIMIT_DEG = 50.0
#: Least spread (difference of unit directions) between two children of a joint that fixes its roll.
SPREAD = 0.2
#: Canonical joints whose bones a default pose sets, lined up bone by bone: the limbs.
SWUNG = frozenset(n for n in ALL_NAMES if canonical_joint(n).group in ("hand", "leg")
                  or n.endswith(("_shoulder", "_elbow", "_forearm", "_wrist")))
#: Canonical joints every default pose holds at rest, placed by the rig's build: the trunk above the
#: base, the neck, head and eyes, and the shoulder girdle.
HELD = frozenset(n for n in ALL_NAMES if n != "base" and n not in SWUNG and canonical_joint(n).group != "foot")
#: Ankles: a foot standing flat in a default pose has only its heading matched (its toes follow).
FEET = ("l_ankle", "r_ankle")
#: Largest tilt (degrees) of a pose's body frame from the world's up for the pose to count as
#: standing (a rest read with the wrong up axis stands on its side).
STANDING_TILT_DEG = 30.0


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


def standing(index: dict[str, int], positions: np.ndarray) -> bool:
    """Whether ``positions`` (J, 3) stand: legs near their canonical directions once the body frame
    is matched, and that frame's up within :data:`STANDING_TILT_DEG` of the world's."""
    up = quat.rotate(base_alignment(index, positions), np.array([0.0, 1.0, 0.0]))
    return bool(upright_error(index, positions) <= UPRIGHT_LIMIT_DEG and up[1] >= np.cos(np.radians(STANDING_TILT_DEG)))


def align(index: dict[str, int], positions: np.ndarray, *, at_rest: bool = False, level: bool = False,
          flat_feet=()) -> dict[str, np.ndarray]:
    """Canonical name -> (4,) world rotation aligning that bone of the pose ``positions`` (J, 3).

    ``index`` maps canonical names (table order, ``base`` included) to joint indices. ``at_rest``:
    the pose holds the trunk, neck, head and girdle at rest; ``level``: its up is the world's (a
    standing rest, :func:`standing`); ``flat_feet``: the ankles (``l_ankle``, ``r_ankle``) whose
    feet stand flat in it. Without them every bone is lined up, as in the paper (see the module
    docstring).
    """
    body = base_alignment(index, positions)
    out = {"base": _level(body) if level else body}
    flat = set(flat_feet)
    kids = canonical_children(index)
    scale = max(float(np.ptp(positions[list(index.values())], axis=0).max()), 1e-9)
    twist = _trunk_twist(index, positions, out["base"]) if at_rest else {}
    for name in index:
        if name == "base":
            continue
        parent = canonical_parent(name, index)
        carried = out[parent if parent is not None else "base"]
        toes_of_flat_foot = canonical_joint(name).group == "foot" and f"{name[0]}_ankle" in flat
        if name in twist:
            out[name] = quat.normalize(quat.multiply(twist[name], carried))
            continue
        if (at_rest and name in HELD) or toes_of_flat_foot:
            out[name] = carried
            continue
        here = positions[index[name]]
        pose_dirs, canon_dirs = [], []
        for child in _aims(kids[name]):
            v = positions[index[child]] - here
            if np.linalg.norm(v) > 1e-4 * scale:  # a zero-length bone has no direction
                pose_dirs.append(_unit(v))
                canon_dirs.append(_unit(canonical_position(child) - canonical_position(name)))
        pose_dirs, canon_dirs = np.array(pose_dirs).reshape(-1, 3), np.array(canon_dirs).reshape(-1, 3)
        if name in flat:
            out[name] = _heading(_level(body), pose_dirs, canon_dirs)
        else:
            out[name] = _bone_alignment(carried, pose_dirs, canon_dirs)
    return out


def _trunk_twist(index: dict[str, int], positions: np.ndarray, base: np.ndarray) -> dict[str, np.ndarray]:
    """The turn about the body's up that each trunk joint below the shoulder girdle adds to its
    parent's alignment so that the shoulder line of ``positions`` (J, 3) lies square to the hip line.

    A rest twisting the chest against the pelvis about the vertical (a combat stance, feet staggered
    and pelvis turned; a dance clip's mean posture) holds that twist as pose, not build: kept, it
    turned a walk's chest 30 degrees off its source's under every frame. The twist is shared evenly
    by the mapped spine joints from the pelvis up to the joint the arms hang from. ``base``: the
    base's alignment. Empty when the hips or shoulders are not both mapped."""
    if not all(n in index for n in ("l_hip", "r_hip", "l_shoulder", "r_shoulder")):
        return {}
    top = canonical_parent("l_shoulder", index)
    while top is not None and canonical_joint(top).group != "torso":
        top = canonical_parent(top, index)
    chain = []
    while top is not None and top != "base":
        chain.append(top)
        top = canonical_parent(top, index)
    if not chain:
        return {}
    line = quat.rotate(base, positions[index["l_shoulder"]] - positions[index["r_shoulder"]]) * (1.0, 0.0, 1.0)
    square = (canonical_position("l_shoulder") - canonical_position("r_shoulder")) * (1.0, 0.0, 1.0)
    if np.linalg.norm(line) < 1e-9 or np.linalg.norm(square) < 1e-9:
        return {}
    angle = float(np.arctan2(np.cross(line, square)[1], np.dot(line, square)))
    share = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), angle / len(chain))
    return {name: share for name in chain}


def _aims(children: list[str]) -> list[str]:
    """The children whose directions align a joint: at a wrist the fingers' knuckles when any is
    mapped, not the thumb, whose base sits where the build puts it."""
    fingers = [c for c in children if canonical_joint(c).group == "hand" and "thumb" not in c]
    return fingers or children


def _level(body: np.ndarray) -> np.ndarray:
    """The body frame's turn ``body`` without its tilt: the world's up stays up. In a standing rest
    the world's up is the pose's; how far the pelvis-to-chest line leans is build (X Bot's and the
    Rocketbox robot's lean 5° to 6° back, Utah's stands straight)."""
    up = quat.rotate(body, np.array([0.0, 1.0, 0.0]))
    return quat.normalize(quat.multiply(quat.between(up, np.array([0.0, 1.0, 0.0])), body))


def _heading(level: np.ndarray, pose_dirs: np.ndarray, canon_dirs: np.ndarray) -> np.ndarray:
    """A flat foot's alignment: the body's level turn ``level`` turned about the vertical so the
    foot's children, seen from above, head like the canonical foot's; the foot keeps its pitch and
    roll, flat on the ground."""
    u = quat.rotate(level, pose_dirs.sum(axis=0)) * (1.0, 0.0, 1.0)
    t = canon_dirs.sum(axis=0) * (1.0, 0.0, 1.0)
    if np.linalg.norm(u) < 1e-6 or np.linalg.norm(t) < 1e-6:
        return level
    return quat.normalize(quat.multiply(quat.between(u, t), level))


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
