"""Making recorded takes usable as locomotion examples: the steadiest cycle, straightened and closed.

Real takes are irregular: they start from standing, curve a little, and a stretch from one left heel
strike to the next does not end in the pose it began with. The builder, on each locomotion clip:

- picks the **steadiest cycle** of a take (:func:`steadiest_cycle`): of its left-to-left strides
  (stepping evenly, when it has such strides: a leap is no cycle), the one whose speed is nearest the
  take's median stride speed, the starts and stops left out;
- **straightens** a cycle that turns slower than :data:`STRAIGHTEN_DEG_S` (:func:`straighten`): the
  root joint is turned back by the turn rate times the time and carried from the circle the take
  walks onto the straight line of the same length, so straight walking exists at every speed the
  takes show (the controller turns the root for any turn rate asked); a cycle travelling within
  :data:`ALIGN_DEG` of its facing (or of straight back) is turned to travel exactly forward (back);
- **closes the cycle** (:func:`close_loop`): each joint's rotation difference between the cycle's
  last frame and its first (the root's without its turn) and the root's height difference are taken
  out progressively over the cycle, so the loop is seamless;
- recognizes **transitions** by what they do (:func:`transition_kind`): a start (standing, then
  walking), a stop (walking, then standing), a turn on the spot (turning with little travel), a step
  (a few steps, standing before and after), or no locomotion at all (no steps); these are not
  blended.

Core frame: metres, seconds, +Y up, +Z forward; angles radians about +Y, + turns left.
"""
from __future__ import annotations

import math

import numpy as np

from .. import quaternions as quat

#: Cycles turning slower than this (degrees per second) are straightened.
STRAIGHTEN_DEG_S = 30.0
#: A cycle travelling within this many degrees of its facing (or of straight back) walks forward (back):
#: its body is turned to travel exactly so (the hips of a real take seldom face its travel exactly).
ALIGN_DEG = 10.0
#: A clip's pelvis travelling slower than this many leg lengths per second over its first (last)
#: quarter second (net ground travel) stands there.
STILL_LEGS_S = 0.15
#: Both feet down for at least this long (seconds) at a clip's start (end), the pelvis moving slower
#: than twice :data:`STILL_LEGS_S` meanwhile, also stands there: a start that turns first shifts its
#: weight before its first step, faster than a body standing still (a walk's double support is shorter).
STAND_S = 0.3
#: A stride steps evenly when the other foot strikes within this share of it from its middle: SmartBody's
#: walks, runs, strafes and circles 0.46-0.55; the strides with a leap of its walk and run with a jump
#: 0.64-0.67 (the pelvis rising 26 cm, 2-6 in the others), passed over for an even stride of the take.
EVEN_STEPS = 0.1
#: A standing take travels less than this many leg lengths over its whole length (:func:`stands_still`)...
IDLE_TRAVEL_LEGS = 0.1
#: ...its feet travel less than this many leg lengths per second (SmartBody's idle: 0; with a degree of
#: rotation noise on every joint, low-passed, 0.23)...
IDLE_FEET_LEGS_S = 0.05
#: ...and its hands stay within this many leg lengths of where they mostly are, relative to the pelvis:
#: SmartBody's idle 0.002, Bandai's waves and raised hands 0.6 and more.
IDLE_HANDS_LEGS = 0.2
#: Clips of at most this many steps may be transitions (starts, stops, steps).
SHORT_STEPS = 4
#: A turn on the spot turns at least this much (degrees) over the clip.
TURN_DEG = 45.0


def _yaw(angle) -> np.ndarray:
    half = 0.5 * np.asarray(angle, dtype=np.float64)
    out = np.zeros(half.shape + (4,))
    out[..., 1] = np.sin(half)
    out[..., 3] = np.cos(half)
    return out


def strides(step_list: list[dict]) -> list[tuple[float, float, list[float]]]:
    """Every stride of a take's steps as (first, next strike of one foot, keys), seconds: left strike to
    left strike with a right strike between, keys (left strike, right strike, next left strike); a take
    without one (a strafe of three steps, right-left-right) from right strike to right strike with a left
    strike between, keys (that left strike, the next right strike, the left strike one stride on), as a
    loop's keys run past its end."""
    times = {foot: [s["strike"] for s in step_list if s["foot"] == foot] for foot in ("left", "right")}
    out = []
    for foot, other in (("left", "right"), ("right", "left")):
        for a, b in zip(times[foot][:-1], times[foot][1:]):
            between = [t for t in times[other] if a < t < b]
            if between:
                out.append((a, b, [a, between[0], b] if foot == "left" else [between[0], b, between[0] + b - a]))
        if out:
            return out
    return out


def _between_share(a: float, b: float, keys: list[float]) -> float:
    """Where the other foot strikes within the stride from ``a`` to ``b`` (seconds), as a share of it."""
    between = keys[1] if abs(keys[0] - a) < 1e-9 else keys[0]
    return (between - a) / max(b - a, 1e-9)


def steadiest_cycle(step_list: list[dict], speed_of, fps: float) -> tuple[int, int] | None:
    """(first, last frame) of the stride (:func:`strides`) whose speed ``speed_of((first, last))`` (m/s)
    is nearest the median over the take's strides; of its strides that step evenly (the other foot
    striking within :data:`EVEN_STEPS` of the middle), when it has any. None without a stride."""
    every = strides(step_list)
    even = [s for s in every if abs(_between_share(*s) - 0.5) <= EVEN_STEPS]
    found = [(int(round(a * fps)), int(round(b * fps))) for a, b, _ in (even or every)]
    if not found:
        return None
    speeds = np.array([speed_of(s) for s in found])
    return found[int(np.argmin(np.abs(speeds - np.median(speeds))))]


def closest_loop_end(rotations: np.ndarray, cycle: tuple[int, int], reach: int) -> int:
    """The frame within ``reach`` of a cycle's (first, last) last frame whose pose (local rotations
    (F, J, 4) of every joint but the root, whose turn the closing takes apart) comes nearest its first:
    where noise leaves a stride's strikes a frame or two off, the loop closes over the stride's own gap,
    not the timing's. ``reach`` 0 keeps the last frame."""
    a, b = cycle
    candidates = np.arange(max(b - reach, a + 2), min(b + reach, len(rotations) - 1) + 1)
    if reach <= 0 or candidates.size < 2:
        return b
    gap = quat.angle_between(rotations[a, 1:][None], rotations[candidates, 1:]).mean(axis=1)
    return int(candidates[np.argmin(gap)])


def _arc(speed: float, direction: float, turn: float, heading: float, t: np.ndarray) -> np.ndarray:
    """(T, 3) ground points at times ``t`` (T,) along a circle (or line, ``turn`` 0) from the origin,
    travelled at ``speed`` m/s in ``direction`` off a facing that starts at ``heading`` and turns at
    ``turn`` rad/s."""
    a = heading + direction
    if abs(turn) < 1e-9:
        return np.stack((speed * math.sin(a) * t, 0 * t, speed * math.cos(a) * t), axis=-1)
    r = speed / turn
    return np.stack((r * (math.cos(a) - np.cos(a + turn * t)), 0 * t, r * (np.sin(a + turn * t) - math.sin(a))), axis=-1)


def _travel(motion) -> tuple[int, np.ndarray] | None:
    """The joint that carries a motion's travel and its positions (F, 3) in the motion's frame: the root
    joint, else the first child of the root whose own translation moves; None if nothing moves."""
    root = motion.root_translations
    if np.ptp(root, axis=0).max() >= 1e-6:
        return 0, root
    jt = motion.joint_translations
    if jt is None:
        return None
    moving = np.nonzero((np.ptp(jt, axis=0).max(axis=1) > 1e-6) & (motion.skeleton.parents == 0))[0]
    if not moving.size:
        return None
    j = int(moving[0])
    return j, root + quat.rotate(motion.local_rotations[:, 0], jt[:, j])


def _turned(rotations: np.ndarray, joint: int, turn: np.ndarray) -> np.ndarray:
    """Local rotations (F, J, 4) with ``joint`` (the root or a child of it) turned by ``turn`` (F, 4)
    in the motion's frame."""
    rot = np.array(rotations)
    if joint == 0:
        rot[:, 0] = quat.multiply(turn, rot[:, 0])
    else:
        r0 = rot[:, 0]
        rot[:, joint] = quat.multiply(quat.multiply(quat.conjugate(r0), quat.multiply(turn, r0)), rot[:, joint])
    return rot


def _moved(motion, joint: int, turn: np.ndarray, positions: np.ndarray):
    """``motion`` with its travelling ``joint`` turned by ``turn`` (F, 4) and placed at ``positions``
    (F, 3), both in the motion's frame."""
    rot = _turned(motion.local_rotations, joint, turn)
    if joint == 0:
        return motion.replace(local_rotations=rot, root_translations=positions)
    jt = np.array(motion.joint_translations)
    jt[:, joint] = quat.rotate(quat.conjugate(rot[:, 0]), positions - motion.root_translations)
    return motion.replace(local_rotations=rot, joint_translations=jt)


def straighten(motion, params: dict, cycle: tuple[int, int], turn: float, align: float = 0.0):
    """``motion`` with ``turn`` rad/s of its cycle's turn rate taken out and its body turned by
    ``align`` radians off its path: the root joint turned by ``align - turn * t`` (t seconds from the
    cycle's first frame) and carried from the circle the cycle walks (``params`` of
    :func:`~infuse.packs.analysis.locomotion_parameters`) onto the circle of the remaining turn rate
    (a straight line when all of it is taken out), same arc speed, same start and first heading of
    travel. Returns the new motion; one whose root joint does not move is returned as it is."""
    travel = _travel(motion)
    if travel is None:
        return motion
    joint, pos = travel
    t = (np.arange(motion.num_frames) - cycle[0]) / motion.fps
    w = params["turn_rate"]
    speed = math.hypot(params["forward_speed"], params["lateral_speed"])  # along the arc
    direction = math.atan2(params["lateral_speed"], params["forward_speed"])
    h0 = params["heading_start"]
    start = pos[cycle[0]] * np.array([1.0, 0.0, 1.0])
    undo = _yaw(align - turn * t)
    walked = start + _arc(speed, direction, w, h0, t)
    kept = start + _arc(speed, direction - align, w - turn, h0 + align, t)
    return _moved(motion, joint, undo, kept + quat.rotate(undo, pos - walked))


def close_loop(motion, cycle: tuple[int, int], turn_rate: float = 0.0):
    """``motion`` with its cycle (first, last frame) closed: each joint's rotation from the cycle's first
    frame to its last (the root's after taking out ``turn_rate`` rad/s) and the travelling joint's
    height change,
    taken out in proportion to the time into the cycle (fully from the last frame on). Returns the
    new motion and the largest rotation taken out (degrees)."""
    a, b = cycle
    if b - a < 2:
        return motion, 0.0
    travel = _travel(motion)
    joint = 0 if travel is None else travel[0]
    turn = _yaw(turn_rate * (np.arange(motion.num_frames) - a) / motion.fps)
    rot = _turned(motion.local_rotations, joint, quat.conjugate(turn))
    gap = quat.multiply(quat.conjugate(rot[a]), rot[b])  # (J, 4): first -> last, in each joint's frame
    gap = np.where(gap[:, 3:] < 0.0, -gap, gap)
    share = np.clip((np.arange(len(rot)) - a) / (b - a), 0.0, 1.0)
    closed = quat.multiply(rot, quat.from_rotvec(-share[:, None, None] * quat.to_rotvec(gap)[None]))
    largest = float(np.degrees(quat.angle_between(rot[a], rot[b]).max()))
    if travel is None:
        return motion.replace(local_rotations=_turned(closed, joint, turn)), largest
    pos = np.array(travel[1])
    pos[:, 1] -= share * (pos[b, 1] - pos[a, 1])
    return _moved(motion.replace(local_rotations=closed), joint, turn, pos), largest


def alignment(direction: float) -> float:
    """The turn (radians) that makes a cycle travelling ``direction`` radians off its facing travel
    exactly forward or back, if it is within :data:`ALIGN_DEG` of either; else 0."""
    limit = math.radians(ALIGN_DEG)
    if abs(direction) <= limit:
        return direction
    if abs(direction) >= math.pi - limit:
        return direction - math.copysign(math.pi, direction)
    return 0.0


def _stands(velocity: np.ndarray, both_down: np.ndarray, fps: float, leg: float) -> bool:
    """Whether a clip stands at its start, from its pelvis's ground velocity (F, 2) m/s and whether both
    feet are down (F,): the pelvis nearly still over the first quarter second (the mean velocity's
    length, net travel, not the mean speed, which mocap noise on the pelvis inflates), or both feet down
    for :data:`STAND_S` with the pelvis slower than twice that."""
    still = STILL_LEGS_S * leg
    span = max(int(round(0.25 * fps)), 1)
    if np.linalg.norm(velocity[:span].mean(axis=0)) < still:
        return True
    down = int(np.argmin(both_down)) if not both_down.all() else len(both_down)
    return down >= max(STAND_S * fps, 1) and float(np.linalg.norm(velocity[:down].mean(axis=0))) < 2.0 * still


def stands_still(foot_flags: np.ndarray, root: np.ndarray, hands: np.ndarray, foot_points: np.ndarray, fps: float,
                 leg: float) -> bool:
    """Whether a clip stands still throughout, as an idle does: both feet down in every frame of its
    (F, 2) contacts, its feet's contact joints (F, P, 3) travelling less than :data:`IDLE_FEET_LEGS_S`
    leg lengths per second along the ground (noise left in them would slide the standing feet), its
    pelvis (F, 3) less than :data:`IDLE_TRAVEL_LEGS` leg lengths over the clip, and its hands (F, H, 3),
    relative to the pelvis, staying within :data:`IDLE_HANDS_LEGS` leg lengths of where they mostly are
    (a wave or a raised hand moves them farther)."""
    if len(root) < 2 or not np.asarray(foot_flags, dtype=bool).all():
        return False
    if np.linalg.norm((root[-1] - root[0])[[0, 2]]) > IDLE_TRAVEL_LEGS * leg:
        return False
    feet_travel = np.linalg.norm(np.diff(foot_points[..., [0, 2]], axis=0), axis=-1).sum(axis=0) * fps / (len(root) - 1)
    if feet_travel.max() > IDLE_FEET_LEGS_S * leg:
        return False
    rel = hands - root[:, None]
    return bool(np.linalg.norm(rel - np.median(rel, axis=0), axis=-1).max() <= IDLE_HANDS_LEGS * leg)


def transition_kind(foot_flags: np.ndarray, root: np.ndarray, heading: np.ndarray, fps: float, leg: float,
                    steps: int) -> str | None:
    """What a clip does, from its (F, 2) foot contacts, pelvis path (F, 3), facing (F,) radians, leg
    length (m) and number of steps: ``"none"`` (no steps: not locomotion), ``"turn"`` (turning more
    than :data:`TURN_DEG` on the spot), and for clips of at most :data:`SHORT_STEPS` steps ``"step"``
    (one or two steps travelling less than a leg length, or standing before and after), ``"start"`` (standing, then walking) or ``"stop"`` (walking, then
    standing; standing is told by :func:`_stands`); None for a walk (what the blend can use)."""
    if steps == 0 or len(root) < 3:
        return "none"
    travel = float(np.linalg.norm((root[-1] - root[0])[[0, 2]]))
    turned = abs(float(heading[-1] - heading[0]))
    if travel < 0.6 * leg and turned > math.radians(TURN_DEG):
        return "turn"
    if steps > SHORT_STEPS:
        return None
    if steps <= 2 and travel < leg:
        return "step"
    velocity = np.gradient(root[:, [0, 2]], axis=0) * fps
    both = np.all(np.asarray(foot_flags, dtype=bool), axis=1, keepdims=True)[:, 0]
    begins, ends = (_stands(velocity, both, fps, leg), _stands(velocity[::-1], both[::-1], fps, leg))
    if begins and ends:
        return "step"
    if begins:
        return "start"
    if ends:
        return "stop"
    return None
