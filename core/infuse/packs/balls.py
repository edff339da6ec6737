"""Infused locomotion clips: each foot's ball kept from going below the ground it is planted on.

Retargeting copies a foot's pitch and scales the leg, so the ankle rises as the source's does for its
leg length; but a foot pitching over its ball must raise its ankle by its own length from ankle to
ball. On a character whose foot is much longer than the source's (relative to the leg), the ball
then swings below the ground as the heel rises (a foot 0.4 m from ankle to ball on a 0.67 m leg: 9 cm
under). Where a ball goes further below its planted height than the source's ball goes below its own
(scaled by the legs' ratio: mocap balls press into the floor by a few centimetres at landings) and
:data:`DEEPER` leg lengths more, the ankle is raised by the rest (two-joint leg IK, the foot keeping
its global rotation), so the ball comes back to that depth: feet that go no deeper are left untouched.
"""
from __future__ import annotations

import numpy as np

from ..contacts import Foot, leg_length
from ..kinematics import forward_kinematics
from ..motion import Motion
from ..runtime.limb_ik import is_carried, solve_limb

#: How much deeper (leg lengths) than the source's a ball may go before its ankle is raised: the height
#: below which the skate measure counts a point's travel (:data:`infuse.metrics.SKATE_LIFT`), so
#: retargeted feet of usual proportions, a centimetre or two deeper at a heel rise, keep their contacts.
DEEPER = 0.03


def planted_heights(positions: np.ndarray, pair: tuple[Foot, Foot], flat: np.ndarray) -> np.ndarray:
    """(2,) height (m) of each foot's ball (else ankle) where the foot lies flat, both its heel and ball
    down: the median over the frames ``flat`` (F, 2) flags, over every frame of a foot never flat.
    ``positions`` (F, J, 3) metres."""
    out = np.zeros(2)
    for k, foot in enumerate(pair):
        point = foot.ball if foot.ball is not None else foot.ankle
        y = positions[:, point, 1]
        out[k] = float(np.median(y[flat[:, k]] if flat[:, k].any() else y))
    return out


def depths(positions: np.ndarray, pair: tuple[Foot, Foot], planted: np.ndarray) -> np.ndarray:
    """(F, 2) how far (m) each foot's ball (else ankle) is below its ``planted`` (2,) height, 0 above it;
    ``positions`` (F, J, 3) metres."""
    points = [foot.ball if foot.ball is not None else foot.ankle for foot in pair]
    return np.maximum(planted[None] - positions[:, points, 1], 0.0)


def balls_above(motion: Motion, pair: tuple[Foot, Foot], planted: np.ndarray, allowed: np.ndarray) -> tuple[Motion, np.ndarray]:
    """``motion`` with each foot's ankle raised where its ball goes deeper below its ``planted`` (2,)
    height (m) than ``allowed`` (F, 2) metres and :data:`DEEPER`, and the raise (F, 2) metres (0 where it
    does not go deeper)."""
    sk = motion.skeleton
    _, pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    tolerance = DEEPER * leg_length(sk, pair)
    raise_m = np.zeros((motion.num_frames, 2))
    for k, foot in enumerate(pair):
        if foot.ball is not None:
            raise_m[:, k] = np.maximum(planted[k] - allowed[:, k] - tolerance - pos[:, foot.ball, 1], 0.0)
    if not raise_m.any():
        return motion, raise_m
    rot = motion.local_rotations.copy()
    goal = pos[:, [pair[0].ankle, pair[1].ankle]]
    goal[..., 1] += raise_m
    limbs = [(foot.hip, foot.knee, foot.ankle) for foot in pair]
    carried = any(is_carried(sk, limb) for limb in limbs)  # such a foot is placed by its local translation
    jt = motion.local_translations().copy() if carried else motion.joint_translations
    solve_limb(sk, rot, motion.root_translations, jt, limbs, goal, weight=(raise_m > 0.0).astype(np.float64), distance=False)
    return motion.replace(local_rotations=rot, joint_translations=jt), raise_m
