"""A played transition clip's feet that turn flat on the ground are lifted while they turn.

Recorded turns on the spot (and starts that turn) often swivel a foot with its heel and ball both
down: the foot turns about the vertical, by up to 150 degrees in half a second, sweeping the floor.
Pinned, a foot on its heel keeps the animation's turn (the leg could not twist that far), so its
ball would slide along an arc; on its ball alone it keeps its yaw and the body turns over it. So
where a flat foot turns faster than :data:`SWIVEL_DEG_S`, by :data:`SWIVEL_MIN_DEG` or more in all
(a landing's twist of a few degrees is left alone), or drags a point that is down along the ground
(:data:`DRAG_M_S`: a take shuffling a foot into place on its ball, or sliding it flat, :data:`FLAT`, its
contacts broken by its speed), the foot is lifted :data:`LIFT` of the leg's length
off the ground, its orientation kept, by two-joint leg IK on the clip, rising and coming down over
:data:`RAMP_S`; the frames it is fully up do not count as down, so the pinning lets it go and lands
it again where it comes down: a step that turns the foot, not a slide. While it rises and comes
down its contacts stay as they were: a foot that was down is held where it stands as it rises (and
where it comes down) and let go in the air, since a foot let go as it starts to rise goes on with
the take's slow turn or drag a few millimetres above the ground.

Positions are metres (+Y up), angles radians about +Y, times seconds; feet are ordered left, right.
"""
from __future__ import annotations

import math

import numpy as np

from infuse import footing
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk

#: A flat foot turning faster than this (degrees per second) about the vertical slides...
SWIVEL_DEG_S = 30.0
#: ...when it turns this much (degrees) or more in one go (turns this near in time are one).
SWIVEL_MIN_DEG = 10.0
GAP_S = 0.1
#: A foot on the ground dragging a point that is down faster than this (m/s), by this much (m) or
#: more in one go, is lifted too.
DRAG_M_S = 0.3
DRAG_MIN_M = 0.05
#: A foot lying flat (its ankle and its ball both within this share of the leg of the heights they
#: stand at) is on the ground, whatever its contacts say: a foot sliding fast enough breaks them.
FLAT = 0.01
#: Height (share of the leg's length) a swivelling foot is lifted to, and seconds to get there and back.
LIFT = 0.04
RAMP_S = 0.15


def _runs(flags: np.ndarray, gap: int) -> list[tuple[int, int]]:
    """[start, end) frame runs of ``flags`` (F,), runs at most ``gap`` frames apart joined."""
    idx = np.flatnonzero(flags)
    if not idx.size:
        return []
    breaks = np.flatnonzero(np.diff(idx) > gap)
    return list(zip(np.r_[idx[0], idx[breaks + 1]].tolist(), (np.r_[idx[breaks], idx[-1]] + 1).tolist()))


def swivel_lift(ankle: np.ndarray, ball: np.ndarray, phases: np.ndarray, fps: float, flat_m: float = 0.0) -> np.ndarray:
    """(F,) how far in [0, 1] a foot is lifted, from its ankle and ball positions (F, 3) and its heel
    and ball contact flags ``phases`` (F, 2) at ``fps``: fully where it swivels flat on the ground or
    drags a point that is down along it (see the module doc; a foot with its ankle and ball both
    within ``flat_m`` metres of the heights they stand at counts as down), eased in and out over
    :data:`RAMP_S` on either side."""
    frames = len(ankle)
    if frames < 2:
        return np.zeros(frames)
    along = ball - ankle
    yaw = np.unwrap(np.arctan2(along[:, 0], along[:, 2]))
    rate = np.abs(np.gradient(yaw)) * fps
    gap = max(int(round(GAP_S * fps)), 1)
    lifted = np.zeros(frames, dtype=bool)
    for a, e in _runs(phases[:, 0] & phases[:, 1] & (rate > math.radians(SWIVEL_DEG_S)), gap):
        if abs(yaw[min(e, frames - 1)] - yaw[a]) >= math.radians(SWIVEL_MIN_DEG):
            lifted[a:e] = True
    # A point that is down (the ball where it is, else the heel's ankle) moving along the ground.
    point = np.where(phases[:, 1:2], ball, ankle)[:, [0, 2]]
    speed = np.r_[0.0, np.linalg.norm(np.diff(point, axis=0), axis=-1) * fps]
    down = np.asarray(phases[:, 0] | phases[:, 1], dtype=bool)
    if flat_m > 0.0 and phases.any(axis=0).all():
        # Lying flat where both points are as low as they stand (their lowest 5% while down).
        floors = [np.percentile(p[phases[:, j], 1], 5.0) for j, p in enumerate((ankle, ball))]
        down |= (ankle[:, 1] < floors[0] + flat_m) & (ball[:, 1] < floors[1] + flat_m)
    held = down & np.concatenate((np.zeros(1, dtype=bool), down[:-1]))  # down at both ends of the frame
    for a, e in _runs(held & (speed > DRAG_M_S), gap):
        if speed[a:e].sum() / fps >= DRAG_MIN_M:
            lifted[a - 1:e] = True
    if not lifted.any():
        return np.zeros(frames)
    # Distance in seconds to the nearest lifted frame, eased into the ramps either side.
    t = np.arange(frames) / fps
    near = np.min(np.abs(t[:, None] - t[lifted][None]), axis=1)
    return 1.0 - footing.smoothstep(near / RAMP_S)


def lift_swivels(sk, motion, legs, phases: np.ndarray, facing: np.ndarray, leg_length: float):
    """``motion`` (a played clip on skeleton ``sk``) with its swivelling feet lifted (see the module
    doc), and its contact ``phases`` (F, 2, 2) with the frames fully lifted up. ``legs``: two (hip, knee,
    ankle, ball) joints, the ball None without one (that foot is left); ``facing`` (F,) radians."""
    feet = [k for k, leg in enumerate(legs) if leg[3] is not None]
    if not feet:
        return motion, phases
    joints = [j for k in feet for j in (legs[k][2], legs[k][3])]
    g_rot, g_pos = chain_fk(sk, motion.local_rotations, motion.root_translations, motion.joint_translations, joints)
    share = np.zeros((motion.num_frames, 2))
    for n, k in enumerate(feet):
        share[:, k] = swivel_lift(g_pos[:, 2 * n], g_pos[:, 2 * n + 1], phases[:, k], motion.fps, FLAT * leg_length)
    if not share.any():
        return motion, phases
    rot = np.array(motion.local_rotations)
    jt = None if motion.joint_translations is None else np.array(motion.joint_translations)
    forward = np.stack((np.sin(facing), np.zeros_like(facing), np.cos(facing)), axis=-1)
    for n, k in enumerate(feet):
        if share[:, k].any():
            goal = g_pos[:, 2 * n] + np.array([0.0, 1.0, 0.0]) * (LIFT * leg_length * share[:, k])[:, None]
            solve_limb(sk, rot, motion.root_translations, jt, legs[k][:3], goal, weight=(share[:, k] > 0.0).astype(float),
                       pole=forward, end_rotation=g_rot[:, 2 * n], distance=False)
    out = np.array(phases, dtype=bool)
    out[share >= 1.0] = False
    return motion.replace(local_rotations=rot, joint_translations=jt) if jt is not None else motion.replace(local_rotations=rot), out
