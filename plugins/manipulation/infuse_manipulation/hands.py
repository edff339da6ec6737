"""Hand shapes on any rig: each finger joint curled toward the palm from the reference pose.

The reference pose (:attr:`~infuse.runtime.rig.Rig.reference_rotations`, the rest pose when it stands)
holds the fingers straight on the rigs infuse reads (T- and A-poses). Its geometry gives, per hand, the
finger direction and the palm normal (the palm faces ``sign · (f × a)``, with ``f`` from the wrist to
the middle knuckle, ``a`` from the little finger's knuckle to the index finger's, ``sign`` +1 on the left
hand and -1 on the right), and per finger joint the local axis that curls it toward the palm (the
thumb's toward a point in front of the palm by the middle finger's second joint). A shape
is a curl in radians per finger and joint; 0 is the reference pose, straight.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat

FINGERS = ("thumb", "index", "middle", "ring", "pinky")
#: Curl (radians) of the three joints of each finger (thumb first) of a pointing hand: the index straight.
POINTING_SHAPE = np.array([[0.35, 0.55, 0.45], [0.0, 0.0, 0.0], [1.35, 1.6, 1.0], [1.4, 1.6, 1.0], [1.45, 1.55, 1.0]])
#: Curl of a hand closed around a held object a few centimetres across.
GRIP_SHAPE = np.array([[0.3, 0.45, 0.4], [0.75, 0.95, 0.6], [0.8, 1.0, 0.6], [0.85, 1.0, 0.6], [0.9, 1.0, 0.6]])


@dataclass(frozen=True)
class Hand:
    """One hand of a rig: ``wrist`` joint; ``joints`` (K,) its finger joints, ``shape_index`` (K, 2) the
    (finger, joint) of each in a (5, 3) shape; ``reference_locals`` (K, 4) their local rotations in the
    reference pose; ``curl_axes`` (K, 3) unit local axes curling them; ``palm`` (3,) the palm normal and
    ``finger`` (3,) the finger direction in the reference pose (character's own frame); ``tip`` the
    joint the hand points with and ``tip_extra_m`` (3,) beyond it in its own frame (0 when it is the
    index fingertip)."""

    side: str
    wrist: int
    joints: np.ndarray
    shape_index: np.ndarray
    reference_locals: np.ndarray
    curl_axes: np.ndarray
    palm: np.ndarray
    finger: np.ndarray
    tip: int
    tip_extra_m: np.ndarray

    @property
    def has_fingers(self) -> bool:
        return len(self.joints) > 0


def reference_locals(rig) -> np.ndarray:
    """(J, 4) local rotations of the rig's reference pose."""
    g = rig.reference_rotations
    parents = rig.skeleton.parents
    parent_rot = np.where((parents >= 0)[:, None], g[np.maximum(parents, 0)], quat.IDENTITY)
    return quat.multiply(quat.conjugate(parent_rot), g)


def bind_hand(rig, side: str) -> Hand | None:
    """The :class:`Hand` of ``side`` ("left" or "right"), or None without a mapped wrist."""
    s = side[0]
    wrist = rig.joint(f"{s}_wrist")
    if wrist is None:
        return None
    _, positions = reference_globals(rig)
    chains = {f: [rig.joint(f"{s}_{f}{k}") for k in (1, 2, 3, 4)] for f in FINGERS}
    knuckle = {f: next((j for j in c if j is not None), None) for f, c in chains.items()}
    w = positions[wrist]
    front = next((knuckle[f] for f in ("middle", "index", "ring") if knuckle[f] is not None), None)
    across = (knuckle["index"], knuckle["pinky"] if knuckle["pinky"] is not None else knuckle["ring"])
    finger = _unit(positions[front] - w) if front is not None else _forearm_direction(rig, s, positions)
    if None not in across:
        a = positions[across[0]] - positions[across[1]]
        palm = _unit(np.cross(finger, a)) * (1.0 if s == "l" else -1.0)
    else:  # no knuckles to tell the palm: the body's down, off the finger direction
        down = quat.rotate(rig.body, np.array([0.0, -1.0, 0.0]))
        palm = _unit(down - np.dot(down, finger) * finger)
    locals_ = reference_locals(rig)
    joints, index, axes = [], [], []
    # The thumb folds toward a point in front of the palm by the middle finger, not straight into the palm.
    middle = next((j for j in chains["middle"][1:2] + chains["middle"][:1] + chains["index"][:1] if j is not None), None)
    fold = None
    if middle is not None and front is not None:
        fold = positions[middle] + 0.3 * np.linalg.norm(positions[front] - w) * palm
    for f, chain in enumerate(FINGERS):
        mapped = [j for j in chains[chain] if j is not None]
        for k, j in enumerate(mapped[:3]):
            below = mapped[k + 1] if k + 1 < len(mapped) else None
            direction = _unit(positions[below] - positions[j]) if below is not None else finger
            toward = _unit(fold - positions[j]) if chain == "thumb" and fold is not None else palm
            axis = np.cross(direction, toward)
            if np.linalg.norm(axis) < 1e-6:
                continue
            joints.append(j)
            index.append((f, k))
            axes.append(quat.rotate(quat.conjugate(rig.reference_rotations[j]), _unit(axis)))
    tip, extra = _tip(rig, chains["index"], positions, wrist, finger)
    return Hand(side, wrist, np.array(joints, dtype=np.int64), np.array(index, dtype=np.int64).reshape(-1, 2),
                locals_[joints] if joints else np.zeros((0, 4)), np.array(axes).reshape(-1, 3), palm, finger, tip, extra)


def shape_rotations(hand: Hand, curl: np.ndarray) -> np.ndarray:
    """Local rotations (F, K, 4) of the hand's finger joints for curls ``curl`` (F, 5, 3) radians."""
    angles = curl[:, hand.shape_index[:, 0], hand.shape_index[:, 1]]  # (F, K)
    half = 0.5 * angles
    offsets = np.empty(angles.shape + (4,))
    offsets[..., :3] = np.sin(half)[..., None] * hand.curl_axes
    offsets[..., 3] = np.cos(half)
    return quat.multiply(hand.reference_locals, offsets)


def set_shape(pose, hand: Hand, shape: np.ndarray, weight: np.ndarray) -> None:
    """Blend the hand's fingers toward ``shape`` (5, 3) radians by ``weight`` (F,) on ``pose``."""
    if not hand.has_fingers:
        return
    curl = np.broadcast_to(shape, (len(weight),) + shape.shape)
    pose.set_rotations(hand.joints, shape_rotations(hand, curl), weight)


def reference_tip(rig, hand: Hand) -> np.ndarray:
    """(3,) position of the pointing tip in the reference pose, the character's own frame (metres)."""
    rot, pos = reference_globals(rig)
    return pos[hand.tip] + quat.rotate(rot[hand.tip], hand.tip_extra_m)


def reference_globals(rig) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (J, 4) and positions (J, 3) of the reference pose, the character's own frame."""
    from infuse.kinematics import forward_kinematics

    locals_ = reference_locals(rig)
    sk = rig.skeleton
    g_rot, g_pos = forward_kinematics(sk, locals_[None], sk.rest_translations[None, 0], None)
    # The reference pose's own root placement: the reference rotations already include the root's.
    return g_rot[0], g_pos[0]


def _tip(rig, chain, positions, wrist: int, finger: np.ndarray) -> tuple[int, np.ndarray]:
    """The joint the hand points with and the offset beyond it (its own frame): the index fingertip; the
    last index joint and one more of its segments; the first index joint and its length from the wrist
    again; or, without an index finger, the wrist itself."""
    mapped = [j for j in chain if j is not None]
    if chain[3] is not None:
        return chain[3], np.zeros(3)
    if len(mapped) >= 2:
        last, before = mapped[-1], mapped[-2]
        step = positions[last] - positions[before]
        return last, quat.rotate(quat.conjugate(rig.reference_rotations[last]), step)
    if mapped:
        step = positions[mapped[0]] - positions[wrist]
        return mapped[0], quat.rotate(quat.conjugate(rig.reference_rotations[mapped[0]]), step)
    return wrist, np.zeros(3)


def _forearm_direction(rig, s: str, positions) -> np.ndarray:
    elbow = rig.joint(f"{s}_elbow")
    wrist = rig.joint(f"{s}_wrist")
    if elbow is None:
        return quat.rotate(rig.body, np.array([1.0 if s == "l" else -1.0, 0.0, 0.0]))
    return _unit(positions[wrist] - positions[elbow])


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, 1e-12)
