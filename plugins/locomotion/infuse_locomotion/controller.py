"""The ``locomotion`` controller: a pack's locomotion cycles blended by speed, turn rate and direction.

Each frame the steering (:mod:`.steering`) asks for a speed, a turn rate and a travel direction. Their
point (velocity along and across the facing, turn rate) gets barycentric weights in the pack's
tessellation, as infused onto the character. The blend is **phase-synchronized and time-warped**: one
phase runs through every cycle at once, advancing by ``dt / T`` with T the weighted cycle duration,
and each clip maps it to its own time through its keys (left strike at phase 0, right strike at 0.5),
so the blended clips step together; each leg is warped further by its foot's contact events (heel
strike, foot flat, heel off, toe off; :mod:`.phase_keys`), so the clips' feet are in the same
support phase at once. **Slow walking**: below the slowest walk the tessellation would mix in the
idle; instead the slowest straight walk plays at a slower cadence with shorter steps (both by the
square root of the speed ratio). **Stops** (below :data:`STAND_FRACTION` of it, or braking for the
end of a path): the feet keep stepping with strides shrinking to nothing until each has landed once
more (without an idle twice) with the pelvis over the point it stops at, at the idle's stance (else
the slowest walk's, feet side by side) and laid flat, then the idle fades in
(:func:`_clock`; without an idle the pelvis rises instead, to stand on legs as straight as the takes'
stance legs: :func:`_stand_height`); turning on the spot steps the same way. **Root motion** is the weighted clips'
velocities (so the realized speed is the requested one inside the pack's range), along the heading
the steering asks for; the part of its turn the blend does not show is spun at the root. Each clip
contributes its pelvis motion relative to its own straight or circular path.

**Planted feet** follow the blend's contact phases (heel down from heel strike to heel off,
ball down from foot flat to toe off). From heel strike the ankle stays where it landed; from
halfway through foot flat (:data:`HANDOVER`, the foot resting still) to toe off the ball
(``forefoot``, else ``toe``) stays put and the foot pivots about it: the ankle goal is the pinned
ball plus the animated ball-to-ankle offset, which carries the foot's pitch, and the two-joint leg
IK (``infuse.runtime.limb_ik``) reaches it with the foot keeping its animated rotation; where the
hip cannot reach it, the heel rises further about the ball. The ball takes over where the corrected
foot had it a frame earlier, so the switch is continuous, and at toe off the correction fades out
over :data:`RELEASE_S`; a foot without a ball, held by its ankle, is let go with its goal kept within
the leg's reach (:func:`infuse.footing.within_reach`).
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import math
import weakref
from dataclasses import dataclass, replace
from collections.abc import Generator
from typing import Any, Callable, NamedTuple

import numpy as np

from infuse import footing, quaternions as quat
from infuse.contacts import DOWN_TOLERANCE, foot_frames
from infuse.errors import MissingFeatureError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.clip import LoopTable, continuous_rotations, sample_motion
from infuse.runtime.limb_ik import LimbSolve, solve_limb, solve_limb_ends_together
from infuse.runtime.pose import chain_fk

from . import pacing, swivels, transitions
from .binding import FootFloors, LocomotionBinding
from .phase_keys import GROUNDED, GROUNDED_SHARE, LIFTED, FootKeys, foot_events, foot_keys, foot_phase, stance_of, warp
from .state import FOOT_VALUES, HELD_COLUMNS, LocomotionState
from .steering import STAY as STAY_M, TURN_IN_PLACE, Steering, SteeringState


#: Seconds over which a released foot's pin correction fades back to the animation, and its extra
#: heel rise (a leg that could not reach its pinned ball) in the early swing.
RELEASE_S = 0.3
RISE_RELEASE_S = 0.1
#: Seconds over which a released foot's pin correction fades in the steps of a stop or a turn on the
#: spot (the foot steps back under the body before it touches down).
STEP_RELEASE_S = 0.15
#: Seconds over which a foot laid flat in a stop's last steps is let go at least (its turn back to
#: the animation's toe off).
LAY_RELEASE_S = 0.3
#: The largest turn (degrees) that lifts a foot or toes off the ground (their tip may not reach higher).
LIFT_MAX_DEG = 90.0
#: Degrees per second at which toes bent to keep their tip off the ground unbend at most, at least (as
#: fast as the pack's toes turn against their feet: :func:`_toes_rate`).
TOE_RELEASE_DEG_S = 150.0
#: Seconds a released ball is held where it was let go at most, while it has not left the ground.
HOLD_S = 0.1
#: A ball let go by the idle's fading share (the walk's blend already swings it) is held along the
#: ground until it has risen this share of the leg (where the skate measure stops counting it), rising
#: with the animation: the blend's swing, under way, would carry it along just above the ground.
SHARE_CLEAR = 0.03
#: A released ball lifts before it travels: until it is LIFT_CLEAR_M above where it was let go, it rises
#: at least one part in LIFT_TRAVEL of how far it has moved from there along the ground (the share of its
#: correction still held): a take's ball pushing off, its drag going on just above the ground, slid there.
LIFT_CLEAR_M = 0.01
LIFT_TRAVEL = 2.0
#: Height of the arc a released foot travels back to the animation over, per metre it travels.
STEP_ARC = 0.25
#: Below this fraction of the slowest walk's speed the character stops (and fades into the idle).
STAND_FRACTION = 0.2
#: Below this fraction of the slowest walk's speed the pelvis stands over the point it stops at (its
#: gait's offset taken out but for this share over :data:`STAND_FRACTION`): the landings that end a
#: stop count from there, so each foot lands once more at the stance under the still body.
STILL_FRACTION = 0.01
#: Share of the moving clips (one minus the idle's) below which their blend turns smoothly into the
#: slowest walk as the speed nears zero: renormalized alone, the blend would jump from the slowest walk
#: to whichever clip the request first gives weight to (a turning walk's pose at the start of a turn).
SLOW_RAMP = 0.1
#: Share of the slowest walk always mixed into the moving clips' weights (its steps' events stay in the blend).
SLOW_EPS = 1e-3
#: Seconds the moving clips' weights take at least to go all the way from one blend to another where
#: the request lies outside the examples' tessellation: brought back to its nearest point there (a
#: speed below the slowest straight walk blended from a slower turning walk), they change far faster
#: with the request than inside, and a clip entering at a third of the blend in one frame turned the
#: head 18-24 degrees (as far again coming back inside). Inside, the blend follows the request as asked.
BLEND_EASE_S = 0.4
#: Least cadence factor of the steps that end a stop or turn on the spot, how fast it is reached
#: (per second), and the phase past the last landing at which they end (double support, both feet down).
STOP_CADENCE = 1.2
#: Landings (both feet) with the pelvis still that end a stop of a pack without an idle (with one,
#: two: the idle's stance fades in): each foot steps back under the body from wherever the stop left
#: it, then once more at the stance.
STOP_LANDINGS = 4
CADENCE_RAMP = 3.0
SETTLE_PHASE = 0.05
#: Phase share over which a foot's stance share rises after strike and falls before toe off
#: (:func:`~.phase_keys.stance_of`), and the least phase a stop holds before the trailing foot's fall starts.
STANCE_RAMP = 0.05
SETTLE_MARGIN = 0.005
#: Turning on the spot faster than this (rad/s) beyond what the blend shows, the feet step.
SPIN_STEP = 0.15
#: Seconds over which a stopped character fades into the pack's idle.
SETTLE_S = 0.5
#: Share of the leg's full length a hip stands above its ankle at most, come to rest without an idle
#: (:func:`_stand_height`): short of :data:`infuse.footing.REACH`, beyond which a foot held by its ball
#: would have its heel raised, with room for a foot a few centimetres off straight under the hip.
STAND_REACH = 0.985
#: Share of the way from foot flat to heel off at which the pinned point passes from the ankle to the ball.
HANDOVER = 0.5
#: How near its resting height (leg lengths) the lower of a swinging foot's sole points, coming down,
#: lands the foot (:func:`_touch_downs`): the height from which the skate measure counts a sliding sole.
TOUCH = 0.03
#: A clip weighing no more than this on a frame is left out of its blend there.
_LEAST_WEIGHT = 1e-6
#: How many pieces of work on blend weights a binding keeps (:func:`_kept`): the oldest goes as one comes.
_WEIGHTS_KEPT = 2048
_ONES4 = np.ones(4)
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
_ORIGIN = np.zeros(3)
_GROUND = np.array([1.0, 0.0, 1.0])  # keeps a point's ground coordinates (x, z)


class PreparedWalks(dict):
    """What :meth:`Locomotion.bind` prepared (:func:`_prepare`) for a character's asset, by (pack name,
    the space's content (:func:`_space_content`), legs, pelvis): the blend space it was prepared from, the
    skeleton, and the binding. Kept for the asset (:meth:`~infuse.runtime.rig.Rig.asset_state_of`): every
    walk of a character made of it reuses it, also where each character has the pack infused into a
    space of its own (a scene's characters); one per pack (a space infused otherwise takes its place),
    and it goes with the asset."""


def yaw(angle) -> np.ndarray:
    """Quaternions (..., 4) of turns by ``angle`` (...) radians about +Y."""
    half = 0.5 * np.asarray(angle, dtype=np.float64)
    out = np.zeros(half.shape + (4,))
    out[..., 1] = np.sin(half)
    out[..., 3] = np.cos(half)
    return out


def clip_path(params: dict, t: np.ndarray) -> np.ndarray:
    """(T, 3) ground path of a clip's pelvis from its start: straight, or a circle when it turns."""
    vf, vl, w, h0 = params["forward_speed"], params["lateral_speed"], params["turn_rate"], params["heading_start"]
    speed, direction = math.hypot(vf, vl), math.atan2(vl, vf)
    a = h0 + direction
    if abs(w) < 1e-6:
        return np.stack((speed * math.sin(a) * t, 0 * t, speed * math.cos(a) * t), axis=-1)
    r = speed / w
    return np.stack((r * (math.cos(a) - np.cos(a + w * t)), 0 * t, r * (np.sin(a + w * t) - math.sin(a))), axis=-1)


def canonical_clip(clip, pelvis: int = 0):
    """The clip with its facing and its travel taken out: joint 0 turned by minus the clip's linear
    heading (or, where joint 0 sits above the pelvis with one child, that child turned as much in
    joint 0's frame, joint 0 left as the clip has it), the mover's translation made relative to the
    clip's path, in the clip's facing frame.
    The path is the ``pelvis`` joint's (as the clip's parameters are measured), so it starts on the
    pelvis's ground point at the origin wherever joint 0 sits. Returns (motion, mover joint)."""
    m = clip.motion
    t = np.arange(m.num_frames) / m.fps
    p = clip.parameters
    h = p["heading_start"] + p["turn_rate"] * t
    undo = yaw(-h)
    mover, pos = 0, m.root_translations
    if np.ptp(pos, axis=0).max() < 1e-6 and m.joint_translations is not None:
        moving = np.nonzero(np.ptp(m.joint_translations, axis=0).max(axis=1) > 1e-6)[0]
        if moving.size:
            mover, pos = int(moving[0]), m.joint_translations[:, moving[0]]
    path = clip_path(p, t)
    _, first = chain_fk(m.skeleton, m.local_rotations[:1], m.root_translations[:1],
                        None if m.joint_translations is None else m.joint_translations[:1], [pelvis, mover])
    start = (pos[0] + first[0, 0] - first[0, 1]) * np.array([1.0, 0.0, 1.0])  # the pelvis's ground point
    offset = quat.rotate(undo, pos - start - path)
    rot = np.array(m.local_rotations)
    below = np.flatnonzero(m.skeleton.parents == 0)
    if mover == 0 and pelvis != 0 and below.size == 1:
        # Joint 0 above the pelvis, with one child: the child turns instead (by the same world turn, in
        # joint 0's frame) and joint 0's translation keeps it in place. Retargeted clips of such rigs
        # leave joint 0 as it rests and turn the hips; turned by minus each clip's heading, joint 0
        # faced 0 degrees in one clip and 180 in another, and a blend of the two turned the body round.
        child = int(below[0])
        turn = quat.multiply(quat.conjugate(rot[:, 0]), quat.multiply(undo, rot[:, 0]))
        rot[:, child] = quat.multiply(turn, rot[:, child])
        hung = quat.rotate(rot[:, 0], m.local_translations()[:, child])  # joint 0 to its child, world
        return m.replace(local_rotations=rot, root_translations=offset + quat.rotate(undo, hung) - hung), mover
    rot[:, 0] = quat.multiply(undo, rot[:, 0])
    if mover == 0:
        return m.replace(local_rotations=rot, root_translations=offset), mover
    jt = np.array(m.joint_translations)
    jt[:, mover] = offset
    return m.replace(local_rotations=rot, joint_translations=jt), mover


@dataclass
class WalkPlan:
    """How a walk to a point goes (:meth:`Locomotion.plan`): seconds from its start until it stands
    there (``arrives_s``), until its stop's last steps and the fade into the idle are surely over
    (``rests_s``: one cycle of the slowest forward walk at the stop's cadence and :data:`SETTLE_S`
    later; with a stop clip, which begins at its gait phase, the longest cycle of its walks more), and the
    steering's state then."""

    arrives_s: float
    rests_s: float
    state: SteeringState


class Locomotion(Controller):
    """Locomotion from a behaviour pack (an installed name, a folder, or a :class:`BlendSpace`).

    Angles are degrees and turn rates degrees per second, as everywhere the project prints them.

    - ``speed`` m/s, ``turn_rate_deg_s`` (+ left), ``direction_deg`` of travel from the facing
      (+ left): numbers or functions of the activity's time (seconds); or ``path`` (ground points in
      the character's own frame, metres) / ``target`` (one point) to walk to, stopping there.
    - ``max_accel``, ``max_decel`` (m/s²), ``max_turn_rate_deg_s``, ``max_turn_accel_deg_s2``.
    - ``pin_feet``: pin planted feet with leg IK (default on).
    """

    kind = "locomotion"
    layer = Layer.BASE
    mode = Mode.OVERRIDE
    blend_in_s = 0.0
    blend_out_s = 0.3
    own_characters_only = True  # a character's walks of every priority evaluated with the others' at once
    call_ms = 2.0  # the feet's pinning and the blend's fixed work (benchmarks/walking_blocks.py)

    def __init__(self, pack="locomotion-male", speed=1.3, turn_rate_deg_s=0.0, direction_deg=0.0, path=None, target=None,
                 max_accel: float = 1.5, max_decel: float = 2.5, max_turn_rate_deg_s: float = 90.0,
                 max_turn_accel_deg_s2: float = 240.0, pin_feet: bool = True):
        if path is not None and target is not None:
            raise UsageError("give a path or a target, not both")
        if target is not None:
            path = [target]
        try:
            # The steering works in radians: converted here, once.
            self.steering = Steering(speed, _radians(turn_rate_deg_s, "turn_rate_deg_s"), _radians(direction_deg, "direction_deg"),
                                     path, max_accel, max_decel, _radians(max_turn_rate_deg_s, "max_turn_rate_deg_s", False),
                                     _radians(max_turn_accel_deg_s2, "max_turn_accel_deg_s2", False))
        except (TypeError, ValueError) as exc:
            raise UsageError(str(exc)) from None
        self.pack = pack
        self.pin_feet = bool(pin_feet)

    def describe(self) -> str:
        return f"locomotion ({getattr(self.pack, 'pack', self.pack)})"

    def plan(self, fps: float, state: SteeringState | None = None, most_s: float = 600.0) -> WalkPlan | None:
        """How a walk along a path (``path=`` or ``target=``) with a :class:`~infuse.packs.BlendSpace`
        pack goes at ``fps``, from the steering at the speeds the pack realizes (faster ones kept to
        its top speed): a :class:`WalkPlan`, or None if it does not stand at its last point within
        ``most_s``. ``state``: where it starts (default: the origin, standing, facing +Z)."""
        st = SteeringState()
        if state is not None:
            st.go_on_from(state)
        space = self.pack
        top = space.speed_limit() if hasattr(space, "speed_limit") else None
        path = self.steering.path
        if path is None:
            return None
        dt = 1.0 / float(fps)
        last, frames, decide, stopped = path[-1], 0, True, False
        clips = space.group("locomotion") if top else []
        played = transitions.played(space, _standing_speed(clips)) if top else []
        stops = transitions.stops(played)
        paced = pacing.pacing_for(stops, fps, *straight_walk(space, clips), float(getattr(state, "phase", 0.0)),
                                  self.steering.max_accel) if stops else None
        slowest_keys = clips[_slowest_walk(clips)].keys if top else (0.0, 0.0, 1.0)
        half = 0.5 * float(slowest_keys[2] - slowest_keys[0])
        while frames * dt < most_s:  # frame by frame: the steering's own loop is per frame anyway
            if decide:  # a transition played whole from standing (as the walk will decide)
                decide = False
                asked = self._asked(frames * dt, top)
                pick = transitions.choose(played, st, path, fps, self.steering.max_decel, TURN_IN_PLACE, STAY_M, asked) \
                    if st.speed < 1e-9 else None
                if pick is not None:
                    frames += int(round(transitions.handover_s(pick, fps) * fps))
                    st.go_on_from(transitions.end_state(pick, transitions.placement(pick, st.x, st.z, st.heading, asked), fps))
                    decide = pick.transition == "turn"
                    if paced is not None and pick.transition == "start":
                        paced.phase = transitions.start_phase(pick, fps, half)
                    continue
            row = self.steering.step(st, frames * dt, dt, top=top)
            if paced is not None:  # the gait's phase, paced as the walk will be
                last_x, last_z = last[0] - st.x, last[1] - st.z
                bearing = (math.atan2(last_x, last_z) - st.heading + math.pi) % (2.0 * math.pi) - math.pi
                factor = paced.factor(st.speed, math.hypot(last_x, last_z), bearing, self._asked(frames * dt, top)) \
                    if row[4] > 0.5 else 1.0
                paced.phase = (paced.phase + dt * factor * paced.cadence(st.speed)) % 1.0
            frames += 1
            stop = transitions.stop_due(stops, st, last, fps) if stops and st.waypoint == len(path) - 1 else None
            if stop is not None:  # where it is as far from the point as a stop clip travels (the walk's own
                # choice waits for the clip's gait phase, within a stride of here)
                frames += int(round(transitions.handover_s(stop, fps) * fps))
                st.x, st.z, st.speed, st.turn = float(last[0]), float(last[1]), 0.0, 0.0
                st.heading += stop.parameters["turn"]
                stopped = True
                break
            if st.waypoint == len(path) - 1 and st.speed < 1e-6 and \
                    math.hypot(st.x - last[0], st.z - last[1]) < STAY_M:
                break
        else:
            return None
        walks = [c for c in space.group("locomotion") if c.role != "idle" and c.parameters["forward_speed"] > 0.0] if top else []
        slowest = min(walks, key=lambda c: c.parameters["forward_speed"]).keys if walks else (0.0, 0.0, 1.0)
        # A stop clip begins at its gait phase, within a stride of where the plan has it begin.
        late = max(c.keys[2] - c.keys[0] for c in walks) if stopped else 0.0
        idle = any(c.role == "idle" for c in space.group("locomotion"))
        steps = 0.5 * (2 if idle else STOP_LANDINGS) * (slowest[2] - slowest[0]) / STOP_CADENCE  # the stop's last steps
        return WalkPlan(frames * dt, frames * dt + steps + SETTLE_S + late, st)

    def handover(self, state: dict) -> dict:
        """A walk following another goes on from its :class:`~.state.LocomotionState` (where it is, heading,
        speed, gait phase, planted feet), a copy; only its path starts afresh, at its first point."""
        walk = state.get(LocomotionState)
        return {} if walk is None else {LocomotionState: replace(copy.deepcopy(walk), waypoint=0)}

    def at_rest(self, state: dict) -> bool:
        """At rest once the stop steps are over (both feet landed under the body) and the idle has fully
        faded in; a walk not evaluated yet (no :class:`~.state.LocomotionState`) counts as at rest."""
        walk = state.get(LocomotionState)
        return walk is None or (walk.settled and walk.idle_frames_left == 0.0)

    def bind(self, rig, report) -> LocomotionBinding:
        from infuse.packs import space_on  # packs load lazily: importing a plugin stays cheap

        space = space_on(rig, self.pack)
        if space.kind != "locomotion" or "locomotion" not in space.tessellations:
            raise UsageError(f"pack {space.pack!r} is not a locomotion pack")
        clips = space.group("locomotion")
        legs = []
        for s in "lr":
            names = (f"{s}_hip", f"{s}_knee", f"{s}_ankle")
            if all(rig.joint(n) is not None for n in names):
                ball = rig.joint(f"{s}_forefoot")
                ball = rig.joint(f"{s}_toe") if ball is None else ball
                legs.append(tuple(rig.joint(n) for n in names) + (ball,))
        if self.pin_feet and len(legs) < 2:
            report("no mapped hips, knees and ankles: feet are not pinned")
        if not clips:
            raise MissingFeatureError(None, f"pack {space.pack!r} has no locomotion cycles")
        pelvis = rig.joint("base") or 0
        prepared = rig.asset_state_of(PreparedWalks)
        key = (space.pack, _space_content(space), tuple(legs), pelvis)
        cached = prepared.get(key)
        if cached is None or cached[1] is not rig.skeleton:
            for other in [k for k in prepared if k[0] == key[0] and k[2:] == key[2:] and k != key]:
                del prepared[other]  # a space infused otherwise takes its place
            cached = prepared[key] = (space, rig.skeleton, _prepare(space, clips, rig.skeleton, legs, pelvis))
        return cached[2]

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """Evaluate every walk of the block. Each drives its blend (:meth:`_drive`), the work it asks for
        (:class:`Ask`: its blend weights, its blend, its shorter steps) done at once for every walk asking
        the same of one binding, their frames stacked; then the walks of characters alike in skeleton,
        legs and feet (:func:`_stack_key`: one asset, one pack) have their feet pinned and kept above the
        ground together, their frames stacked (one forward kinematics and one leg IK for them all: a block
        of one frame costs about the same for one walk as for several), the feet held alike and the legs'
        leg IK of every such group in one go; then each writes its pose, in the jobs' order."""
        drives = [job.controller._drive(job, block) for job in jobs]
        asked: dict[int, Ask] = {}
        done: dict[int, tuple | None] = {}
        for n, drive in enumerate(drives):
            _resume(n, drive, None, asked, done)
        while asked:  # the work asked for, together where it can be
            asking: dict[tuple, list[int]] = {}
            for n, ask in asked.items():
                asking.setdefault((ask.work, ask.key), []).append(n)
            now, asked = asked, {}
            for members in asking.values():
                asks = [now[n] for n in members]
                rows = asks[0].rows if len(asks) == 1 else \
                    tuple(None if a[0] is None else np.concatenate(a) for a in zip(*(ask.rows for ask in asks)))
                out = asks[0].work(*asks[0].shared, *rows, *(list(a) for a in zip(*(ask.walk for ask in asks))))
                ends = [0, *itertools.accumulate(len(ask.rows[0]) for ask in asks)]
                for n, a, e in zip(members, ends[:-1], ends[1:]):
                    _resume(n, drives[n], tuple(None if x is None else x[a:e] for x in out), asked, done)
        driven = [(job, done[n]) for n, job in enumerate(jobs)]
        groups: dict[tuple, list] = {}
        for job, walk in driven:
            if walk is not None:
                key = (_stack_key(job.binding), job.controller.pin_feet, walk[1][2] is None)
                groups.setdefault(key, []).append((job, walk[1]))
        dt = 1.0 / block.fps
        poses = {}
        pinned = []  # each group's binding, walks, pose and its pinning (:meth:`_pin`, or None)
        for group in groups.values():
            b: LocomotionBinding = group[0][0].binding
            parts = list(zip(*(p for _, p in group)))  # each walk's rotations, root, translations or None, ...
            rot, root, contact, forward, spun, made = (np.concatenate(parts[k]) for k in (0, 1, 3, 4, 5, 6))
            jt = None if parts[2][0] is None else np.concatenate(parts[2])
            ends = [0, *itertools.accumulate(len(p[0]) for _, p in group)]
            runs = [(job.state_of(LocomotionState), a, e) for (job, _), a, e in zip(group, ends[:-1], ends[1:])]
            pinning = None
            if group[0][0].controller.pin_feet and len(b.legs) == 2:
                pinning = cls._pin(b, runs, rot, root, jt, contact, forward, dt, spun, made)
            pinned.append((b, group, runs, rot, root, jt, pinning))
        # Every group's feet held in one go, and their legs in one leg IK (the arithmetic on all their
        # frames at once), then the feet kept up.
        steps = [None if pinning is None else _advance(pinning) for *_, pinning in pinned]
        _hold_all([holding for done, holding in (step for step in steps if step is not None) if not done], dt)
        legs_of = [None if step is None or pinning is None else step[1] if step[0] else _advance(pinning)[1]
                   for (*_, pinning), step in zip(pinned, steps)]
        solved = iter(solve_limb_ends_together([legs for legs in legs_of if legs is not None]))
        for (b, group, runs, rot, root, jt, _), legs in zip(pinned, legs_of):
            feet = None
            if legs is not None:
                _, above, ankles = next(solved)
                if b.floors is not None and above is not None and ankles is not None:
                    feet = _feet_below(b.skeleton, b.floors, rot, jt, above, ankles)
            if b.floors is not None:
                _keep_feet_up(b.skeleton, b.floors, rot, root, jt, runs, dt, feet)
            for (job, _), (_, a, e) in zip(group, runs):
                poses[id(job)] = (rot[a:e], root[a:e], None if jt is None else jt[a:e])
        for job, walk in driven:
            if walk is not None:
                cls._write(job, walk[0], *poses[id(job)])

    def _drive(self, job, block):
        """The walk's state carried through the block and its pose before the feet are pinned: its
        active frames (A,) of the block and the parts :meth:`_steered` gives over them, or None when
        the walk has not begun. A generator: it yields the work :meth:`_steered` asks for (:class:`Ask`)
        and takes it back done (:meth:`evaluate` does it), and returns that."""
        b: LocomotionBinding = job.binding
        active = np.nonzero(job.local_times >= -1e-9)[0]
        if not active.size:
            return None
        st = job.state_of(LocomotionState)
        dt = 1.0 / block.fps
        times = job.local_times[active]
        # The block in parts, in time order: transition clips played whole, and the steered blend.
        parts, i = [], 0
        while i < len(times):
            if st.playing is None and st.chooser != id(self):
                st.chooser = id(self)  # a walk decides once it begins (again after a turn on the spot)
                if st.settled and st.speed < 1e-9 and len(b.legs) == 2:
                    asked = self._asked(float(times[i]), b.limit)
                    pick = transitions.choose(b.played, st, self.steering.path, block.fps, self.steering.max_decel,
                                              TURN_IN_PLACE, STAY_M, asked)
                    if pick is not None:
                        st.playing = (pick.name, float(times[i]), transitions.placement(pick, st.x, st.z, st.heading, asked))
            start, part, handing = i, None, None
            if st.playing is None:
                # A shallow copy to come back to: the steered blend replaces the state's fields, never
                # writes into its arrays (only the feet's pinning does, after every walk is driven).
                before = copy.copy(st) if b.stops and self.steering.path is not None else None
                part = yield from self._steered(b, st, times[i:], dt, job.report)
                stop = None if before is None else self._stop_at(b, before, st, block.fps, dt)
                if stop is not None:  # walk up to where the stop begins, then play it
                    f, clip, place = stop
                    st.restore(before)
                    part = (yield from self._steered(b, st, times[i:i + f], dt, job.report)) if f else None
                    st.trace = None
                    st.playing = (clip.name, float(times[i + f]), place)
                    i += f
                else:
                    i = len(times)
            else:
                name, began, place = st.playing
                clip = b.space.clips[name]
                i += int(np.count_nonzero(times[i:] < began + transitions.handover_s(clip, block.fps) - 1e-9))
                if i > start:
                    part = self._played(b, st, clip, place, times[start:i] - began, block.fps)
                handing = (clip, began, place) if i < len(times) else None
            if part is not None:
                parts.append(self._faded(b, st, part, times[start:i], block.fps))
            if handing is not None:
                self._hand_over(b, st, handing[0], handing[2], block.fps)
                st.fading = (handing[0].name, handing[1], handing[2])
        if len(parts) == 1:  # the block in one part (most blocks)
            return active, parts[0]
        return active, tuple(None if a[0] is None else np.concatenate(a) for a in zip(*parts))

    def _asked(self, t: float, top) -> float:
        """The speed (m/s) asked at the activity's time ``t`` seconds, kept to ``top(0)`` (the pack's
        top speed straight ahead) where given."""
        asked = self.steering.requests()[0](t)
        return min(asked, float(top(0.0))) if top is not None else asked

    def _stop_at(self, b: LocomotionBinding, before: LocomotionState, st: LocomotionState, fps: float, dt: float):
        """Where a steered stretch (from state ``before`` to ``st``, its frames in ``st.trace``)
        would hand over to a stop clip: the first frame on the way to the path's last point, heading
        for it within :data:`~.transitions.STOP_BEARING`, at about the clip's speed where it begins
        (within :data:`~.transitions.STOP_SPEEDS`), at the clip's gait phase where it begins, and as
        far from the point as the clip travels (its travel scaled within :data:`~.transitions.STOP_SCALES`,
        and no more than a stride later would need). Returns (frame, clip, placement) or None."""
        path = self.steering.path
        trace, st.trace = st.trace, None
        if path is None or trace is None or st.waypoint != len(path) - 1:
            return None
        x, z, heading, speed, phase, advance = trace
        last = path[-1]
        dist = np.hypot(last[0] - x, last[1] - z)
        off = np.abs((np.arctan2(last[0] - x, last[1] - z) - heading + np.pi) % (2.0 * np.pi) - np.pi)
        best = None
        for clip in b.stops:
            at, travel = _stop_marks(b, clip, fps)
            if at is None:
                continue
            # The clip's phase reached between this frame and the next (each frame's own advance, so
            # the frame found is the same whichever frames are evaluated together).
            ok = ((np.mod(at - phase, 1.0) < advance) & (advance < 0.5)
                  & (off < transitions.STOP_BEARING) & (np.abs(np.log(np.maximum(speed, 1e-9) / clip.parameters["speed_start"])) < math.log(transitions.STOP_SPEEDS))
                  & (np.abs(np.log(np.maximum(dist, 1e-9) / travel)) < math.log(transitions.STOP_SCALES)))
            # A stride later it may have about as far to go as the clip travels: then it waits for that.
            scale = np.log(np.maximum(dist, 1e-9) / travel)
            stride = speed * dt / np.maximum(advance, 1e-9)
            later = np.log(np.maximum(dist - stride, 1e-9) / travel)
            hits = np.flatnonzero(ok & (np.abs(scale) <= np.abs(later)))
            if hits.size and (best is None or hits[0] < best[0]):
                f = int(hits[0])
                best = (f, clip, transitions.stop_placement(clip, fps, float(x[f]), float(z[f]), last))
        return best

    def _played(self, b: LocomotionBinding, st: LocomotionState, clip, place, local, fps: float):
        """A transition ``clip`` placed by ``place`` (:func:`~.transitions.placement`) at its times
        ``local`` (F,) seconds, at ``fps``: the parts :meth:`_steered` gives; ``st``'s ``x``, ``z`` and
        ``heading`` follow it."""
        rot, root, jt, _ = sample_motion(b.played_motions[clip.name], local, loop=False)
        turn, root0, at, scale, _ = place
        q = yaw(turn)
        rot = np.array(rot)
        rot[:, 0] = quat.multiply(q, rot[:, 0])
        # The pelvis's ground travel is eased (a start's) and scaled (a stop's), the root carried with the pelvis.
        pelvis = transitions.pelvis_at(clip, local)
        rel = root - np.array([root0[0], 0.0, root0[1]])
        rel[:, [0, 2]] = root[:, [0, 2]] - pelvis + scale * (transitions.placed_pelvis(clip, place, local, fps) - root0)
        root = quat.rotate(q, rel) + np.array([at[0], 0.0, at[1]])
        if b.table.translations is None:
            jt = None
        elif jt is None:
            jt = np.repeat(clip.motion.local_translations()[:1], len(local), axis=0)
        frames = np.clip(np.rint(local * clip.motion.fps).astype(np.int64), 0, clip.motion.num_frames - 1)
        contact = b.played_phases[clip.name][frames].astype(np.float64)
        facing = turn + b.played_facing[clip.name][frames]
        forward = np.stack((np.sin(facing), np.zeros_like(facing), np.cos(facing)), axis=-1)
        ground = transitions.placed_root(clip, place, local[-1:], fps)[0]
        st.x, st.z, st.heading = float(ground[0]), float(ground[1]), float(facing[-1])
        return rot, root, jt, contact, forward, np.full(len(local), st.spun), np.zeros(len(local), dtype=bool)

    def _hand_over(self, b: LocomotionBinding, st: LocomotionState, clip, place, fps: float) -> None:
        """The steering takes over from transition ``clip`` (see :mod:`.transitions`): its state where the
        clip hands over; after a start, the gait's phase from the clip's last strikes (left at 0, right
        at 0.5), walking; after a turn on the spot, standing, to decide again; after a stop, standing there."""
        st.go_on_from(transitions.end_state(clip, place, fps))
        st.playing, st.blend = None, None
        if clip.transition != "start":  # standing: after a turn it decides again, after a stop it is there
            st.settled, st.idle_frames_left, st.landings, st.to_go = True, 0.0, -1, -1.0
            st.chooser = None if clip.transition == "turn" else id(self)
            return
        phase = transitions.start_phase(clip, fps, 0.5 * float(b.durations[np.argmax(b.slowest)]))
        st.settled, st.idle_frames_left, st.landings, st.to_go, st.phase = False, _settle_frames(1.0 / fps), -1, -1.0, float(phase)

    def _faded(self, b: LocomotionBinding, st: LocomotionState, part, times, fps: float):
        """``part`` (see :meth:`_steered`) at the activity's ``times`` (F,) with the transition that
        handed over before it fading out over it (its last :data:`~.transitions.HANDOVER_S`), at ``fps``."""
        if st.fading is None:
            return part
        name, began, place = st.fading
        clip = b.space.clips[name]
        local = times - began
        mixing = np.nonzero(local < clip.duration)[0]
        if mixing.size < len(local):
            st.fading = None
        if not mixing.size:
            return part
        rot, root, jt, contact, forward, spun, made = part
        rot, root, contact, forward = np.array(rot), np.array(root), np.array(contact), np.array(forward)
        jt = None if jt is None else np.array(jt)
        was = self._played(b, LocomotionState(), clip, place, local[mixing], fps)
        on = transitions.handover_s(clip, fps)
        w = footing.smoothstep((local[mixing] - on) / max(clip.duration - on, 1e-9))
        # The pelvis goes straight from the clip's to what follows (joint 0 may sit away from it: mixed
        # about joint 0, the pelvis would swing by the turn between the two).
        _, before = chain_fk(b.skeleton, was[0], was[1], was[2], [b.pelvis])
        _, after = chain_fk(b.skeleton, rot[mixing], root[mixing], None if jt is None else jt[mixing], [b.pelvis])
        walk = rot[mixing]
        rot[mixing] = quat.slerp(was[0], walk, w[:, None])
        below = np.flatnonzero(b.skeleton.parents == 0)
        if b.pelvis != 0 and below.size == 1:
            # Joint 0 above the pelvis with one child (see canonical_clip): the clip and the walk may split
            # the facing between the two differently; the child's turn from the root is mixed as one.
            c = int(below[0])
            child = quat.slerp(quat.multiply(was[0][:, 0], was[0][:, c]), quat.multiply(walk[:, 0], walk[:, c]), w)
            rot[mixing, c] = quat.multiply(quat.conjugate(rot[mixing, 0]), child)
        root[mixing] = was[1] + (root[mixing] - was[1]) * w[:, None]
        if jt is not None:
            jt[mixing] = was[2] + (jt[mixing] - was[2]) * w[:, None, None]
        _, mixed_pelvis = chain_fk(b.skeleton, rot[mixing], root[mixing], None if jt is None else jt[mixing], [b.pelvis])
        root[mixing] += before[:, 0] + (after[:, 0] - before[:, 0]) * w[:, None] - mixed_pelvis[:, 0]
        contact[mixing] = was[3] + (contact[mixing] - was[3]) * w[:, None, None]
        mixed = was[4] + (forward[mixing] - was[4]) * w[:, None]
        forward[mixing] = mixed / np.maximum(np.linalg.norm(mixed, axis=-1, keepdims=True), 1e-9)
        return rot, root, jt, contact, forward, spun, made

    def _steered(self, b: LocomotionBinding, st: LocomotionState, times, dt, report):
        """The steered blend at the activity's ``times`` (F,) seconds: rotations (F, J, 4), root (F, 3),
        joint translations (F, J, 3) or None, contact phases (F, 2, 2), the heading's direction (F, 3),
        the turn spun at the root so far (F,) radians and the frames (F,) bool stepping as no clip does
        (a stop's or a turn on the spot's steps, coming to rest: :func:`_touch_downs`), before the feet
        are pinned. A generator: it yields the work it asks for (:class:`Ask`: the blend driven, placed
        and its steps shortened, :func:`_walked`) and takes it back done."""
        start = (st.x, st.z, st.heading)
        req = self.steering.run(st, times, dt, top=b.limit)
        if st.capped is not None and not st.warned:
            asked, done, towards = st.capped
            report(f"asked {asked:.2f} m/s {_towards(towards)}; pack {b.space.pack!r} realizes at most {done:.2f} m/s "
                       f"that way: {'walking at ' + format(done, '.2f') + ' m/s' if done > 0 else 'not moving'}")
            st.warned = True
        rot, root, jt, contact, forward, spun, made = yield Ask(_walked, (id(b),), (b, dt), (times, req),
                                                               (st, self, start, len(times)))
        return rot, root, jt, contact, forward, spun, made

    @staticmethod
    def _write(job, active, rot, root, jt) -> None:
        """Write the walk's rotations (A, J, 4), root (A, 3) and joint translations (A, J, 3) or None
        on its ``active`` (A,) frames of the block into the job's pose."""
        pose = job.pose
        weight = job.weight
        if active.size < len(weight):  # the walk starts inside the block: the frames before keep the pose
            weight = np.where(job.local_times >= -1e-9, weight, 0.0)
            rot = _scatter(pose.local_rotations[:1], active, rot, len(weight))
            root = _scatter(pose.root_translations, active, root, len(weight))
            if jt is not None:
                jt = _scatter(pose.joint_translations if pose.joint_translations is not None
                              else job.rig.skeleton.rest_translations[None], active, jt, len(weight))
        pose.set_rotations(np.arange(rot.shape[1]), rot, weight, job.mode)
        pose.set_root(root, weight, job.mode)
        if jt is not None:
            pose.set_translations(np.arange(1, jt.shape[1]), jt[:, 1:], weight, job.mode)

    @staticmethod
    def _blend(b: LocomotionBinding, w, orders, phase, standing, times, half_frame):
        """Weighted, sign-aligned rotations, root offsets, joint translations, foot contact phases
        (F, 2, 2) and stance shares (F, 2) (:func:`~.phase_keys.stance_of`) of the moving clips
        (weights ``w`` (F, N)) at blend ``phase``, each leg time-warped by its foot's events; then
        faded into the idle clips by ``standing`` (F,) (played at the activity's ``times`` (F,), None
        where nothing fades into an idle).
        ``half_frame`` (F,): half a frame's advance of the phase. ``orders`` (F, N): each frame's clips
        in the order its walk sums them (:func:`_clips_of`), then -1: frames of several walks blending
        other clips are blended at once, each summed as its walk alone would sum it (a clip another
        walk brings in weighs nothing on it and adds zeros)."""
        used, of, w, stepping_share, events, keys, count, frames, sample_of, weight_of = _summed(b, w, orders)
        stepping, feet = of.stepping, of.feet
        # Each clip's phases (U, 3, F): the body's at the blend phase, each leg's at its foot's phase;
        # then their times in the clips.
        phases = np.empty((used.size, 3, len(phase)))
        phases[:] = phase
        if of.foot_events is not None:
            phases[feet, 1:] = np.swapaxes(foot_phase(of.foot_events, events, phase, keys), 1, 2)
        clock = warp(of.keys, phases)
        fade = of.idle if standing.max() > 1e-6 else of.idle[:0]
        if fade.size:  # the idle clips, played at the activity's times
            clock = np.concatenate((clock, np.broadcast_to(times, (fade.size, 3, len(times)))))
        # Component-major samples: rotations (4, U, F, J), roots (3, U, F), joint translations (3, U, F, J).
        rot, root, jt = b.table.sample(of.with_idle if fade.size else used, clock, b.limbs)
        rot_of, root_of = rot[:, sample_of, frames], root[:, sample_of, frames]  # (4, F, U', J), (3, F, U')
        jt_of = None if jt is None else jt[:, sample_of, frames]
        acc = _accumulate(None, rot_of[:, :, 0], root_of[:, :, 0], None if jt_of is None else jt_of[:, :, 0], weight_of[:, 0])
        for u in range(1, count):
            acc = _accumulate(acc, rot_of[:, :, u], root_of[:, :, u], None if jt_of is None else jt_of[:, :, u], weight_of[:, u])
        if not of.all_stepping:  # clips without foot events: their own contact flags, in each walk's order
            contact, support = np.zeros((len(phase), 2, 2)), np.zeros((len(phase), 2))
            flags = np.zeros((used.size, len(phase), 2, 2))
            for u in np.flatnonzero(~feet).tolist():
                flags[u] = Locomotion._phases(b, used[u], clock[u, 0])
            stepless = weight_of * ~feet[sample_of]
            for u in range(count):
                if stepless[:, u].any():
                    mine = flags[sample_of[:, u], frames[:, 0]]
                    contact += mine * stepless[:, u, None, None]
                    support += mine.max(axis=2) * stepless[:, u, None]
        if stepping.size:
            # A frame holds the half-frame either side of it (as the events were found): a foot lands
            # in the frame whose span holds its strike, and is pinned from there.
            early = events.copy()
            early[:, :, 0] -= half_frame[:, None]
            flags, share = stance_of(early, phase, HANDOVER, STANCE_RAMP)
            if of.all_stepping:  # (their sums start here)
                contact, support = flags * stepping_share[:, None, None], share * stepping_share[:, None]
            else:
                contact += flags * stepping_share[:, None, None]
                support += share * stepping_share[:, None]
        if fade.size:
            share = standing / fade.size
            kept = 1.0 - standing
            acc = (acc[0] * kept[:, None], acc[1] * kept, None if acc[2] is None else acc[2] * kept[:, None])
            contact *= kept[:, None, None]
            support *= kept[:, None]
            for u, i in enumerate(fade, start=used.size):
                acc = _accumulate(acc, rot[:, u], root[:, u], None if jt is None else jt[:, u], share)
                flags = Locomotion._phases(b, i, times)
                contact += flags * share[:, None, None]
                support += flags.max(axis=2) * share[:, None]
        rot, root, jt = acc
        out = np.empty(rot.shape[1:] + (4,))
        np.divide(rot, np.sqrt(np.square(rot).sum(axis=0)), out=out.transpose(2, 0, 1))  # normalized, frame-major
        return out, np.ascontiguousarray(root.T), None if jt is None else np.ascontiguousarray(jt.transpose(1, 2, 0)), contact, support

    @staticmethod
    def _phases(b, i, t) -> np.ndarray:
        """(F, 2, 2) heel and ball contact flags of clip ``i`` at its times ``t`` (seconds, looping)."""
        clip = b.clips[i]
        motion = clip.motion
        frame = np.rint((t % max(motion.duration, 1e-9)) * motion.fps).astype(np.int64)
        return clip.phases[np.minimum(frame, len(clip.phases) - 1)]

    @staticmethod
    def _shorten(b: LocomotionBinding, w, stride, rot, root, jt, turn_q, forward, settle, down, laid) -> None:
        """Shorter steps: each ankle's horizontal offset from the hips scaled by ``stride`` (F,) about
        its cycle mean (the blend ``w`` of the clips'), its height and the foot's rotation kept, by leg
        IK; the other joints' swing about their cycle mean scaled alike (smaller arm swing). While
        stopping, ``settle`` (F,) in [0, 1] moves that mean toward the idle's stance (the last steps
        land where the feet stand) and lays the feet down: each foot turns toward lying as in the
        idle, its ankle toward its lowest height, fully in the middle of a stance and not in the
        swing (a foot that stepped low and slow would shuffle along the ground): its height by
        ``down`` (F, 2) (how far into the stop times its stance share), its orientation by ``laid``
        (F, 2) (the same, let go slower), so nothing jumps at strike or toe off.
        ``turn_q`` (F, 4) turns the facing frame to the heading, ``forward`` (F, 3) is the heading's direction."""
        stance_feet = b.stance_feet
        body, frames = b.body_columns, len(rot)
        means, centre, low = _cycle_means(b, w)
        mean = means.copy()
        mean[:, 0] = quat.multiply(turn_q, mean[:, 0])  # the root's mean in the facing frame, turned to the heading
        calmer = quat.slerp(mean, rot[:, body], stride[:, None])
        # One FK of the legs (hip, knee, ankle, the hip's parent, ball; (2F, 2, 5)) for the pose as it is
        # (the goals) and with the calmer body (the leg IK's chains), the two stacked.
        both = np.concatenate((rot, rot))
        both[frames:, body] = calmer
        g_rot, g_pos = chain_fk(b.skeleton, both, np.concatenate((root, root)), None if jt is None else np.concatenate((jt, jt)),
                                b.pin_joints)
        g_rot, g_pos = g_rot.reshape(2 * frames, 2, 5, 4), g_pos.reshape(2 * frames, 2, 5, 3)
        pos = g_pos[:frames]
        feet = g_rot[:frames, :, 2:3]  # (F, 2, 1 or 2, 4): each foot's ankle (and ball) global rotations to keep
        if stance_feet is not None:
            if _any(laid):
                flat = quat.multiply(turn_q[:, None, None], stance_feet)
                feet = quat.slerp(g_rot[:frames, :, [2, 4]], flat, laid[:, :, None])
            else:  # nothing laid down (walking slower, not stopping): the slerp's start, as it leaves it
                feet = quat.normalize(g_rot[:frames, :, [2, 4]])
        hips = 0.5 * (pos[:, 0, 0] + pos[:, 1, 0])
        rot[:, body] = calmer
        # Each ankle's goal (F, 2, 3): its offset from the hips scaled about the (settling) cycle mean.
        if b.has_idle and _any(settle):
            centre = centre + settle[:, None, None] * (b.ankle_means[np.argmax(b.idle)] - centre)
        centre = quat.rotate(turn_q[:, None], centre)
        goal = hips[:, None] + centre + stride[:, None, None] * (pos[:, :, 2] - hips[:, None] - centre)
        goal[..., 1] = low + (pos[:, :, 2, 1] - low) * (1.0 - down)
        # The legs are apart: both in one solve. The feet keep their animated orientation, not the one
        # the calmer pelvis would give them (a planted foot would turn about its pinned ankle).
        shorter = np.abs(stride - 1.0) > 1e-6  # the frames whose steps are shortened (all, mostly: no weights then)
        solve_limb(b.skeleton, rot, root, jt, b.leg_limbs, goal, weight=None if _all(shorter) else shorter.astype(float),
                   pole=forward, end_rotation=feet[:, :, 0], chains=(g_rot[frames:, :, :4], g_pos[frames:, :, :4]), distance=False)
        if stance_feet is not None and b.balls_on_ankles.size:
            k = b.balls_on_ankles
            rot[:, b.balls[k]] = quat.multiply(quat.conjugate(feet[:, k, 0]), feet[:, k, 1])

    @staticmethod
    def _pin(b: LocomotionBinding, runs, rot, root, jt, contact, forward, dt, spun, made) -> Generator[Holding, None, LimbSolve | None]:
        """Pin planted feet by leg IK: the sole under the heel while the heel is down (a foot landing
        turned up rolls down about it, its ankle swinging over it; the ankle itself where the binding
        knows no heel, ``b.heel_levers``), the ball while only it is down (the foot pivoting about it,
        its heel rising further when the leg would not reach). A planted foot does not turn with the
        part of the heading's turn spun at the root (turning on the spot, the body turns over it; the
        clips' own turning shows in their feet already), and on its ball
        it only pitches (about the horizontal axis across it, rolling over its ball), keeping the yaw
        and roll it had as the ball took over: the animation's twist or roll of a foot on the ground
        (a take's, a blend's) would swing the ankle about the pinned ball. The corrections fade out
        after toe off. ``contact`` (F, 2, 2); ``forward`` (F, 3) the heading's direction; ``spun``
        (F,) the turn spun at the root so far (radians). ``runs``: the walks whose frames the arrays
        stack, each as its state and its frames (start, end). A swinging foot of the frames ``made`` (F,)
        lands where it touches the ground (:func:`_touch_downs`). A generator: it yields the feet held
        alike through all their walk's frames (:class:`Holding`, held with the other groups' by
        :meth:`evaluate`, :func:`_hold_all`) and returns the leg IK that brings both legs to their goals
        (a :class:`~infuse.runtime.limb_ik.LimbSolve` on ``rot``, solved with the other groups'), or None
        where no foot is pinned."""
        # One FK for both legs before either is pinned: hip, knee, ankle, the hip's parent, the ball
        # (F, 2, 5). Each leg's IK leaves the other leg as it is, and turning a foot leaves its leg.
        g_rot_all, g_pos_all = chain_fk(b.skeleton, rot, root, jt, b.pin_joints)
        g_rot_all, g_pos_all = g_rot_all.reshape(len(rot), 2, 5, 4), g_pos_all.reshape(len(rot), 2, 5, 3)
        anchors_all = footing.anchors(contact[..., 0], contact[..., 1], b.has_ball, _heels_up(b, g_rot_all, g_pos_all))
        # (F, 2) held by the ball for the idle's sake: because the pose lifted the heel the flags hold
        # down (the idle's fading share holding a foot the walk's has lifted), or by flags that are that
        # share (neither 0 nor 1) of a foot on its ball: a blend of a standing leg and a stepping one.
        on_ball = anchors_all == footing.BALL
        posed_all = on_ball & (contact[..., 1] <= contact[..., 0])
        shared = np.zeros_like(on_ball)  # (F, 2) held by the idle's fading share
        if _any(b.idle):
            shared = on_ball & ((contact > 1e-6) & (contact < 1.0 - 1e-6)).any(axis=-1)
            posed_all |= shared
        goals = g_pos_all[:, :, 2].copy()
        feet_all = g_pos_all[:, :, 2::2]  # (F, 2, 2, 3) ankle and ball
        weights = np.zeros(anchors_all.shape)
        rises = np.zeros(goals.shape)  # extra heel rise about the ball, rotation vector in the foot's frame
        turns = np.zeros(anchors_all.shape + (4,))  # (F, 2, 4) world turn of each foot from the animation's to the pinned
        turns[..., 3] = 1.0
        touching_all = np.zeros(anchors_all.shape, dtype=bool)  # (F, 2) held where it touched, before its blend's strike
        touched = _touch_downs(b, runs, anchors_all, feet_all, made, dt)
        if _any(touched):
            touching_all = touched > 0
            anchors_all = np.where(touching_all, touched, anchors_all)
            posed_all |= touched == footing.BALL
        # The feet held through all their walk's frames by what held them a frame before: those held
        # alike (the anchor, as many frames) in one go, all walks together (the common case by far).
        starts = np.array([a0 for _, a0, _ in runs])
        held_before = np.array([st.anchor for st, _, _ in runs])  # (R, 2)
        anchor_before = np.concatenate((anchors_all[:1], anchors_all[:-1]))
        anchor_before[starts] = held_before
        steady = ~np.logical_or.reduceat(anchors_all != anchor_before, starts, axis=0) & (held_before != footing.FREE)
        # Held to the block's end: each as (walk, foot, first frame, frames, anchor, carried from (None: its
        # walk's state), held (below) with the others held as many frames.
        holds: list[tuple[int, int, int, int, int, np.ndarray | None]] = \
            [(i // 2, i % 2, runs[i // 2][1], runs[i // 2][2] - runs[i // 2][1], kind, None)
             for i, kind in zip(np.flatnonzero(steady).tolist(), held_before[steady].tolist())]
        for r in np.flatnonzero(~steady.all(axis=1)).tolist():  # the walks with a foot held otherwise
            st, a0, a1 = runs[r]
            g_rot, g_pos, anchors, touching = g_rot_all[a0:a1], g_pos_all[a0:a1], anchors_all[a0:a1], touching_all[a0:a1]
            frames = a1 - a0
            feet_pos = feet_all[a0:a1]
            ankle_pos = g_pos[:, :, 2]
            # The feet one frame earlier (from the last block at the first frame).
            before = np.concatenate((st.last[None], feet_pos[:-1]))
            changes = anchors != np.concatenate((st.anchor[None], anchors[:-1]))
            changing = changes.any(axis=0).tolist()
            heading, turned = forward[a0:a1], spun[a0:a1]
            for k in range(2):
                if steady[r, k]:
                    continue
                goal, weight, rise, ankle, turn = goals[a0:a1, k], weights[a0:a1, k], rises[a0:a1, k], ankle_pos[:, k], turns[a0:a1, k]
                prev = int(st.anchor[k])
                # Views of the carried state: never written in place here, only replaced (stored back below),
                # the planted foot's values in FOOT_VALUES' order.
                pin, landed, landed_as, across, landed_spun, toes_up, foot_heading, held_swivel, offset, ball_offset, lifted, left, \
                    let_go = (st.feet[k, at] for at, _ in FOOT_VALUES.values())
                landed_spun, toes_up, foot_heading, held_swivel = float(landed_spun), float(toes_up), float(foot_heading), float(held_swivel)
                released, free_s, clear = float(st.released[k]), float(st.free_s[k]), bool(st.clear[k])
                lever = feet_pos[:, k, 1] - ankle  # (F, 3) the animated ankle to ball
                bounds = sorted({0, frames, *np.flatnonzero(changes[:, k]).tolist()}) if changing[k] else [0, frames]
                i = 0
                while i < len(bounds) - 1:  # each stretch held alike (one may split: a ball aloft, below)
                    s, e = bounds[i], bounds[i + 1]
                    i += 1
                    kind = int(anchors[s, k])
                    if kind == footing.FREE and prev == footing.FREE and released >= RELEASE_S:
                        # Let go long enough ago that its corrections have faded out (and were dropped then):
                        # it swings as the animation has it (no weight, no turn), only its clocks run on,
                        # as below with the ball up on every frame.
                        quick = np.where(made[a0 + s:a0 + e], RELEASE_S / STEP_RELEASE_S, 1.0)
                        released = float((released + dt * np.cumsum(quick))[-1])
                        free_s = float((round(free_s / dt) + (e - s)) * dt)
                        continue
                    if kind == footing.FREE:
                        if prev != footing.FREE:
                            released, free_s = 0.0, 0.0
                            clear = bool(shared[a0 + s - 1, k] if s > 0 else st.shared[k])
                        rises_by = b.grounded_m * (SHARE_CLEAR / GROUNDED if clear else 1.0)
                        # Processed piece by piece, each ending at a frame whose ball is still held (its heel's
                        # rise and where it leaves the ball carry to the frames after it), as frame by frame:
                        # the same frames whatever the block. The time in the air counts whole frames.
                        end = e
                        while s < end:
                            # The ball stays where it was let go until it leaves the ground (a take's ball may push
                            # off moving along it), at most HOLD_S, and the release's clock runs from then on.
                            # Once it has left (``released``: time since), it is not held again where the
                            # animation's ball dips back (a long foot's, pitching down as it swings): held
                            # again, the ankle swung back by 17-23 cm for a frame.
                            since = (round(free_s / dt) + np.arange(1, end - s + 1)) * dt
                            up = (feet_pos[s:end, k, 1, 1] + ball_offset[1] > let_go[1] + rises_by) | (since > HOLD_S)
                            up = np.logical_or.accumulate(up | (released > 0.0))
                            e = s + int(np.argmin(up)) + 1 if not _all(up) else end
                            since, up = since[:e - s], up[:e - s]
                            free_s = float(since[-1])
                            down = np.maximum.accumulate(np.where(up, -1, np.arange(e - s)))  # the last frame still down
                            if down[-1] >= 0:
                                held_at = let_go - feet_pos[s + np.maximum(down, 0), k, 1]
                                if clear:  # held along the ground, rising with the animation
                                    held_at[:, 1] = ball_offset[1]
                                ball_offset = np.where((down >= 0)[:, None], held_at, ball_offset)
                            else:
                                ball_offset = ball_offset[None]  # the same on every frame
                            # In the steps of a stop or a turn on the spot (short and slow, landing where they
                            # touch) the correction is gone within STEP_RELEASE_S: faded over RELEASE_S, the foot
                            # came down before it was back under the body, and stood there.
                            quick = np.where(made[a0 + s:a0 + e], RELEASE_S / STEP_RELEASE_S, 1.0)
                            age = released + dt * np.cumsum(up * quick)
                            fade = 1.0 - footing.smoothstep(age / RELEASE_S)
                            # The foot's corrections fade out keeping it rigid: the ball's offset fades and the
                            # ankle hangs from the ball (not the ball from the ankle: the ball leaves the
                            # ground last, and the fading turn would swing it along the ground).
                            turn[s:e] = _share_of(left, fade)
                            hang = quat.rotate(turn[s:e], lever[s:e])
                            if _any(lifted):
                                rise[s:e] = lifted * (1.0 - footing.smoothstep(age / RISE_RELEASE_S))[:, None]
                                # The heel's extra rise (a turn in the corrected foot's frame) turns the lever too.
                                corrected = quat.multiply(turn[s:e], g_rot[s:e, k, 2])
                                hang = quat.rotate(_from_rotvec(quat.rotate(corrected, rise[s:e])), hang)
                            goal[s:e] = feet_pos[s:e, k, 1] + ball_offset * fade[:, None] - hang
                            # A foot far from where the animation has it steps there over an arc, not along the
                            # ground (a foot let go late in its swing, starting to walk after a turn on the spot).
                            goal[s:e, 1] += STEP_ARC * 4.0 * fade * (1.0 - fade) * np.hypot(ball_offset[:, 0], ball_offset[:, 2])
                            # Rising, it lifts before it travels (LIFT_TRAVEL): the take's ball may still drag on.
                            ball = goal[s:e] + hang  # (n, 3) the released ball
                            rise_m = np.minimum(np.hypot(ball[:, 0] - let_go[0], ball[:, 2] - let_go[2]) / LIFT_TRAVEL, LIFT_CLEAR_M)
                            goal[s:e, 1] += np.where(up, fade * np.maximum(rise_m - (ball[:, 1] - let_go[1]), 0.0), 0.0)
                            # Off the ground, kept within reach as a foot without a ball is (below): a ball let go
                            # far behind (a long foot's, pinned where it landed) held the leg straight toward it,
                            # and the knee bent by 18 degrees and the hip turned by 46 in the frame it came back.
                            if _any(up):
                                lifting = s + np.flatnonzero(up)
                                goal[lifting] = footing.within_reach(goal[lifting], g_pos[lifting, k, :3])
                            held = np.nonzero(~up)[0]
                            if held.size:  # still pivoting about the ball held on the ground: the heel rises where the hip cannot reach
                                h = s + held
                                goal[h], more = footing.heel_rise(quat.multiply(turn[h], g_rot[h, k, 2]), g_pos[h, k, :3], goal[h], let_go + 0.0 * goal[h],
                                                                  across)
                                rise[h] += more
                                if held[-1] == e - s - 1:  # the rise the release fades from
                                    lifted = rise[e - 1].copy()
                            ball_offset = ball_offset[-1].copy()
                            weight[s:e] = fade > 0.0
                            released = float(age[-1])
                            if fade[-1] <= 0.0:
                                offset, ball_offset, lifted, left = np.zeros(3), np.zeros(3), np.zeros(3), _IDENTITY.copy()
                            s = e
                    else:
                        if kind == footing.BALL and prev == footing.ANKLE and before[s, k, 1, 1] + ball_offset[1] - feet_pos[s, k, 1, 1] > b.touch_m:
                            # Its ball (corrected) is up in the air where the animation's has come down (a
                            # blend's foot slapping flat about its held heel, its pitch slowed): pinned there
                            # it would hold the foot up and drop it when let go. The heel stays held until
                            # the foot's pitch has caught up with the animation's.
                            pitch, up = _toes_slowed([(b, 1)], quat.multiply(g_rot[None, s:e, k, 2], quat.conjugate(landed)), across[None],
                                                     np.array([toes_up]), dt)
                            lagging = up[0] > -pitch[0]
                            if lagging[0]:
                                kind = footing.ANKLE
                                if not _all(lagging):
                                    e = s + int(np.argmin(lagging))
                                    bounds.insert(i, e)
                        if kind != prev and prev == footing.FREE:
                            # The anchor lands: it stays where the corrected foot puts it now. A ball let go
                            # that has not left the ground since stays where it is held (its offset is from the
                            # animation's ball a frame ago: added to this frame's, the foot moved on by the
                            # animation's step, 3 cm in a frame as a turn on the spot passed to a start).
                            fade = 1.0 - footing.smoothstep(released / RELEASE_S)
                            left = _share_of(left, fade)
                            pin = (feet_pos[s, k, 1] if released > 0.0 else before[s, k, 1]) + ball_offset * fade
                            if kind == footing.ANKLE:  # back from the ball to the heel's sole, along the corrected foot
                                reach = quat.rotate(left, lever[s])
                                pin = pin - reach + _heel_of(b, k, reach)
                        elif kind != prev:
                            # The anchor passes from the heel to the ball (or back): the new one stays
                            # where the corrected foot had it a frame ago (the ball's correction is the
                            # ankle's and the foot's turn about it; the heel's sole, the ankle's and that
                            # turn of the foot as it was then), so the foot does not move on with the
                            # blend's drift at the switch, nor jump by the turn.
                            was = before[s, k]
                            if kind == footing.BALL:
                                pin = was[1] + ball_offset
                            else:
                                pin = was[0] + offset + _heel_of(b, k, quat.rotate(left, was[1] - was[0]))
                        if kind != prev:
                            # The foot's orientation now (corrected as a frame ago), and the axis across it.
                            # Passing from one point to the other, the foot goes on from its pose a frame ago:
                            # the animation's turn since then shows only as the new anchor lets it (on the
                            # ball its pitch), not whole (a foot turning on the spot swung about the ball).
                            landed, landed_spun = g_rot[s, k, 2], turned[s]
                            if prev != footing.FREE:
                                landed = g_rot[s - 1, k, 2] if s > 0 else st.last_rot[k]
                            landed_as = quat.multiply(left, landed)
                            along = quat.rotate(left, feet_pos[s, k, 1] - feet_pos[s, k, 0])  # the corrected foot's
                            along = along if math.hypot(along[0], along[2]) > 1e-6 else heading[s]
                            across = np.array([along[2], 0.0, -along[0]]) / math.hypot(along[0], along[2])
                        heading_from, held_from, toes_from = foot_heading, held_swivel, toes_up
                        if kind == footing.ANKLE and kind != prev:  # the toes and the swivel count anew
                            heading_from, held_from, toes_from = math.nan, 0.0, 0.0
                            if prev == footing.BALL:
                                # From the ball, the swivel counts from the corrected foot a frame ago: the
                                # animation's turn in the frame the heel takes over swept the ball 1 cm.
                                was_reach = quat.rotate(left, before[s, k, 1] - before[s, k, 0])
                                heading_from = math.atan2(was_reach[0], was_reach[2])
                        carried = np.concatenate((pin, landed, landed_as, across, (landed_spun, toes_from, heading_from, held_from)))
                        if s == 0 and e == frames:  # all the block: held with the others (below), its state then
                            holds.append((r, k, a0 + s, e - s, kind, carried))
                            prev = kind
                            continue
                        hold = _hold([(b, 1)], np.array([kind]), np.array([k]), _held_feet(carried[None]), g_rot[None, s:e, k, 2], g_pos[None, s:e, k],
                                     turned[None, s:e], contact[None, a0 + s:a0 + e, k, 1] > 0.5, touching[None, s:e, k],
                                     posed_all[None, a0 + s:a0 + e, k], dt)
                        goal[s:e], turn[s:e], weight[s:e] = hold.goal[0], hold.turn[0], 1.0
                        if hold.rises is not None:
                            rise[s:e] = hold.rises[0]
                        pin = hold.held.pins[0]
                        toes_up, foot_heading, held_swivel = float(hold.held.toes_up[0]), float(hold.held.foot_heading[0]), float(hold.held.held_swivel[0])
                        offset, ball_offset, lifted, left, let_go = hold.offset[0], hold.ball_offset[0], hold.rise[0], hold.foot_turn[0], hold.let_go[0]
                    prev = kind
                st.anchor[k], st.released[k], st.free_s[k], st.clear[k] = prev, released, free_s, clear
                st.feet[k] = np.concatenate((pin, landed, landed_as, across, (landed_spun, toes_up, foot_heading, held_swivel), offset,
                                             ball_offset, lifted, left, let_go))  # in FOOT_VALUES' order
        if holds:
            yield Holding(b, runs, holds, g_rot_all, g_pos_all, spun, contact, touching_all, posed_all, (goals, turns, rises, weights))
        ends = [a1 - 1 for _, _, a1 in runs]  # each walk's last frame, carried to its next block
        for (st, _, _), last, last_rot, last_shared in zip(runs, feet_all[ends], g_rot_all[ends, :, 2], shared[ends]):
            st.last, st.last_rot, st.shared = last, last_rot, last_shared
        # A foot without a ball has no heel to rise about it: held by its ankle as the hip walks on, its
        # pin may lie beyond the leg's reach (the knee locked straight), and once let go its goal would come
        # back within reach in a frame or two, bending the knee by tens of degrees in one. Let go, its
        # goal is kept within reach, the knee bending at least as the animation's.
        for k in np.flatnonzero(~b.has_ball).tolist() if not _all(b.has_ball) else ():
            free = anchors_all[:, k] == footing.FREE
            if _any(free):
                goals[free, k] = footing.within_reach(goals[free, k], g_pos_all[free, k, :3])
        if _any(rises):
            g_rot_all[:, :, 2] = quat.multiply(g_rot_all[:, :, 2], _turn_feet(b, rot, rises))
        feet_rot = quat.multiply(turns, g_rot_all[:, :, 2])  # (F, 2, 4) the ankles' global rotations to reach
        if not _any(weights):
            return None
        # Both legs in one solve (a leg of weight 0 keeps its hip and knee, its ankle set to the rotation it
        # has): one leg costs as much, and the solve gives both ankles' places for keeping the feet up.
        return LimbSolve(b.skeleton, rot, root, jt, b.leg_limbs, goals, weight=weights, pole=forward, end_rotation=feet_rot,
                         chains=(g_rot_all[:, :, :4], g_pos_all[:, :, :4]), distance=False)


def _touch_downs(b: LocomotionBinding, runs, anchors: np.ndarray, feet: np.ndarray, made: np.ndarray, dt: float) -> np.ndarray:
    """(F, 2) what holds each swinging foot that has touched the ground before its blend's strike
    (:data:`~infuse.footing.ANKLE` or :data:`~infuse.footing.BALL`, 0 elsewhere), from ``anchors``
    (F, 2) (:func:`infuse.footing.anchors`) and the animated ankles and balls ``feet`` (F, 2, 2, 3)
    metres, frames ``dt`` seconds apart, of the walks ``runs`` (:meth:`Locomotion._pin`: each walk's
    state and frames) all at once; each walk's ``st.touched`` (2,) carries it from its last block.

    A free foot lands where the lower of its sole points (the sole under the heel, the ball), coming
    down, first comes within ``b.touch_m`` of its resting height (``b.sole_floor``), held by that point
    to its blend's strike (by the ball only while the ball is that low: a ball pinned in the air is no
    contact): a blend's swing that reaches the ground before its strike (a stop's shrinking or
    vanishing stride, a step on the spot) would otherwise slide the foot along the ground to where the
    strike puts it. Not before it has been off the ground long enough for its pinning's correction to
    fade (:data:`HOLD_S` and :data:`STEP_RELEASE_S`): held sooner, it stood where the correction left
    it, short of its place (a foot held behind as the pelvis came over it, 30 cm)."""
    free = anchors == footing.FREE
    states = [st for st, _, _ in runs]
    starts = [a0 for _, a0, _ in runs]
    # The walks with a swinging foot in frames of a made step: where none, none held.
    swinging = np.logical_or.reduceat(made, starts) & np.logical_or.reduceat(free.any(axis=1), starts) if _any(made) else \
        np.zeros(len(runs), dtype=bool)
    if swinging.sum() <= 1 and len(runs) > 1:  # one walk or none: that walk's frames alone
        out: np.ndarray = np.zeros(anchors.shape, np.int64)
        for r, (st, a0, a1) in enumerate(runs):
            if swinging[r]:
                out[a0:a1] = _touch_downs(b, [(st, 0, a1 - a0)], anchors[a0:a1], feet[a0:a1], made[a0:a1], dt)
            else:
                st.touched = np.zeros(2, np.int64)
        return out
    if not _any(swinging):
        states[0].touched = np.zeros(2, np.int64)
        return np.zeros(anchors.shape, np.int64)
    f = len(anchors)
    walk_start: np.ndarray | None = None  # (F,) each walk's first frame (None: one walk)
    idx = np.arange(f)[:, None]  # (F, 1) frames since the walk's first
    free_s = states[0].free_s
    if len(runs) > 1:
        walk_start = np.zeros(f, dtype=bool)
        walk_start[starts] = True
        walk = np.cumsum(walk_start) - 1  # (F,) each frame's walk
        idx = idx - np.array(starts)[walk][:, None]
        free_s = np.array([st.free_s for st in states])[walk]  # (F, 2)
    # The feet a frame before each (from the walk's last block at its first frame), and now.
    before = np.concatenate((feet[:1], feet[:-1]))
    before[starts] = np.array([st.last for st in states])
    both = np.concatenate((before, feet))  # (2F, 2, 2, 3)
    heel = both[:, :, 0, 1] + _heel_heights(b, both[:, :, 1] - both[:, :, 0])  # (2F, 2) heights
    by_heel = (heel <= both[:, :, 1, 1]) | ~b.has_ball  # (2F, 2)
    lowest = np.where(by_heel, heel, both[:, :, 1, 1]) - b.sole_floor  # the lower sole point's
    # Frames off the ground (F, 2): from the swing's first frame, or carried from the last block.
    was_free = np.concatenate((free[:1], free[:-1]))
    was_free[starts] = np.array([st.anchor for st in states]) == footing.FREE
    swung = _latest(free & ~was_free, walk_start)
    swung = np.where(swung >= 0, idx - swung, idx + np.rint(np.minimum(free_s, 1e3) / dt)) + 1
    coming = (free & (lowest[f:] < b.touch_m) & (lowest[f:] < lowest[:f]) & made[:, None]
              & (swung * dt >= HOLD_S + STEP_RELEASE_S - 1e-9))
    # Held from the first frame of its swing (its run of free frames, ``began``) coming down low (or
    # from the walk's first, carried) to the swing's end (the blend's strike), by its lower sole
    # point: where the blend's foot rocks between heel and ball, it rolls over them.
    was_free[starts] = False
    began = _latest(free & ~was_free, walk_start)
    carried = np.zeros(free.shape, dtype=bool)
    carried[starts] = free[starts] & (np.array([st.touched for st in states]) > 0)
    first = _latest(coming | carried, walk_start)
    held = free & (first >= began) & (first >= 0) & made[:, None]
    aloft = feet[:, :, 1, 1] - b.sole_floor >= b.touch_m  # (F, 2) the ball not within touch of its floor
    kind = np.where(by_heel[f:] | aloft, footing.ANKLE, footing.BALL)
    out = np.where(held, kind, 0)
    for st, (_, _, a1) in zip(states, runs):
        st.touched = out[a1 - 1].copy()
    return out


def _any(flags: np.ndarray) -> bool:
    """Whether any of ``flags`` is set: counted, as numpy's any() costs several times more on a block's few values."""
    return bool(np.count_nonzero(flags))


def _all(flags: np.ndarray) -> bool:
    """Whether all of ``flags`` are set (see :func:`_any`)."""
    return bool(np.count_nonzero(flags) == np.size(flags))


def _latest(marks: np.ndarray, first: np.ndarray | None) -> np.ndarray:
    """(F, K) for each frame the latest frame at or before it within its walk's frames where ``marks``
    (F, K) holds, counted from the walk's first frame (-1: none); ``first`` (F,) the walks' first frames
    (each walk's frames follow one another), None: the frames are one walk's."""
    f = len(marks)
    at = np.arange(f)[:, None]
    if first is None:
        whole: np.ndarray = np.maximum.accumulate(np.where(marks, at, -1), axis=0)
        return whole
    start = np.maximum.accumulate(np.where(first, np.arange(f), 0))[:, None]  # each frame's walk's first frame
    # Marks at 2 x their frame, a walk's first frame unmarked at one less: nothing of an earlier walk's carries on.
    latest = np.maximum.accumulate(np.where(marks, 2 * at, np.where(first[:, None], 2 * at - 1, -1)), axis=0)
    out: np.ndarray = np.where(latest >= 2 * start, latest // 2 - start, -1)
    return out


class HeldFeet(NamedTuple):
    """P planted feet (a walk's foot each) as a held stretch carries them, each field as the
    :class:`~.state.LocomotionState` field of that name has it for the foot, a frame before the stretch:
    where the anchor holds ``pins`` (P, 3), the foot's rotation as it landed, animated and corrected,
    ``landed`` and ``landed_as`` (P, 4), the horizontal axis across it ``across`` (P, 3), the turn spun at
    the root then ``landed_spun`` (P,) radians; held by the heel, how far its toes are up ``toes_up`` (P,),
    its heading ``foot_heading`` (P,) (NaN: its swivel counts from the stretch's first frame) and the turn
    held off it ``held_swivel`` (P,), radians."""

    pins: np.ndarray
    landed: np.ndarray
    landed_as: np.ndarray
    across: np.ndarray
    landed_spun: np.ndarray
    toes_up: np.ndarray
    foot_heading: np.ndarray
    held_swivel: np.ndarray


class Hold(NamedTuple):
    """What :func:`_hold` makes of P feet held over n frames: the ankles' goals ``goal`` (P, n, 3), the
    feet's world turns from the animation's ``turn`` (P, n, 4), the heels' extra rise about the ball
    ``rises`` (P, n, 3) (rotation vectors in the foot's frame; None: all held by the heel), the feet carried
    on (``held``, :class:`HeldFeet`), and the corrections at the last frame that a release fades out, as
    :class:`~.state.LocomotionState` names them: the ankle's ``offset`` and the ball's ``ball_offset``
    (P, 3), the heel's extra ``rise`` (P, 3), the foot's turn ``foot_turn`` (P, 4), and where the ball is,
    ``let_go`` (P, 3)."""

    goal: np.ndarray
    turn: np.ndarray
    rises: np.ndarray | None
    held: HeldFeet
    offset: np.ndarray
    ball_offset: np.ndarray
    rise: np.ndarray
    foot_turn: np.ndarray
    let_go: np.ndarray


def _hold(owners: list[tuple[LocomotionBinding, int]], kind: np.ndarray, feet: np.ndarray, held: HeldFeet, foot_rot: np.ndarray,
          leg: np.ndarray, turned: np.ndarray, ball_down: np.ndarray, touching: np.ndarray, posed: np.ndarray, dt: float) -> Hold:
    """P feet, each one of a walk's (``feet`` (P,): 0 left, 1 right; ``owners``: the bindings of the walks,
    each with how many of the feet in turn are its walks'), held by ``kind`` (P,)
    (:data:`~infuse.footing.ANKLE` or :data:`~infuse.footing.BALL`) over n frames ``dt`` seconds apart,
    carried from ``held`` (:meth:`Locomotion._pin`). The animation's ankles' global rotations ``foot_rot``
    (P, n, 4), its legs ``leg`` (P, n, 5, 3) (hip, knee, ankle, the hip's parent, the ball; metres), the
    turn spun at the root ``turned`` (P, n) radians; (P, n) bool: the blend's ball down ``ball_down``,
    touched down before its strike ``touching``, held by the ball for the pose's sake ``posed``. The work
    along frames is cumulative (the toes' slowed pitch, the swivel held off, the touching ball's height),
    so a stretch gives the same frames whether it comes in one call or frame by frame."""
    on_heel = kind == footing.ANKLE  # (P,)
    heels, balls = _any(on_heel), not _all(on_heel)
    ankle, ball = leg[:, :, 2], leg[:, :, 4]
    lever = ball - ankle  # (P, n, 3) the animated ankle to ball
    pins, across = held.pins, held.across
    toes_up, foot_heading, held_swivel = held.toes_up, held.foot_heading, held.held_swivel
    # The animation's turn of the foot since it landed (world frame): on its heel all of it but the turn
    # spun at the root, on its ball only its pitch (the twist about the axis across the foot).
    since = quat.multiply(foot_rot, quat.conjugate(held.landed)[:, None])
    if heels:
        # On its heel, its toes come down no faster than the pack's feet turn near the ground (a blend's
        # foot slapping flat in a frame would swing the ankle about the heel by centimetres). The pitch is
        # the twist of the turn since it landed about the axis across; ``toes_up`` carries it (toes up positive).
        pitch, up = _toes_slowed(owners, since, across, toes_up, dt)
        toes_up = np.where(on_heel, up[:, -1], toes_up) if balls else up[:, -1]
        kept = quat.multiply(since, quat.from_axis_angle(across[:, None], -(pitch + up)))  # both about one axis
    if balls:
        pitched = np.concatenate((across[:, None] * (since[..., :3] @ across[:, :, None]), since[..., 3:]), axis=-1)
        pitched /= np.maximum(np.sqrt((pitched * pitched).sum(axis=-1, keepdims=True)), 1e-12)
        kept = np.where(on_heel[:, None, None], kept, pitched) if heels else pitched
    turn = quat.multiply(quat.multiply(kept, held.landed_as[:, None]), quat.conjugate(foot_rot))  # on the heel, yet to turn about +Y
    reach = quat.rotate(turn, lever)  # the corrected ankle to ball
    if heels:
        # On the heel the foot turns back by the turn spun at the root since it landed (``spin`` (P, n)
        # radians about +Y), and while its ball is down too, its heading (its ankle-to-ball direction about
        # the vertical) holds: a blend's or take's swivel about the heel, or a roll down about an axis not
        # square to the foot, would sweep the ball along the ground. ``held_off`` (P, n) the turn held off
        # (radians), summed frame by frame; the ball is down where the blend's is, and where the foot
        # touched down before its strike. Both turn it about +Y, in one turn.
        spin = held.landed_spun[:, None] - turned
        heading_now = (np.arctan2(reach[..., 0], reach[..., 2]) + spin + math.pi) % (2.0 * math.pi) - math.pi
        start = np.where(np.isnan(foot_heading), heading_now[:, 0], foot_heading)
        swivel = heading_now - np.concatenate((start[:, None], heading_now[:, :-1]), axis=1)
        swivel = (swivel + math.pi) % (2.0 * math.pi) - math.pi
        held_off = held_swivel[:, None] + np.cumsum(np.where(ball_down | touching, swivel, 0.0), axis=1)
        foot_heading, held_swivel = (np.where(on_heel, heading_now[:, -1], foot_heading), np.where(on_heel, held_off[:, -1], held_swivel)) \
            if balls else (heading_now[:, -1], held_off[:, -1])
        turn = quat.multiply(yaw(np.where(on_heel[:, None], spin - held_off, 0.0) if balls else spin - held_off), turn)
        reach = quat.rotate(turn, lever)
        goal = pins[:, None] - (_heel_of(owners[0][0], feet, reach) if len(owners) == 1 else _heels_of(owners, feet, reach))
    if balls:
        # Touching down by its ball, the ball goes down as the animation's does (never held above it: a
        # ball held where it first touched, the animation's foot coming down on, held the foot up in the
        # air and dropped it at the strike).
        held_at = np.repeat(pins[:, None], reach.shape[1], axis=1)
        if _any(touching):
            held_at[..., 1] = np.minimum(pins[:, 1:2], np.minimum.accumulate(np.where(touching, ball[..., 1], np.inf), axis=1))
        pins = np.where(on_heel[:, None], pins, held_at[:, -1]) if heels else held_at[:, -1]
        goal = np.where(on_heel[:, None, None], goal, held_at - reach) if heels else held_at - reach
    # The ankle at the animation's height; held by the ball for the pose's sake, no lower than keeps the
    # ball at the height it took over at (the blend's leg, half standing and half swinging, would push it
    # into the ground, and it would rise from there still down and slide as the foot is let go); touching
    # down by the heel, no higher than keeps the heel where it touched (the blend's foot rising again
    # before its strike would lift it and drop it back in a frame).
    landing = touching & on_heel[:, None]
    pinned = goal[..., 1].copy() if _any(landing) else None
    goal[..., 1] = np.where(posed, np.maximum(ankle[..., 1], goal[..., 1]), ankle[..., 1])
    if pinned is not None:
        goal[..., 1] = np.where(landing, np.minimum(goal[..., 1], pinned), goal[..., 1])
    ball_goal = goal[:, -1] + reach[:, -1]
    rise = None
    if balls:  # the heel rises further about the ball where the hip cannot reach
        n = goal.shape[0] * goal.shape[1]
        risen = footing.heel_rise(quat.multiply(turn, foot_rot).reshape(n, 4), leg[:, :, :3].reshape(n, 3, 3), goal.reshape(n, 3),
                                  (goal + reach).reshape(n, 3), np.broadcast_to(across[:, None], goal.shape).reshape(n, 3),
                                  np.repeat(~on_heel, goal.shape[1]) if heels else None)
        goal, rise = risen[0].reshape(goal.shape), risen[1].reshape(goal.shape)
    lifted = np.zeros(pins.shape) if rise is None else rise[:, -1]
    return Hold(goal, turn, rise, held._replace(pins=pins, toes_up=toes_up, foot_heading=foot_heading, held_swivel=held_swivel),
                goal[:, -1] - ankle[:, -1], ball_goal - ball[:, -1], lifted, turn[:, -1].copy(), ball_goal)


def _held_feet(values: np.ndarray) -> HeldFeet:
    """The :class:`HeldFeet` of P feet's values ``values`` (P, >= :data:`~.state.HELD_COLUMNS`) laid out as
    :attr:`~.state.LocomotionState.feet` has them (views)."""
    return HeldFeet(*(values[:, FOOT_VALUES[name][0]] for name in HeldFeet._fields))


class Holding(NamedTuple):
    """A group's feet held alike through all their walks' frames (:meth:`Locomotion._pin`): its binding,
    walks ``runs`` and ``holds`` (each foot's walk, foot, first frame and frames held, its anchor, and what
    it is carried from: ``HELD_COLUMNS`` values laid out as :attr:`~.state.LocomotionState.feet` has them,
    None: as its walk's state has them); the frames' legs ``g_rot``, ``g_pos`` (F, 2, 5, 4 / 3), ``spun``
    (F,), ``contact`` (F, 2, 2), ``touching``, ``posed`` (F, 2) as the pinning has them; ``out``: the goals
    (F, 2, 3), turns (F, 2, 4), rises (F, 2, 3) and weights (F, 2) they are written into."""

    b: LocomotionBinding
    runs: list
    holds: list
    g_rot: np.ndarray
    g_pos: np.ndarray
    spun: np.ndarray
    contact: np.ndarray
    touching: np.ndarray
    posed: np.ndarray
    out: tuple


def _advance(steps: Generator[Any, None, Any]) -> tuple[bool, Any]:
    """Step the generator ``steps`` on: (False, what it yields next) or (True, what it returns)."""
    try:
        return False, next(steps)
    except StopIteration as done:
        return True, done.value


def _hold_all(groups: list[Holding], dt: float) -> None:
    """Hold the feet of every group's walks (:class:`Holding`) to the end of their walk's frames, those
    held as many frames in one :func:`_hold` (of all groups: its arithmetic costs about as much for all
    as for one), write the goals, turns, rises and weights, and carry the walks' states on."""
    everys = [np.array([st.feet for st, _, _ in g.runs]) for g in groups]  # (R, 2, C) each group's planted feet's values
    for n in sorted({h[3] for g in groups for h in g.holds}):
        parts = []  # each group's feet held n frames: its index, walks, feet, frames
        inputs = []
        for gi, g in enumerate(groups):
            held = [h for h in g.holds if h[3] == n]
            if not held:
                continue
            walks, feet, first, _, kinds = np.array([h[:5] for h in held]).T
            values = everys[gi][walks, feet]  # (P, C)
            for i, h in enumerate(held):
                if h[5] is not None:
                    values[i, :HELD_COLUMNS] = h[5]
            at, foot = first[:, None] + np.arange(n), feet[:, None]  # (P, n) frames, (P, 1) feet
            parts.append((gi, walks, feet, at, foot))
            inputs.append((kinds, feet, values, g.g_rot[at, foot, 2], g.g_pos[at, foot], g.spun[at], g.contact[at, foot, 1] > 0.5,
                           g.touching[at, foot], g.posed[at, foot]))
        kinds, feet, values, foot_rot, leg, turned, ball_down, touching, posed = \
            inputs[0] if len(inputs) == 1 else (np.concatenate(x) for x in zip(*inputs))
        hold = _hold([(groups[gi].b, len(walks)) for gi, walks, *_ in parts], kinds, feet, _held_feet(values), foot_rot, leg, turned,
                     ball_down, touching, posed, dt)
        left = (*hold.held, hold.offset, hold.ball_offset, hold.rise, hold.foot_turn, hold.let_go)  # in FOOT_VALUES' order
        carried = np.concatenate([v if v.ndim == 2 else v[:, None] for v in left], axis=1)
        for (gi, walks, feet, at, foot), a, e in zip(parts, *_row_bounds([len(part[1]) for part in parts])):
            goals, turns, rises, weights = groups[gi].out
            goals[at, foot], turns[at, foot], weights[at, foot] = hold.goal[a:e], hold.turn[a:e], 1.0
            if hold.rises is not None:
                rises[at, foot] = hold.rises[a:e]
            everys[gi][walks, feet] = carried[a:e]
    for g, every in zip(groups, everys):
        for r in sorted({h[0] for h in g.holds}):
            g.runs[r][0].feet = every[r]


def _row_bounds(counts: list[int]) -> tuple[list[int], list[int]]:
    """The first and past-the-last rows of parts of ``counts`` rows stacked in order."""
    ends = list(itertools.accumulate(counts))
    return [0, *ends[:-1]], ends


def _toes_slowed(owners: list[tuple[LocomotionBinding, int]], since: np.ndarray, across: np.ndarray, before: np.ndarray,
                 dt: float) -> tuple[np.ndarray, np.ndarray]:
    """P feet held by their heels (``owners``: their walks' bindings, each with how many of the feet in turn
    are its walks'): their pitch (P, F) radians, toes down positive, the twist about the horizontal axis
    ``across`` (P, 3) of their turn ``since`` (P, F, 4) they landed, and how far their toes are up (P, F)
    radians, coming down no faster than the binding's ``landing_rad_s`` from ``before`` (P,) a frame before
    the first, frames ``dt`` seconds apart (as the animation's where that has no limit)."""
    pitch = 2.0 * np.arctan2((since[..., :3] @ across[:, :, None])[..., 0], since[..., 3])
    pitch = (pitch + math.pi) % (2.0 * math.pi) - math.pi
    if len(owners) == 1:
        rate = owners[0][0].landing_rad_s
        return pitch, (_slow_fall(-pitch[..., None], before[:, None], rate * dt)[..., 0] if math.isfinite(rate) else -pitch)
    up = np.empty(pitch.shape)
    for (b, _), a, e in zip(owners, *_row_bounds([count for _, count in owners])):
        rate = b.landing_rad_s
        up[a:e] = _slow_fall(-pitch[a:e, :, None], before[a:e, None], rate * dt)[..., 0] if math.isfinite(rate) else -pitch[a:e]
    return pitch, up


def _stop_marks(b: LocomotionBinding, clip, fps: float) -> tuple[float | None, float]:
    """A stop ``clip``'s gait phase at its start (:func:`~.transitions.stop_phase`, None without one) and
    how far (m) it travels at ``fps`` (:func:`~.transitions.stop_travel`): worked out once, kept on ``b``
    (a walk heading for its last point looks at every stop clip every block)."""
    key = (clip.name, fps)
    known = b.stop_marks.get(key)
    if known is None:
        at = transitions.stop_phase(clip)
        known = b.stop_marks[key] = (at, transitions.stop_travel(clip, fps) if at is not None else 0.0)
    return known


def _resume(n: int, drive, value, asked: dict, done: dict) -> None:
    """Go on with walk ``n``'s :meth:`Locomotion._drive` generator, sending it ``value``: what it asks
    for next goes into ``asked``, what it returns into ``done``, by ``n``."""
    try:
        asked[n] = drive.send(value)
    except StopIteration as stop:
        done[n] = stop.value


def _clips_of(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The clips blended by weights ``w`` (F, N): those weighing more than :data:`_LEAST_WEIGHT` on some
    frame, and the same in the order the blend sums them (most weight over the frames first, ties in
    the clips' order)."""
    used = np.nonzero(w.max(axis=0) > _LEAST_WEIGHT)[0]
    return used, used[np.argsort(-w[:, used].sum(axis=0), kind="stable")]


class ClipSet(NamedTuple):
    """What :meth:`Locomotion._blend` takes of a binding for the clips ``used`` (U,) it blends: those with
    foot events ``stepping`` (S,) and their events (S, 8), the flags ``feet`` (U,) of those, their events
    (U', 2, 4) or None without any, whether all have them, the clips' keys (U, 1, 1, 3), the idle clips
    (I,) and ``used`` followed by them (U + I,). Worked out once per binding and set of clips."""

    stepping: np.ndarray
    stepping_events: np.ndarray
    feet: np.ndarray
    foot_events: np.ndarray | None
    all_stepping: bool
    keys: np.ndarray
    idle: np.ndarray
    with_idle: np.ndarray


def _clip_set(b: LocomotionBinding, used: np.ndarray) -> ClipSet:
    """The :class:`ClipSet` of clips ``used`` (U,) (increasing indices) in binding ``b``, kept on it."""
    key = used.tobytes()
    known = b.clip_sets.get(key)
    if known is None:
        feet = b.stepping[used]
        stepping = used[feet]
        idle = np.flatnonzero(b.idle)
        known = b.clip_sets[key] = ClipSet(stepping, b.events[stepping].reshape(-1, 8), feet,
                                           b.events[stepping] if feet.any() else None, bool(feet.all()),
                                           b.keys[used, None, None], idle, np.concatenate((used, idle)))
    return known


class Summed(NamedTuple):
    """How :meth:`Locomotion._blend` sums the clips for weights ``w`` (F, N) and the orders (F, N) its walks sum
    them in: the clips ``used`` (U,) (weighing more than :data:`_LEAST_WEIGHT` on some frame: one is left out of
    each frame it weighs no more than that on, as when that frame is blended alone, other frames of the block
    not bringing it in), their :class:`ClipSet`, the weights ``w`` (F, N) so left out, the share of the clips
    with foot events ``stepping_share`` (F,) and their events blended ``events`` (F, 2, 4) (both zeros without
    any) with the clips' in :func:`~.phase_keys.foot_keys` (None without any), the most clips a frame sums ``most``, the frames' indices ``frames`` (F, 1), and each frame's clips in
    its walk's order (U', one gather): their samples' places ``sample_of`` (F, U') among ``used`` and weights
    ``weight_of`` (F, U'), none past its walk's clips."""

    used: np.ndarray
    of: ClipSet
    w: np.ndarray
    stepping_share: np.ndarray
    events: np.ndarray
    keys: FootKeys | None
    most: int
    frames: np.ndarray
    sample_of: np.ndarray
    weight_of: np.ndarray


def _summed(b: LocomotionBinding, w: np.ndarray, orders: np.ndarray) -> Summed:
    """The :class:`Summed` of weights ``w`` (F, N) and ``orders`` (F, N) in binding ``b`` (:func:`_kept`)."""
    def sums() -> Summed:
        weighs = w > _LEAST_WEIGHT
        used = np.flatnonzero(weighs.any(axis=0))  # every walk's clips
        kept = np.where(weighs, w, 0.0)
        of = _clip_set(b, used)
        if of.stepping.size:
            ws = kept[:, of.stepping]
            stepping_share = ws.sum(axis=1)  # (F,) the clips with foot events
            events = ((ws / np.maximum(stepping_share[:, None], 1e-9)) @ of.stepping_events).reshape(-1, 2, 4)
        else:
            stepping_share, events = np.zeros(len(w)), np.zeros((len(w), 2, 4))
        listed = orders >= 0
        most = int(listed.sum(axis=1).max())
        listed, clips = listed[:, :most], np.maximum(orders[:, :most], 0)
        frames = np.arange(len(w))[:, None]
        keys = None if of.foot_events is None else foot_keys(of.foot_events, events)
        return Summed(used, of, kept, stepping_share, events, keys, most, frames, np.searchsorted(used, clips),
                      np.where(listed, kept[frames, clips], 0.0))

    return _kept(b, ("sums", w.tobytes() + orders.tobytes()), sums)


def _kept(b: LocomotionBinding, key: tuple, make: Callable[[], Any]) -> Any:
    """What ``make()`` gives (a tuple of arrays and others, the arrays read only), kept on binding ``b`` by ``key``
    (the work's name and its inputs as bytes): work that depends on the blend weights alone, which walks cruising
    or standing ask for block after block (at most :data:`_WEIGHTS_KEPT` kept: the oldest goes as one comes,
    so no block lets go of them all at once)."""
    known = b.by_weights.get(key)
    if known is None:
        while len(b.by_weights) >= _WEIGHTS_KEPT:
            del b.by_weights[next(iter(b.by_weights))]
        known = b.by_weights[key] = make()
        for x in known:
            if isinstance(x, np.ndarray):
                x.flags.writeable = False
    return known


class Ask(NamedTuple):
    """Work a walk's :meth:`Locomotion._drive` asks for and waits on: ``work(*shared, *stacked, *walks)``,
    done once for every walk of the block asking for the same ``work`` and ``key`` (:meth:`Locomotion.evaluate`),
    with ``shared`` the first one's, ``stacked`` their ``rows`` (arrays (F, ...), or None for all)
    concatenated and ``walks`` their ``walk`` values, a list of each (one per walk, in the walks' order:
    their states, how many frames each has). It returns arrays (F, ...) or None, frame by frame: each walk
    takes back its rows."""

    work: Callable
    key: tuple
    shared: tuple
    rows: tuple
    walk: tuple = ()


class Weighed(NamedTuple):
    """The blend weights of the steering's requests (R,) in a binding's blend space (:func:`_weights`):
    ``w`` (R, N), the moving share ``slow`` (R,), the requests ``inside`` (R,) bool the tessellation, and
    what the drive reads of them: the moving clips' weights ``target`` (R, N) (:func:`_moving`), the turn
    rate ``turning`` (R,) rad/s the blend shows and the share ``moving`` (R,) of the clips not idle (1 - the
    idle's weight; ``slow`` without an idle)."""

    w: np.ndarray
    slow: np.ndarray
    inside: np.ndarray
    target: np.ndarray
    turning: np.ndarray
    moving: np.ndarray


def _bound_weights(b: LocomotionBinding, req: np.ndarray) -> Weighed:
    """The :class:`Weighed` blend of the steering's requests ``req`` (R, 5) (speed, turn, direction first) in
    the pack's locomotion blend space as bound in ``b`` (:func:`_kept`)."""
    def weighed() -> Weighed:
        w, slow, inside, moving = _weights(b.space, b.idle, b.velocities, req[:, 0], req[:, 2], req[:, 1])
        return Weighed(w, slow, inside, _moving(w, b.idle, b.slowest), w @ b.velocities[:, 2], moving)

    return _kept(b, ("weights", req[:, :3].tobytes()), weighed)


def _walked(b: LocomotionBinding, dt: float, times, req, states: list, walks: list, starts: list, counts: list):
    """The steered blend of walks of binding ``b`` at once, their frames stacked (R,) (see :func:`_driven` for the
    arguments): driven (:func:`_driven`), placed (:func:`_placed`; the idle faded in on the rows of the walks fading
    into it, none on the others, as each alone) and, on the rows of the walks whose strides are shorter on some
    frame, its steps shortened (:func:`_shortened`). Returns each frame's rotations (R, J, 4), root (R, 3), joint
    translations (R, J, 3) or None, contact phases (R, 2, 2), heading's direction (R, 3), turn spun at the root
    (R,) and the frames stepping as no clip does (R,) bool (see :meth:`Locomotion._steered`)."""
    wm, order, phase, half_frame, standing, settle, rest, stride, heading, px, pz, mover, spun, made, held, fading = \
        _driven(b, dt, times, req, states, walks, starts, counts)
    fades = bool(fading.any()) and b.has_idle
    if fades and not fading.all():  # a walk not fading into the idle shows none of it, as alone
        standing = np.where(fading, standing, 0.0)
    rot, root, jt, contact, turn_q, forward, down, laid = _placed(
        b, dt, wm, order, phase, standing, times if fades else None, half_frame, settle, rest, stride, heading, px, pz,
        mover, held, states, counts)
    if len(b.legs) == 2:
        shorter = np.abs(stride - 1.0) > 1e-6
        if counts.count(counts[0]) == len(counts):
            short = shorter.reshape(len(counts), -1).any(axis=1)
        else:
            short = np.array([shorter[e - c:e].any() for c, e in zip(counts, itertools.accumulate(counts))])
        if short.all():
            rot, jt = _shortened(b, wm, stride, rot, root, jt, turn_q, forward, settle, down, laid)
        elif short.any():
            at = np.flatnonzero(np.repeat(short, counts))
            short_rot, short_jt = _shortened(b, wm[at], stride[at], rot[at], root[at], None if jt is None else jt[at],
                                             turn_q[at], forward[at], settle[at], down[at], laid[at])
            rot[at] = short_rot
            if jt is not None:
                jt[at] = short_jt
    return rot, root, jt, contact, forward, spun, made


def _driven(b: LocomotionBinding, dt: float, times, req, states: list, walks: list, starts: list, counts: list):
    """The steered blend driven for walks of binding ``b`` at once, their frames stacked (R,): the
    activities' ``times`` (R,) seconds and the steering's requests ``req`` (R, 5) (:meth:`Steering.run`),
    each walk's state (``states``, carried on), its controller (``walks``), where it stood before the
    steering ran (``starts``: x, z, heading) and how many frames it has (``counts``). Each frame's
    blend weights (:func:`_bound_weights`), eased (:func:`_eased`), its root motion along the heading,
    the gait's clock (:func:`_clock`), the turn spun at the root; rows (R, ...): the moving clips'
    weights (R, N), the order each walk sums them in (R, N), the phase, half a frame's advance of it,
    the idle's share, how far into a stop, how far come to rest, the stride factor, the heading
    (radians) and ground point (m), the joint the walk travels on, the turn spun at the root, the
    frames stepping as no clip does (a stop's, a turn on the spot's, coming to rest), those holding
    the phase at a stop without an idle (a foot laid down does not rise there), and whether the walk
    fades into the idle (its every row)."""
    speed, turn, direction, stopping, final = req[:, 0], req[:, 1], req[:, 2], req[:, 3] > 0.5, req[:, 4] > 0.5
    w, slow, inside, target, turning, moving = _bound_weights(b, req)
    has_idle = b.has_idle
    ends = list(itertools.accumulate(counts))
    spans = list(zip([0, *ends[:-1]], ends))
    last = np.array(ends) - 1
    # The root moves as asked (the request is feasible: the steering keeps to the pack's top speed),
    # the blend shows it; the clips' own turn shows what it can of the heading's.
    vf, vl = speed * np.cos(direction), speed * np.sin(direction)
    vt = turning if has_idle else turning * slow
    # Root motion: integrate the blend's own velocities from where the last block ended; the heading
    # turns as asked, the part of the turn the blend does not show (on the spot, or harder than the
    # turning examples) spun at the root.
    x0, z0, h0 = zip(*starts)
    turned = turn * dt
    heading = _before_each(h0, turned, counts)
    ahead = heading + turned  # each frame's step along the heading it turns to, as the steering integrates
    sin_ahead, cos_ahead = np.sin(ahead), np.cos(ahead)
    step_x = (vf * sin_ahead + vl * cos_ahead) * dt
    step_z = (vf * cos_ahead - vl * sin_ahead) * dt
    px, pz = _before_each(np.stack((x0, z0), axis=-1), np.stack((step_x, step_z), axis=-1), counts).T
    for st, x, z, h in zip(states, (px[last] + step_x[last]).tolist(), (pz[last] + step_z[last]).tolist(),
                           (heading[last] + turned[last]).tolist()):
        st.x, st.z, st.heading = x, z, h
    spinning = np.abs(turn - vt) > SPIN_STEP
    # Below the slowest walk the tessellation mixes in the idle: walk the moving clips instead, with
    # a slower cadence and shorter strides in equal proportion (the walk ratio, step length over
    # cadence, stays about constant with speed), and show the idle only when nearly standing.
    wm = _eased_each(target, states, dt / BLEND_EASE_S, inside, counts)
    for st, blend in zip(states, wm[last]):
        st.blend = blend
    eased = wm - target  # the turn the eased blend shows more than the asked one's
    vt = vt + (eased @ b.velocities[:, 2]) * moving
    period = np.maximum(wm @ b.durations, 1e-3)
    paces: list = [None] * len(states)
    for k, (st, walk, (a, e)) in enumerate(zip(states, walks, spans) if b.stops else ()):
        path = walk.steering.path
        if path is not None and final[a:e].any():  # the stop clip begun on time (:mod:`.pacing`)
            to_x, to_z = path[-1][0] - px[a:e], path[-1][1] - pz[a:e]  # the last point from each frame, as the steering saw it
            bearing = (np.arctan2(to_x, to_z) - direction[a:e] - heading[a:e] + np.pi) % (2.0 * np.pi) - np.pi
            cruise = np.array([walk._asked(t, b.limit) for t in times[a:e].tolist()])  # the speed it speeds up to
            fps = 1.0 / dt
            paces[k] = (pacing.pacing_for(b.stops, fps, b.walk_speeds, b.walk_cadences, st.phase, walk.steering.max_accel,
                                          [_stop_marks(b, c, fps) for c in b.stops]),
                        np.where(final[a:e], speed[a:e], 0.0), np.hypot(to_x, to_z), bearing, cruise)
    phase, advance, stride, standing, rest = _clocks(states, slow, stopping, spinning, period, dt, has_idle,
                                                     lambda i: _settle_phases(b, wm[i:i + 1])[0], paces, counts)
    if b.stops:  # where it went, frame by frame: where a stop clip may take over
        for st, (a, e) in zip(states, spans):
            st.trace = (px[a:e], pz[a:e], heading[a:e], speed[a:e], phase[a:e], advance[a:e])
    # The heading's turn the blend does not show, spun at the root (radians, from the walk's start):
    # the idle's share of the pose shows none of the turning clips' (their planted feet turning back).
    shown = vt * (1.0 - standing)
    unshown = (turn - shown) * dt
    spun = _before_each([st.spun for st in states], unshown, counts)
    for st, turned_at in zip(states, (spun[last] + unshown[last]).tolist()):
        st.spun = turned_at
    # How far into a stop; the idle plays as it is (so a block standing throughout needs no change).
    settle = np.minimum(np.maximum(1.0 - slow / STAND_FRACTION, 0.0), 1.0) * (1.0 - standing)  # np.clip costs more
    stride = stride + (1.0 - stride) * standing
    # A foot laid down at the end of a stop without an idle does not rise while the phase holds there
    # (:func:`_placed`).
    held = None if has_idle else (advance == 0.0) & ((slow < STAND_FRACTION) | stopping)
    # The steps of a stop or a turn on the spot (shrinking, on the spot, coming to rest: the clips take
    # none such) land a foot where it touches.
    made = (slow < STAND_FRACTION) | stopping | (rest > 0.0)
    order, mover, fading = _walk_clips(b, w, wm, standing, counts)
    return wm, order, phase, 0.5 * advance, standing, settle, rest, stride, heading, px, pz, mover, spun, made, held, fading


def _before_each(starts, steps: np.ndarray, counts: list) -> np.ndarray:
    """(R, ...) :func:`_before` for walks' frames stacked: each walk's start (``starts`` (W, ...)) plus the
    ``steps`` (R, ...) taken before each of its frames, the walks having ``counts`` (W,) frames each, in order."""
    f = counts[0]
    starts = np.asarray(starts, dtype=np.float64)
    if f == 1 and len(counts) == len(steps):  # a frame a walk: its start (plus no steps, as below)
        return (starts + 0.0).reshape(steps.shape)
    if counts.count(f) < len(counts):  # walks of different lengths: each on its own
        out = np.empty(steps.shape)
        for start, c, e in zip(starts, counts, itertools.accumulate(counts)):
            out[e - c] = 0.0
            np.cumsum(steps[e - c:e - 1], axis=0, out=out[e - c + 1:e])
            out[e - c:e] += start
        return out
    out = np.empty((len(counts), f) + steps.shape[1:])
    out[:, 0] = 0.0
    if f > 1:
        np.cumsum(steps.reshape((-1, f) + steps.shape[1:])[:, :-1], axis=1, out=out[:, 1:])
    out += starts[:, None]
    return out.reshape(steps.shape)


def _eased_each(target: np.ndarray, states: list, step: float, inside: np.ndarray, counts: list) -> np.ndarray:
    """(R, N) :func:`_eased` for walks' frames stacked (``target`` (R, N), ``inside`` (R,); ``counts`` (W,)
    frames each), each from its state's eased weights, its state's ``blend_held`` updated. Walks whose
    blend keeps up take their targets, looked at all at once (the frame loop runs only for one that lags)."""
    f = counts[0]
    befores = [st.blend for st in states]
    if counts.count(f) == len(counts) and all(x is not None and x.shape == target.shape[1:] for x in befores):
        n = target.shape[1]
        stacked = target.reshape(-1, f, n)
        at = inside.reshape(-1, f)
        if f == 1:  # each walk's one frame follows its last block's
            prev, free = np.array(befores)[:, None], at
        else:
            prev = np.concatenate((np.array(befores)[:, None], stacked[:, :-1]), axis=1)
            free = at.copy()
            free[:, 1:] &= at[:, :-1]
        jump = (np.abs(stacked - prev).max(axis=2) > step) & ~free
        if not jump.any() and not any(st.blend_held for st in states):
            for st, held in zip(states, (~at[:, -1]).tolist()):
                st.blend_held = held
            return target
    out = target.copy()
    for st, e, c in zip(states, itertools.accumulate(counts), counts):
        out[e - c:e], st.blend_held = _eased(target[e - c:e], st.blend, step, inside[e - c:e], st.blend_held)
    return out


def _walk_clips(b: LocomotionBinding, w: np.ndarray, wm: np.ndarray, standing: np.ndarray, counts: list) -> tuple[np.ndarray, ...]:
    """For walks' frames stacked (blend weights ``w`` (R, N), the moving clips' ``wm`` (R, N), the idle's share
    ``standing`` (R,); ``counts`` (W,) frames each): the clips each walk sums, in its order (:func:`_clips_of`),
    then -1 (R, N); the joint it travels on (R,) (the most weighted clip's mover) and whether it fades into
    the idle (R,) bool, each walk's on all its rows."""
    f, n = counts[0], wm.shape[1]
    if counts.count(f) == len(counts):
        def ordered() -> tuple[np.ndarray, np.ndarray]:
            if f == 1:  # a frame a walk: each row is its walk's sums
                used, summed, weighed = wm > _LEAST_WEIGHT, wm, w
            else:
                per = wm.reshape(-1, f, n)
                used, summed, weighed = per.max(axis=1) > _LEAST_WEIGHT, per.sum(axis=1), w.reshape(-1, f, n).sum(axis=1)
            ranked = np.argsort(np.where(used, -summed, np.inf), axis=1, kind="stable")
            return np.where(np.arange(n) < used.sum(axis=1)[:, None], ranked, -1), np.asarray(b.movers)[np.argmax(weighed, axis=1)]

        orders, movers = _kept(b, ("orders", f, wm.tobytes() + w.tobytes()), ordered)
        fading = (standing if f == 1 else standing.reshape(-1, f).max(axis=1)) > 1e-6
    else:
        ends = list(itertools.accumulate(counts))
        orders = np.full((len(counts), n), -1)
        movers = np.empty(len(counts), dtype=np.int64)
        fading = np.empty(len(counts), dtype=bool)
        for k, (c, e) in enumerate(zip(counts, ends)):
            summed = _clips_of(wm[e - c:e])[1]
            orders[k, :summed.size] = summed
            movers[k] = b.movers[int(np.argmax(w[e - c:e].sum(axis=0)))]
            fading[k] = standing[e - c:e].max() > 1e-6
    if f == 1 and counts.count(1) == len(counts):
        return orders, movers, fading
    return np.repeat(orders, counts, axis=0), np.repeat(movers, counts), np.repeat(fading, counts)


def _placed(b: LocomotionBinding, dt: float, w, orders, phase, standing, times, half_frame, settle, rest, stride, heading, px, pz,
            mover, held, states: list, counts: list):
    """The blend (:meth:`Locomotion._blend` of ``w`` to ``half_frame``, see there) placed on the steered path,
    frame by frame: the pelvis taken ``settle`` (F,) of the way over the point the steering stands at (and
    risen to the standing height by ``rest`` (F,) without an idle), the pose turned to ``heading`` (F,)
    radians and carried to ``px``, ``pz`` (F,) metres on the joint ``mover`` (F,) (0: the root). Returns its
    rotations (F, J, 4), root (F, 3), joint translations (F, J, 3) or None, contact phases (F, 2, 2), the
    heading's turn (F, 4) and direction (F, 3), and how far each foot is laid down (F, 2): ``down`` by its
    stance share into a stop, and ``laid`` also through the swing of strides shrunk by ``stride`` (F,), let
    go slower (:data:`LAY_RELEASE_S`; not at all on the frames ``held`` (F,) bool, or None for none) from each
    walk's state (``states``, carried on; ``counts`` (W,) its frames)."""
    rot, root, jt, contact, support = Locomotion._blend(b, w, orders, phase, standing, times, half_frame)
    if not b.has_idle:
        resting = rest > 0.0
        if resting.any():
            # Come to rest without an idle: both feet stay down where they are, laid flat about their
            # balls over the rest's fade (the held phase of a walk may have a foot in the air).
            contact[resting] = (0.9, 1.0)  # heel and ball: each foot pinned by its ball, its heel coming down
            support = np.maximum(support, rest[:, None])
    # Coming to a stop, the pelvis comes over the point the steering stands at (the clips carry it
    # ahead, behind or aside of their path as their gait goes): its ground point (F, 3) in the
    # facing frame, wherever joint 0 sits, is taken out by ``settle``.
    pelvis = root if b.pelvis == 0 else chain_fk(b.skeleton, rot, root, jt, [b.pelvis])[1][:, 0]  # joint 0: its root translation
    centre = pelvis * _GROUND * settle[:, None]
    if b.stand_height > 0.0 and rest.any():
        # Coming to rest without an idle, the pelvis rises to the takes' standing height (the stop's
        # held double support had the knees bent 33-45 degrees): the legs, solved to the feet held
        # down, straighten as the takes' stance legs.
        centre[:, 1] = rest * (pelvis[:, 1] - b.stand_height)
    # Place the blended pose on the integrated path.
    turn_q = yaw(heading)
    forward = np.zeros((len(heading), 3))
    forward[:, 0], forward[:, 2] = np.sin(heading), np.cos(heading)
    rot[:, 0] = quat.multiply(turn_q, rot[:, 0])
    ground = np.zeros((len(px), 3))
    ground[:, 0], ground[:, 2] = px, pz
    if not mover.any():
        root = ground + quat.rotate(turn_q, root - centre)
    else:  # walks travelling on other joints: each set of frames on its own
        for m in np.unique(mover).tolist():
            on = np.flatnonzero(mover == m)
            if m == 0:
                root[on] = ground[on] + quat.rotate(turn_q[on], root[on] - centre[on])
            else:
                jt[on, m] = ground[on] + quat.rotate(turn_q[on], jt[on, m] - centre[on])
    down = settle[:, None] * support
    # Stepping on the spot (strides of nothing) a foot stays flat through its swing as well: landing
    # turned up as a walk's heel strike, held where it touched, it rolled down about its heel and
    # stood short of its place by the roll.
    flat = np.maximum(down, (settle * (1.0 - np.minimum(stride, 1.0)))[:, None])
    return rot, root, jt, contact, turn_q, forward, down, _laid(flat, held, dt, states, counts)


def _laid(flat: np.ndarray, held: np.ndarray | None, dt: float, states: list, counts: list) -> np.ndarray:
    """(R, 2) how far each foot is laid down, for walks' frames stacked: following ``flat`` (R, 2) (their stance
    share), but let go no faster than over :data:`LAY_RELEASE_S` (:func:`_slow_fall`) from each walk's state
    (``states``, its ``laid`` carried on; ``counts`` (W,) frames each), and not at all on the frames ``held``
    (R,) bool (None: none). At the stop's quicker cadence the share falls within a frame or two before toe
    off, and the foot would turn from lying flat to the animation's toe off at once. Standing still at the
    end of a stop without an idle, a foot lies down no less than as the stop's last step left it until it
    comes to rest (the held phase may be past the trailing foot's toe off starting): there it does not fall."""
    release = dt / LAY_RELEASE_S
    f = counts[0]
    if (held is None or not held.any()) and counts.count(f) == len(counts):
        laid = _slow_fall(flat.reshape(-1, f, 2), np.array([st.laid for st in states]), release).reshape(-1, 2)
    else:
        laid = np.empty_like(flat)
        for st, c, e in zip(states, counts, itertools.accumulate(counts)):
            on = held[e - c:e] if held is not None else None
            step = np.where(on, 0.0, release)[:, None] if on is not None and on.any() else release
            laid[e - c:e] = _slow_fall(flat[e - c:e], st.laid, step)
    for st, at in zip(states, laid[np.array(list(itertools.accumulate(counts))) - 1]):
        st.laid = at
    return laid


def _cycle_means(b: LocomotionBinding, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cycle means the blend ``w`` (F, N) of the clips' gives :meth:`Locomotion._shorten`: the body's mean
    rotations (F, B, 4) (the root's in the clips' facing frame), each ankle's mean offset from the hips (F, 2, 3)
    and its lowest height (F, 2) m (:func:`_kept`)."""
    return _kept(b, ("means", w.tobytes()), lambda: (quat.normalize((w @ b.body_means).reshape(len(w), -1, 4)),
                                                     (w @ b.ankle_means.reshape(len(b.ankle_means), 6)).reshape(-1, 2, 3),
                                                     w @ b.ankle_low))


def _shortened(b: LocomotionBinding, w, stride, rot, root, jt, turn_q, forward, settle, down, laid):
    """:meth:`Locomotion._shorten` on the arrays given (see there); returns the rotations and the joint
    translations or None, shortened."""
    Locomotion._shorten(b, w, stride, rot, root, jt, turn_q, forward, settle, down, laid)
    return rot, jt


#: Each blend space's :func:`_space_content`, by the space's id, for as long as the space lives.
_CONTENTS: dict[int, str] = {}


def _space_content(space) -> str:
    """A digest of what :func:`_prepare` reads of a blend space: its clips (motions, keys, contacts,
    parameters) and tessellations. Worked out once per space: spaces infused alike (one pack on
    characters of one asset, infused for each) share one prepared binding, not one each, prepared again
    whenever another of them walked last."""
    known = _CONTENTS.get(id(space))
    if known is None:
        digest = hashlib.blake2b(digest_size=20)

        def add(*values) -> None:
            for v in values:
                if isinstance(v, np.ndarray):
                    digest.update(repr((v.dtype.str, v.shape)).encode())
                    digest.update(np.ascontiguousarray(v).tobytes())
                else:
                    digest.update(repr(v).encode())

        add(space.pack, space.version, space.kind)
        for name in sorted(space.clips):
            c = space.clips[name]
            m = c.motion
            add(name, c.role, c.hand, c.loop, c.stroke, c.transition, sorted((k, repr(v)) for k, v in c.parameters.items()),
                m.fps, m.local_rotations, m.root_translations, m.joint_translations, c.keys, c.contacts, c.phases, c.pelvis)
        for group in sorted(space.tessellations):
            t = space.tessellations[group]
            add(group, t.coordinates, t.labels, t.points, t.origin, t.scale, t.basis, t.simplices)
        known = _CONTENTS[id(space)] = digest.hexdigest()
        weakref.finalize(space, _CONTENTS.pop, id(space), None)
    return known


#: Each binding's :func:`_stack_key`, kept for as long as the binding lives.
_STACK_KEYS: weakref.WeakKeyDictionary[LocomotionBinding, tuple] = weakref.WeakKeyDictionary()


def _stack_key(b: LocomotionBinding) -> tuple:
    """What the walks pinned and kept up together share (:meth:`Locomotion.evaluate`): the skeleton (the
    same object), the legs, how low the feet may go (:class:`~.binding.FootFloors`, by value) and how
    fast a held heel's foot pitches down (``landing_rad_s``).
    Characters of one asset walking one pack have it alike, each with its own binding."""
    key = _STACK_KEYS.get(b)
    if key is None:
        f = b.floors
        floors = None if f is None else tuple(tuple(np.asarray(v).ravel().tolist()) for v in (
            f.ankles, f.balls, f.ankle_parents, f.ball_parents, f.point, f.kept, f.tip, f.toes, f.point_floor, f.tip_floor, f.across, f.release, f.heels, f.heel_turns))
        key = _STACK_KEYS[b] = (id(b.skeleton), tuple(b.legs), floors, b.landing_rad_s)
    return key


def _prepare(space, clips, sk, legs, pelvis: int = 0) -> LocomotionBinding:
    """What walking needs of a pack's locomotion ``clips`` on skeleton ``sk`` with ``legs`` ((hip, knee,
    ankle, ball) joints) and its ``pelvis`` joint: the canonical clips, their mean poses, foot events and
    the legs' stances. The same for every walk of a character with that pack, so :meth:`Locomotion.bind` keeps it."""
    prepared = [canonical_clip(c, pelvis) for c in clips]
    p = lambda k: np.array([c.parameters[k] for c in clips])  # noqa: E731
    idle = np.array([c.role == "idle" for c in clips])
    speeds = np.hypot(p("forward_speed"), p("lateral_speed"))
    slowest = np.full(len(clips), 0.0)
    slowest[_slowest_walk(clips)] = 1.0
    motions = [m for m, _ in prepared]
    limbs = np.zeros(sk.num_joints, dtype=np.int64)  # 0 body, 1 left leg, 2 right leg
    for k, leg in enumerate(legs[:2] if len(legs) == 2 else []):
        limbs[leg[0]] = k + 1
    for j in range(sk.num_joints):
        if limbs[j] == 0 and sk.parents[j] >= 0:
            limbs[j] = limbs[sk.parents[j]]
    means = [mean_rotations(m) for m in motions]
    signs = [np.where(np.sum(m * means[0], axis=-1, keepdims=True) < 0.0, -1.0, 1.0) for m in means]
    ankle_means = np.zeros((len(clips), 2, 3))  # (N, foot, 3) ankle from the hips' midpoint, facing frame
    ankle_low = np.zeros((len(clips), 2))  # (N, foot) lowest ankle height over the cycle
    grounded_m, heel_levers, sole_floor, leg_length = 0.0, None, np.zeros(2), 0.0
    if len(legs) == 2:  # one FK over every clip's cycle (its closing frame left out)
        cycles = [slice(0, max(m.num_frames - 1, 1)) for m in motions]
        moved = any(m.joint_translations is not None for m in motions)
        _, pos = chain_fk(sk, np.concatenate([m.local_rotations[c] for m, c in zip(motions, cycles)]),
                          np.concatenate([m.root_translations[c] for m, c in zip(motions, cycles)]),
                          np.concatenate([m.local_translations()[c] for m, c in zip(motions, cycles)]) if moved else None,
                          [legs[0][0], legs[1][0], legs[0][2], legs[1][2]] + [leg[2] if leg[3] is None else leg[3] for leg in legs])
        ankles = pos[:, 2:4] - 0.5 * (pos[:, 0] + pos[:, 1])[:, None]
        start, heights = 0, []
        for i, c in enumerate(cycles):
            ankle_means[i] = ankles[start:start + c.stop].mean(axis=0)
            ankle_low[i] = pos[start:start + c.stop, 2:4, 1].min(axis=0)
            feet = pos[start:start + c.stop, 2:, 1].reshape(-1, 2, 2).swapaxes(1, 2)  # (F, foot, ankle / ball)
            heights.append(np.concatenate((feet, feet[:1])))  # the loop closed
            start += c.stop
        rest = sk.rest_global_positions
        leg_length = float(np.mean([np.linalg.norm(rest[leg[1]] - rest[leg[0]]) + np.linalg.norm(rest[leg[2]] - rest[leg[1]])
                                    for leg in legs]))
        grounded_m = GROUNDED * leg_length
        planted_feet = np.concatenate([c.contacts[s] for c, s in zip(clips, cycles)])
        sole_floor = np.array([footing.planted_height(pos[:, 4 + k, 1], planted_feet[:, k]) for k in range(2)])
        if all(leg[3] is not None for leg in legs):
            heel_levers = _heel_levers(pos[:, 2:4], pos[:, 4:6], np.concatenate([c.contacts[s] for c, s in zip(clips, cycles)]), leg_length)
        # Strikes where the heels reach the ground, toe offs where the balls leave it (the takes' feet
        # land and push off moving, on the ground a few frames beyond their contacts).
        events = [foot_events(c, h, leg_length) if c.role != "idle" else None for c, h in zip(clips, heights)]
    else:
        events = [foot_events(c) if c.role != "idle" else None for c in clips]
    # The idle's feet (ankle and ball rotations, facing frame): how a stop lays them down. Without an
    # idle, each foot as it lies flat in the slowest straight walk forward, the one stops play (midway
    # from foot flat to heel off; else the slowest stepping clip): a walk back's feet land by the toes.
    # The same poses give the heights the feet stand at: no foot goes lower (:func:`_keep_feet_up`).
    stance_feet = floors = None
    walking = [(int(i), e) for i in np.argsort(np.where(idle, np.inf, np.where(slowest > 0.0, -1.0, speeds)))
               if (e := events[i]) is not None and not idle[i]]
    if len(legs) == 2 and (idle.any() or walking):
        if idle.any():
            m, frames = motions[int(np.argmax(idle))], np.zeros(2, dtype=np.int64)
        else:
            i, slowest_events = walking[0]
            m = motions[i]
            flat = np.mod(0.5 * (slowest_events[:, 1] + slowest_events[:, 2]), 1.0)
            frames = np.clip(np.round(warp(np.asarray(clips[i].keys), flat) * m.fps).astype(np.int64), 0, m.num_frames - 1)
        floors = _floors(sk, legs, m, frames, leg_length, _toes_rate(sk, legs, [mv for mv, e in zip(motions, events) if e is not None]))
        if all(leg[3] is not None for leg in legs):
            g_rot, _ = chain_fk(sk, m.local_rotations[frames], m.root_translations[frames],
                                None if m.joint_translations is None else m.joint_translations[frames],
                                [legs[0][2], legs[0][3], legs[1][2], legs[1][3]])
            stance_feet = np.stack((g_rot[0, :2], g_rot[1, 2:]))
    played = transitions.played(space, _standing_speed(clips)) if len(legs) == 2 else []
    # Each played transition's facing (F,) radians, contact phases (F, 2, 2) and motion (its swivelling feet lifted).
    played_facing, played_phases, played_motions = {}, {}, {}
    for c in played:
        m = c.motion
        _, pos = chain_fk(sk, m.local_rotations, m.root_translations, m.joint_translations,
                          [legs[0][0], legs[1][0], legs[0][2], legs[1][2]] + [leg[2] if leg[3] is None else leg[3] for leg in legs])
        left = pos[:, 0] - pos[:, 1]
        h = np.unwrap(np.arctan2(-left[:, 2], left[:, 0]))
        played_facing[c.name] = h + 2.0 * math.pi * round((c.parameters["facing_start"] - h[0]) / (2.0 * math.pi))
        heights = pos[:, 2:, 1].reshape(-1, 2, 2).swapaxes(1, 2)  # (F, foot, ankle / ball)
        grounded = transitions.grounded(c.phases, heights, GROUNDED * leg_length, LIFTED * leg_length, GROUNDED_SHARE)
        played_motions[c.name], played_phases[c.name] = swivels.lift_swivels(sk, m, legs, grounded, played_facing[c.name], leg_length)
    body = np.nonzero(limbs == 0)[0]
    walk_speeds, walk_cadences = straight_walk(space, clips)
    stand_height = 0.0 if idle.any() or len(legs) != 2 else _stand_height(sk, legs, motions[int(np.argmax(slowest))], clips[int(np.argmax(slowest))], pelvis)
    two = len(legs) == 2  # the joints the stride and the pinning work on, both legs at once
    balls = np.array([leg[2] if leg[3] is None else leg[3] for leg in legs] if two else [], dtype=np.int64)
    return LocomotionBinding(
        space=space, clips=clips, limit=space.speed_limit(), table=LoopTable(motions), movers=[mv for _, mv in prepared],
        velocities=np.stack((p("forward_speed"), p("lateral_speed"), p("turn_rate")), axis=1),
        durations=np.array([(c.keys[2] - c.keys[0]) for c in clips]), keys=np.array([c.keys for c in clips]),
        events=np.array([np.zeros((2, 4)) if e is None else e for e in events]),
        stepping=np.array([e is not None for e in events]), idle=idle, slowest=slowest,
        body_means=(np.stack([m[body] for m in means]) * np.stack(signs)[:, body]).reshape(len(clips), -1),
        ankle_means=ankle_means, ankle_low=ankle_low, played=played, stops=transitions.stops(played),
        played_facing=played_facing, played_phases=played_phases, played_motions=played_motions, skeleton=sk, pelvis=pelvis, legs=legs, limbs=limbs,
        body=body, grounded_m=grounded_m, stance_feet=stance_feet, floors=floors,
        leg_limbs=[(leg[0], leg[1], leg[2]) for leg in legs] if two else [], balls=balls,
        has_ball=np.array([leg[3] is not None for leg in legs] if two else [], dtype=bool),
        balls_on_ankles=np.array([k for k, leg in enumerate(legs) if two and leg[3] is not None
                                  and int(sk.parents[leg[3]]) == leg[2]], dtype=np.int64),
        pin_joints=[j for leg, ball in zip(legs, balls.tolist())
                    for j in (*leg[:3], leg[0] if sk.parents[leg[0]] < 0 else int(sk.parents[leg[0]]), ball)],
        walk_speeds=walk_speeds, walk_cadences=walk_cadences, heel_levers=heel_levers, sole_floor=sole_floor,
        touch_m=TOUCH * leg_length, landing_rad_s=_landing_rate(sk, legs, [mv for mv, e in zip(motions, events) if e is not None], leg_length),
        stand_height=stand_height)


def _stand_height(sk, legs, motion, clip, pelvis: int) -> float:
    """The height (m, above the clips' ground) the ``pelvis`` joint stands at over legs as straight as
    the straightest stance leg of a walk's canonical ``motion`` (its ``clip``'s cycle): each leg's hip
    that far (its hip-to-ankle distance, at most :data:`STAND_REACH` of the leg) straight above its
    ankle's lowest height, the pelvis as high above the hip as on that frame; the mean of the two legs,
    0 where no foot is planted."""
    cycle = slice(0, max(motion.num_frames - 1, 1))
    planted = np.asarray(clip.contacts[cycle], dtype=bool)
    if not planted.any():
        return 0.0
    _, pos = chain_fk(sk, motion.local_rotations[cycle], motion.root_translations[cycle],
                      None if motion.joint_translations is None else motion.local_translations()[cycle],
                      [pelvis, legs[0][0], legs[1][0], legs[0][2], legs[1][2]])
    reach = np.where(planted, np.linalg.norm(pos[:, 1:3] - pos[:, 3:5], axis=-1), -np.inf)  # (F, 2)
    straightest = np.argmax(reach, axis=0)
    rest = sk.rest_global_positions
    most = [STAND_REACH * (np.linalg.norm(rest[leg[1]] - rest[leg[0]]) + np.linalg.norm(rest[leg[2]] - rest[leg[1]])) for leg in legs]
    heights = [pos[:, 3 + k, 1].min() + min(reach[f, k], most[k]) + pos[f, 0, 1] - pos[f, 1 + k, 1]
               for k, f in enumerate(straightest.tolist()) if planted[:, k].any()]
    return float(np.mean(heights))


def _tip(sk, joint: int) -> np.ndarray | None:
    """(3,) the offset of ``joint``'s farthest child joint or end site in its frame (at rest), or None."""
    offsets = [sk.rest_translations[c] for c in np.flatnonzero(sk.parents == joint)]
    offsets += [o for j, o in zip(sk.end_site_parents, sk.end_site_offsets) if j == joint]
    if not offsets:
        return None
    far = max(offsets, key=lambda o: float(np.linalg.norm(o)))
    return np.array(far) if np.linalg.norm(far) > 1e-6 else None


def _toes_rate(sk, legs, motions) -> float:
    """How fast (radians per second) the toes of a pack's stepping clips ``motions`` turn against their
    feet: the median over the clips and feet of the 99th percentile of the ball joint's turn relative to
    the ankle between frames, at least :data:`TOE_RELEASE_DEG_S` (0 rad/s without ball joints)."""
    if not motions or any(leg[3] is None for leg in legs):
        return 0.0
    rates: list[float] = []
    for m in (m for m in motions if m.num_frames > 1):
        g_rot, _ = chain_fk(sk, m.local_rotations, m.root_translations, m.joint_translations,
                            [legs[0][2], legs[0][3], legs[1][2], legs[1][3]])
        toes = quat.multiply(quat.conjugate(g_rot[:, [0, 2]]), g_rot[:, [1, 3]])  # (F, 2, 4) against the feet
        rates.extend(np.percentile(quat.angle_between(toes[:-1], toes[1:]) * m.fps, 99, axis=0).tolist())
    return max(float(np.median(rates)) if rates else 0.0, math.radians(TOE_RELEASE_DEG_S))


def _landing_rate(sk, legs, motions, leg_length: float) -> float:
    """How fast (radians per second) the feet of a pack's stepping clips ``motions`` turn near the ground
    (ankle within :data:`TOUCH` of the leg ``leg_length`` (m) of its lowest in the clip, on both frames):
    the median over the clips and feet of the 99th percentile of the ankle's turn between such frames
    (infinite without two legs or clips: no limit)."""
    if len(legs) != 2 or not motions:
        return math.inf
    rates: list[float] = []
    for m in (m for m in motions if m.num_frames > 1):
        g_rot, g_pos = chain_fk(sk, m.local_rotations, m.root_translations, m.joint_translations, [legs[0][2], legs[1][2]])
        low = g_pos[..., 1] < g_pos[..., 1].min(axis=0) + TOUCH * leg_length  # (F, 2)
        low = low[1:] & low[:-1]
        turn = quat.angle_between(g_rot[:-1], g_rot[1:]) * m.fps  # (F - 1, 2)
        rates.extend(float(np.percentile(turn[low[:, k], k], 99)) for k in range(2) if low[:, k].any())
    return float(np.median(rates)) if rates else math.inf


def _floors(sk, legs, motion, frames, leg_length: float, toes_rate: float = 0.0) -> FootFloors | None:
    """What :func:`_keep_feet_up` needs of two ``legs`` on skeleton ``sk``, standing in ``motion``'s
    ``frames`` (2,) (one per foot), the toes kept up unbending at most ``toes_rate`` (rad/s, :func:`_toes_rate`;
    :data:`TOE_RELEASE_DEG_S` when 0): each foot's ankle, its "ball" (the ball joint, else the ankle), the
    tip of a foot without a ball joint (its farthest child or end site, a tenth of the leg's length
    ``leg_length`` (m) or more from the ankle; an offset (3,) in the ankle's frame), the toes' tip (offset in the ball's frame; only with a ball joint), the joints they hang
    from, and the heights (m) the two tips stand at; None where neither foot has a tip. Both feet stand on
    one ground: where both have a tip, both stand at the lower of their heights (a foot-flat frame whose
    toes are bent up, as in a walk back, would otherwise hold that foot's toes up all the walk)."""
    ankles = np.array([leg[2] for leg in legs])
    balls = np.array([leg[2] if leg[3] is None else leg[3] for leg in legs])
    point = np.zeros((2, 3))
    tip = np.zeros((2, 3))
    kept = np.zeros(2, dtype=bool)
    toes = np.zeros(2, dtype=bool)
    for k, leg in enumerate(legs):
        end = _tip(sk, int(balls[k]))
        if leg[3] is None:  # a tip on the ankle itself (a capture's end site) is no foot's tip
            end = end if end is not None and np.linalg.norm(end) >= 0.1 * leg_length else None
            kept[k] = end is not None
            point[k] = 0.0 if end is None else end
        else:
            toes[k] = end is not None
            tip[k] = 0.0 if end is None else end
    if not (kept | toes).any():
        return None
    ankle_parents = np.array([max(int(sk.parents[a]), 0) for a in ankles])
    ball_parents = np.array([max(int(sk.parents[b]), 0) for b in balls])
    joints = np.stack((ankle_parents, ankles, ball_parents, balls), axis=1)  # (2, 4)
    g_rot, g_pos = chain_fk(sk, motion.local_rotations[frames], motion.root_translations[frames],
                            None if motion.joint_translations is None else motion.joint_translations[frames], joints.ravel())
    g_rot, g_pos = g_rot.reshape(2, 2, 4, 4)[[0, 1], [0, 1]], g_pos.reshape(2, 2, 4, 3)[[0, 1], [0, 1]]
    point_floor = (g_pos[:, 3] + quat.rotate(g_rot[:, 3], point))[:, 1]
    tip_floor = (g_pos[:, 3] + quat.rotate(g_rot[:, 3], tip))[:, 1]
    if kept.all():
        point_floor[:] = point_floor.min()
    if toes.all():
        tip_floor[:] = tip_floor.min()
    # Children of a ball joint carrying joints behind it (a heel joint hanging from the toes, 25 cm
    # behind them on SmartBody's rigs): each with its rotation against the ankle at rest.
    rest_rot, rest_pos = sk.rest_global_rotations, sk.rest_global_positions
    heels, heel_turns = [], []
    for k, leg in enumerate(legs):
        if leg[3] is None:
            continue
        forward = (rest_pos[leg[3]] - rest_pos[leg[2]]) * np.array([1.0, 0.0, 1.0])
        size = float(np.linalg.norm(forward))
        for child in np.flatnonzero(sk.parents == leg[3]).tolist():
            below = _subtree(sk, child)
            if size > 1e-9 and ((rest_pos[below] - rest_pos[leg[3]]) @ forward < -0.5 * size * size).any():
                heels.append((k, child))
                heel_turns.append(quat.multiply(quat.conjugate(rest_rot[leg[2]]), rest_rot[child]))
    ahead = g_pos[:, 3] + quat.rotate(g_rot[:, 3], np.where(kept[:, None], point, tip)) - g_pos[:, 1]
    across = np.stack((-ahead[:, 2], np.zeros(2), ahead[:, 0]), axis=-1)  # ahead x +Y
    across /= np.maximum(np.linalg.norm(across, axis=-1, keepdims=True), 1e-12)
    return FootFloors(ankles=ankles, balls=balls, ankle_parents=ankle_parents, ball_parents=ball_parents,
                      joints=joints.ravel(), point=point, kept=kept, tip=tip, toes=toes,
                      point_floor=point_floor, tip_floor=tip_floor, across=quat.rotate(quat.conjugate(g_rot[:, 1]), across),
                      release=toes_rate if toes_rate > 0.0 else math.radians(TOE_RELEASE_DEG_S),
                      heels=np.array(heels, dtype=np.int64).reshape(-1, 2), heel_turns=np.array(heel_turns).reshape(-1, 4))


def _subtree(sk, joint: int) -> list[int]:
    """``joint`` and every joint below it."""
    inside = np.zeros(sk.num_joints, dtype=bool)
    inside[joint] = True
    for j in range(joint + 1, sk.num_joints):  # parents precede children
        inside[j] = sk.parents[j] >= 0 and inside[sk.parents[j]]
    return np.flatnonzero(inside).tolist()


def _lift(v: np.ndarray, height: np.ndarray, along: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The horizontal axes (..., 3) across directions ``along`` (..., 3) (``along`` x +Y) and the
    turns (...) radians about them that give offsets ``v`` (..., 3) vertical component ``height``
    (...), turning ``v``'s end up in front (toes bending up, a foot's heel coming down); zero where
    ``v`` already reaches that high. A turn is at most :data:`LIFT_MAX_DEG`, less as ``v`` comes to
    point straight down or back (none then: which way is up in front is lost)."""
    # Written out component by component: numpy's generic cross, norm, stack and clip cost more than
    # the arithmetic on a block's few feet.
    ax, az = -along[..., 2], along[..., 0]
    size = np.maximum(np.sqrt(ax * ax + az * az), 1e-12)
    ax, az = ax / size, az / size
    axis = np.zeros(along.shape)
    axis[..., 0], axis[..., 2] = ax, az
    # The height after a turn t about the axis is c cos t + s sin t (the axis is horizontal); with
    # s > 0 it rises from t = 0 to its top at t = atan2(s, c), in (0, pi).
    c, s = v[..., 1], az * v[..., 0] - ax * v[..., 2]  # s: (axis x v)'s vertical component
    r = np.maximum(np.hypot(c, s), 1e-12)
    angle = np.maximum(np.arctan2(s, c) - np.arccos(np.minimum(np.maximum(height / r, -1.0), 1.0)), 0.0)
    most = math.radians(LIFT_MAX_DEG) * np.minimum(np.maximum(4.0 * s / r, 0.0), 1.0)  # 15 degrees or more off straight down
    return axis, np.where(c < height, np.minimum(angle, most), 0.0)


def _feet_below(sk, floors: FootFloors, rot, jt, above: np.ndarray, ankles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The global rotations (F, 2, 4, 4) of each foot's ankle's parent, ankle, ball's parent and ball
    (``floors.joints``' order) and the positions (F, 2, 2, 3) of its ankle and ball in the pose ``rot`` (F, J, 4), ``jt`` (F, J, 3) or
    None, from the ankles' parents' global rotations ``above`` (F, 2, 4) and the ankles' positions
    ``ankles`` (F, 2, 3) (the leg IK's): the joints down from the ankle to the ball, stepped as a forward
    kinematics would (the rotations composed in its order)."""
    frames = len(rot)
    g_rot, g_pos = np.empty((frames, 2, 4, 4)), np.empty((frames, 2, 2, 3))
    g_rot[:, :, 0], g_pos[:, :, 0] = above, ankles
    g_rot[:, :, 1] = ankle_rot = quat.multiply(above, rot[:, floors.ankles])
    for foot, steps in _foot_steps(sk, floors):
        rotation, position, parent_rot = ankle_rot[:, foot], ankles[:, foot], above[:, foot]
        for js in steps:
            offset = sk.rest_translations[js] if jt is None else jt[:, js]
            parent_rot = rotation
            position = position + quat.rotate(rotation, offset)
            rotation = quat.multiply(rotation, rot[:, js])
        g_rot[:, foot, 2], g_rot[:, foot, 3], g_pos[:, foot, 1] = parent_rot, rotation, position
    return g_rot, g_pos


#: Each skeleton's joints from its feet's ankles down to their balls (:func:`_foot_steps`), by ankles and balls.
_FOOT_STEPS: weakref.WeakKeyDictionary[Any, dict[tuple, list]] = weakref.WeakKeyDictionary()


def _foot_steps(sk, floors: FootFloors) -> list[tuple[int | slice, np.ndarray]]:
    """The joints below each foot's ankle down to its ball (``floors.ankles``, ``floors.balls``), as (feet,
    joints) pairs: both feet side by side (all feet, joints (S, 2)) where their paths are as long, else
    each alone (its index, joints (S,)); none where the ball is the ankle. Worked out once per skeleton."""
    key = (*floors.ankles.tolist(), *floors.balls.tolist())
    known = _FOOT_STEPS.setdefault(sk, {})
    steps = known.get(key)
    if steps is None:
        paths = []
        for ankle, ball in zip(key[:2], key[2:]):
            path, j = [], ball
            while j != ankle:
                path.append(j)
                j = int(sk.parents[j])
            paths.append(path[::-1])
        steps = known[key] = [(slice(None), np.array(paths, dtype=np.int64).reshape(2, -1).T)] if len(paths[0]) == len(paths[1]) \
            else [(k, np.array(p, dtype=np.int64)) for k, p in enumerate(paths)]
    return steps


def _keep_feet_up(sk, floors: FootFloors, rot, root, jt, runs, dt: float, feet: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """No toes lower than they stand (in place; see :func:`_floors`): where the tip of a foot without a
    ball joint would go below the height it stands at, the foot pitches about its ankle until it does
    not; where the toes' tip of a foot with one would, the toes bend up about the ball, and unbend
    no faster than the pack's toes turn (``floors.release``; ``st.toe_bend`` carries the bends, radians, from block
    to block). A foot rolling over its ball at toe off pitches as the pack's does: a longer foot, or
    toes the pack's clips do not bend, would dig into the ground. Both turns are about the horizontal
    axis across the foot or toes. ``rot`` (F, J, 4), ``root`` (F, 3), ``jt`` (F, J, 3) or None; ``feet``: the
    feet's joints' global rotations and positions (:func:`_feet_below`) when the caller has them."""
    if feet is None:
        g_rot, g_pos = chain_fk(sk, rot, root, jt, floors.joints)
        g_rot, g_pos = g_rot.reshape(len(rot), 2, 4, 4), g_pos.reshape(len(rot), 2, 4, 3)[:, :, 1::2]
    else:
        g_rot, g_pos = feet
    ankle, ball = g_pos[:, :, 0], g_pos[:, :, 1]
    ball_rot, ball_parent = g_rot[:, :, 3], g_rot[:, :, 2]
    # Ahead along each foot as it stands, carried by its ankle (+Y x the axis across it): the axis the
    # turns are about stays across the foot when its ankle-to-tip direction points down or back (a foot
    # pitched over its ball at toe off), which would flip it and bend the toes down a frame.
    across = quat.rotate(g_rot[:, :, 1], floors.across)
    ahead = np.zeros(across.shape)
    ahead[..., 0], ahead[..., 2] = across[..., 2], -across[..., 0]
    angle = None
    if _any(floors.kept):
        point = ball + quat.rotate(g_rot[:, :, 3], floors.point) - ankle
        axis, angle = _lift(point, floors.point_floor - ankle[..., 1], ahead)
        angle = angle * floors.kept
    if angle is not None and _any(angle):  # feet that pitch (others keep their rotations as they are)
        pitch = quat.from_axis_angle(axis, angle)
        ankle_rot = quat.multiply(pitch, g_rot[:, :, 1])
        rot[:, floors.ankles] = quat.multiply(quat.conjugate(g_rot[:, :, 0]), ankle_rot)
        # Below the ankle everything turned by the pitch: the ball, its parent and the tip.
        ball = ankle + quat.rotate(pitch, ball - ankle)
        ball_rot = quat.multiply(pitch, ball_rot)
        ball_parent = np.where((floors.ball_parents == floors.ankles)[None, :, None], ankle_rot,
                               quat.multiply(pitch, ball_parent))
    if not _any(floors.toes):
        return
    tip = quat.rotate(ball_rot, floors.tip)
    axis, angle = _lift(tip, floors.tip_floor - ball[..., 1], ahead)  # across the whole foot
    if len(runs) > 1 and len({a1 - a0 for _, a0, a1 in runs}) == 1:  # walks as long: side by side, in one go
        up = _slow_fall(angle.reshape(len(runs), -1, angle.shape[-1]), np.stack([st.toe_bend for st, _, _ in runs]),
                        floors.release * dt).reshape(angle.shape)
        for st, _, a1 in runs:
            st.toe_bend = up[a1 - 1].copy()
    else:
        up = np.empty(angle.shape)
        for st, a0, a1 in runs:
            up[a0:a1] = _slow_fall(angle[a0:a1], st.toe_bend, floors.release * dt)
            st.toe_bend = up[a1 - 1].copy()
    up = up * floors.toes
    if _any(up):  # toes bent (else they keep their rotations)
        ball_rot = quat.multiply(quat.from_axis_angle(axis, up), ball_rot)
        rot[:, floors.balls] = np.where(floors.toes[None, :, None], quat.multiply(quat.conjugate(ball_parent), ball_rot),
                                        rot[:, floors.balls])
    if floors.heels.size:  # joints of the foot hanging from the toes stay with the foot, however the toes bend
        k, child = floors.heels[:, 0], floors.heels[:, 1]
        rot[:, child] = quat.multiply(quat.conjugate(ball_rot[:, k]), quat.multiply(g_rot[:, k, 1], floors.heel_turns))


def _slowest_walk(clips) -> int:
    """Index of the slowest straight walk forward among locomotion ``clips`` (not a strafe or a turn;
    of any moving clip without one): what slow walks and stops play."""
    v = np.array([[c.parameters[k] for k in ("forward_speed", "lateral_speed", "turn_rate")] for c in clips])
    moving = np.nonzero([c.role != "idle" for c in clips])[0]
    ahead = moving[(v[moving, 0] > 2.0 * np.abs(v[moving, 1])) & (np.abs(v[moving, 2]) < math.radians(10.0))]
    pool = ahead if ahead.size else moving
    return int(pool[np.argmin(np.hypot(v[pool, 0], v[pool, 1]))])


def _standing_speed(clips) -> float:
    """Below this speed (m/s) a character stands: :data:`STAND_FRACTION` of the slowest walk's."""
    p = clips[_slowest_walk(clips)].parameters
    return STAND_FRACTION * math.hypot(p["forward_speed"], p["lateral_speed"])




def _heel_levers(ankles: np.ndarray, balls: np.ndarray, planted: np.ndarray, leg_length: float) -> np.ndarray:
    """(2, 3) each foot's sole under the heel, the point below its ankle at its ball's height, as an
    offset in the foot's frame (:func:`infuse.contacts.foot_frames`), as the skate measure finds it
    (:func:`infuse.contacts.sole_positions`): the median over the frames the foot lies flat, planted
    with its ankle and ball lowest (their summed height within ``DOWN_TOLERANCE`` leg lengths of its
    least; an idle may stand a foot on its ball). ``ankles``, ``balls`` (F, 2, 3) metres, ``planted``
    (F, 2) bool, over the clips' cycles."""
    height = ankles[..., 1] + balls[..., 1]
    candidates = planted | ~planted.any(axis=0)
    least = np.where(candidates, height, np.inf).min(axis=0)
    flat = candidates & (height <= least + DOWN_TOLERANCE * leg_length)
    drop = np.zeros(ankles.shape)
    drop[..., 1] = balls[..., 1] - ankles[..., 1]
    local = np.einsum("fkij,fkj->fki", foot_frames(ankles, balls), drop)
    return np.stack([np.median(local[flat[:, k], k], axis=0) for k in range(2)])


def _heel_of(b: LocomotionBinding, k: int | np.ndarray, reach: np.ndarray) -> np.ndarray:
    """(..., 3) from foot ``k``'s ankle to the sole under its heel (metres), the foot's ankle-to-ball
    vectors being ``reach`` (..., 3): ``b.heel_levers`` carried by the foot's frame (:func:`_soles`) as
    the skate measure carries it; zeros (the ankle) without. With feet ``k`` (P,), one for each row of
    ``reach`` (P, n, 3)."""
    if b.heel_levers is None:
        return np.zeros_like(reach)
    lever = b.heel_levers[k]
    return _soles(lever if lever.ndim == 1 else lever[:, None], reach)


def _heels_of(owners: list[tuple[LocomotionBinding, int]], feet: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """(P, n, 3) :func:`_heel_of` of feet ``feet`` (P,) of several bindings (``owners``: each with how many
    of the feet in turn are its walks'), their ankle-to-ball vectors ``reach`` (P, n, 3)."""
    if all(b.heel_levers is None for b, _ in owners):
        return np.zeros_like(reach)
    levers = np.concatenate([np.zeros((e - a, 3)) if b.heel_levers is None else b.heel_levers[feet[a:e]]
                             for (b, _), a, e in zip(owners, *_row_bounds([count for _, count in owners]))])
    return _soles(levers[:, None], reach)


def _heel_heights(b: LocomotionBinding, reach: np.ndarray) -> np.ndarray:
    """(..., 2) how high the soles under both feet's heels lie above their ankles (metres, :func:`_heel_of`'s
    vertical parts), their ankle-to-ball vectors being ``reach`` (..., 2, 3)."""
    if b.heel_levers is None:
        return np.zeros(reach.shape[:-1])
    return _soles(b.heel_levers, reach, heights=True)


def _soles(lever: np.ndarray, reach: np.ndarray, heights: bool = False) -> np.ndarray:
    """(..., 3) offsets ``lever`` (..., 3, broadcast to ``reach``) in the frames of feet whose ankle-to-ball
    vectors are ``reach`` (..., 3), in the world (metres); with ``heights`` only their vertical parts (...). The frames are
    :func:`infuse.contacts.foot_frames`' (forward along ``reach``, side horizontal, up), written out
    axis by axis on the foot's pitch: the frames themselves cost more on a block's few feet."""
    forward = reach / np.maximum(np.sqrt((reach * reach).sum(axis=-1, keepdims=True)), 1e-12)
    fx, fy, fz = forward[..., 0], forward[..., 1], forward[..., 2]
    level = np.maximum(np.sqrt(fx * fx + fz * fz), 1e-12)  # the forward axis' horizontal length
    if heights:
        up: np.ndarray = lever[..., 0] * fy + lever[..., 2] * level
        return up
    along, side = lever[..., 0] - lever[..., 2] * fy / level, lever[..., 1] / level  # along the ground ahead, across
    out = np.empty(reach.shape)
    out[..., 0], out[..., 1], out[..., 2] = fx * along - fz * side, lever[..., 0] * fy + lever[..., 2] * level, fz * along + fx * side
    return out


def _heels_up(b: LocomotionBinding, g_rot: np.ndarray, g_pos: np.ndarray) -> np.ndarray | None:
    """(F, 2) bool: the feet whose heel the pose has lifted, its sole under the heel more than
    ``b.grounded_m`` above the ball's height (level with it lying flat), from the legs' global
    rotations and positions (F, 2, 5, 4 / 3) as :meth:`Locomotion._pin` has them (the ankle third,
    the ball last); None without the feet's flat pose (``b.heel_levers``)."""
    if b.heel_levers is None:
        return None
    reach = g_pos[:, :, 4] - g_pos[:, :, 2]
    heel = g_pos[:, :, 2, 1] + _heel_heights(b, reach)
    up: np.ndarray = heel - g_pos[:, :, 4, 1] > b.grounded_m
    return up


def _turn_feet(b: LocomotionBinding, rot, rise) -> np.ndarray:
    """Turn both feet by ``rise`` (F, 2, 3) rotation vectors in their own frames, in place, the toes
    keeping their orientation where the ball joint hangs from the ankle; returns the turns (F, 2, 4)."""
    delta = _from_rotvec(rise)
    ankles = [leg[2] for leg in b.legs]
    rot[:, ankles] = quat.multiply(rot[:, ankles], delta)
    k = b.balls_on_ankles
    if k.size:
        rot[:, b.balls[k]] = quat.multiply(quat.conjugate(delta[:, k]), rot[:, b.balls[k]])
    return delta


def _share_of(turn: np.ndarray, share) -> np.ndarray:
    """Turns (F, 4) by ``share`` (F,) in [0, 1] of the turn ``turn`` (4,): the slerp from the identity,
    its angle worked out once (``quat.slerp``'s general form costs more than the maths on a block's
    few frames)."""
    q = turn if turn[3] >= 0.0 else -turn
    theta = math.acos(min(abs(float(q[3])), 1.0))
    s = math.sin(theta)
    t = np.asarray(share, dtype=np.float64)
    if s < 1e-6:  # (nearly) no turn: a plain lerp
        wa, wb = 1.0 - t, t
    else:
        wa, wb = np.sin((1.0 - t) * theta) / s, np.sin(t * theta) / s
    out = wb[..., None] * q
    out[..., 3] += wa
    return out / np.sqrt((out * out).sum(axis=-1, keepdims=True))


def _from_rotvec(rotvec: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4) of rotation vectors (..., 3) (axis times angle, radians), through their axis
    and angle (SciPy's conversion costs more than the maths on a block's few frames)."""
    angle = np.sqrt((rotvec * rotvec).sum(axis=-1))
    return quat.from_axis_angle(rotvec / np.maximum(angle, 1e-300)[..., None], angle)


def _radians(value, name: str, timed: bool = True):
    """A setting ``name`` in degrees in radians: a number, or where ``timed`` a function of seconds."""
    if timed and callable(value):
        return lambda t: math.radians(float(value(t)))
    try:
        return math.radians(float(value))
    except (TypeError, ValueError):
        kind = "a number or a function of seconds" if timed else "a number"
        raise UsageError(f"{name} is degrees ({kind}), not {value!r}") from None


def _towards(direction: float) -> str:
    """A travel direction (radians off the facing, + left) in words."""
    deg = math.degrees(direction)
    return "forward" if abs(deg) < 1.0 else f"{abs(deg):.0f} deg to the {'left' if deg > 0 else 'right'} of the facing"


def _slowest_towards(velocities: np.ndarray, idle: np.ndarray, direction) -> np.ndarray:
    """(F,) speed (m/s) of the slowest moving example travelling within 45 degrees of each ``direction``
    (F,) radians (of any moving example where none does): a pack without an idle walks slower than
    that by slowing it. (A blend of walks forward and back may stand still, but it steps on the spot.)"""
    v = velocities
    moving = ~idle & (np.hypot(v[:, 0], v[:, 1]) > 1e-3)
    speeds = np.where(moving, np.hypot(v[:, 0], v[:, 1]), np.inf)
    off = np.abs((direction[:, None] - np.arctan2(v[:, 1], v[:, 0])[None] + np.pi) % (2.0 * np.pi) - np.pi)
    near = np.where(off < np.pi / 4, speeds[None], np.inf).min(axis=1)
    return np.where(np.isfinite(near), near, speeds.min(initial=np.inf) if moving.any() else 0.0)


def _weights(space, idle: np.ndarray, velocities: np.ndarray, speed, direction,
             turn) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Blend weights (F, N) in the locomotion blend ``space`` (examples ``idle`` (N,) bool, with
    ``velocities`` (N, 3)) for the requests (F,), the moving share (F,) of the slowest walk's speed,
    (F,) flags of the requests inside the tessellation and the share (F,) of the clips not idle (1 - the
    idle's weight; the moving share without an idle):
    where the full request lies outside the tessellation, its turn rate is the nearest one the
    tessellation holds at that velocity (the rest is spun at the root; :meth:`BlendSpace.locomotion_weights`). With an idle among the examples the moving share is one
    minus its weight; without, a request slower than the slowest example in its direction is blended
    at that example's speed and the share is the ratio of the speeds."""
    has_idle = bool(idle.any())
    if not has_idle:
        floor = _slowest_towards(velocities, idle, direction)
        # no slower than the examples not travelling against it reach, which the space blends it from
        reached = space.slowest(direction)
        floor = np.where(np.isfinite(reached), np.maximum(reached, floor), floor)
        slow = np.where(speed < floor, speed / np.maximum(floor, 1e-9), 1.0)
        speed = np.maximum(speed, floor)
    query = np.empty((len(speed), 3))
    query[:, 0], query[:, 1], query[:, 2] = speed * np.cos(direction), speed * np.sin(direction), turn
    w, inside = space.locomotion_weights(query)
    if has_idle:
        moving = 1.0 - np.add.reduce(w[:, idle], axis=1)
        slow = np.minimum(np.maximum(moving, 0.0), 1.0)  # a clip, cheaper than np.clip on few values
    return w, slow, inside, moving if has_idle else slow


def _moving(w: np.ndarray, idle: np.ndarray, slowest: np.ndarray) -> np.ndarray:
    """(F, N) the moving clips' weights from blend weights ``w`` (F, N): the idle's left out, the rest
    renormalized, turning into the slowest walk (``slowest`` (N,) one there) as their share falls to
    nothing (:data:`SLOW_RAMP`)."""
    wm = np.where(idle[None], 0.0, w)
    moving = np.add.reduce(wm, axis=1)
    if np.logical_and.reduce(moving >= SLOW_RAMP):  # none of the slowest walk (the ramp at one; the sum below as it gives it)
        return (wm + SLOW_EPS * slowest[None]) / (moving + SLOW_EPS)[:, None]
    near = footing.smoothstep(moving / SLOW_RAMP)[:, None]  # the slowest walk when standing
    return near * (wm + SLOW_EPS * slowest[None]) / (moving + SLOW_EPS)[:, None] + (1.0 - near) * slowest[None]


def _eased(target: np.ndarray, before: np.ndarray | None, step: float, inside: np.ndarray,
           held: bool) -> tuple[np.ndarray, bool]:
    """(F, N) blend weights following ``target`` (F, N) from ``before`` (N,) (the last frame's; None: the first
    target), and whether the frame after the last is held too. A frame whose request and the one before lie
    inside the tessellation (``inside`` (F,) bool; the one before the first: not ``held``) takes its target
    while the blend kept up; any other moves straight toward its target, no weight by more than ``step``:
    where the target jumps as the request leaves, lies outside or comes back into the tessellation, the blend
    goes over in equal steps until it has caught up. Frames where it keeps up are the target's, to the bit (so
    every partition of the frames into blocks gives the same weights); the frame loop runs only while it lags."""
    if before is None or before.shape != target.shape[1:]:
        before, held = target[0], False
    free = inside & np.concatenate(([True], inside[:-1]))
    prev = np.concatenate((before[None], target[:-1]))
    jump = (np.abs(target - prev).max(axis=1) > step) & ~free
    if not held and not jump.any():
        return target, not inside[-1]
    out = target.copy()
    first = 0 if held else int(np.argmax(jump))
    x = out[first - 1] if first else before
    lagging = held
    for i in range(first, len(target)):
        if not lagging and not jump[i:].any():
            break  # caught up, and no jump ahead: the rest is the target's
        d = target[i] - x
        far = float(np.abs(d).max())
        lagging = far > step and not (free[i] and not lagging)
        x = x + d * (step / far) if lagging else out[i]
        out[i] = x
    return out, lagging or not inside[-1]


def straight_walk(space, clips) -> tuple[np.ndarray, np.ndarray]:
    """Speeds (S,) m/s from standing to the pack's top speed straight ahead, and the cadence (S,)
    (cycles per second) the steered blend walks straight ahead at each (:func:`_steered`'s weights)."""
    idle = np.array([c.role == "idle" for c in clips])
    velocities = np.array([[c.parameters[k] for k in ("forward_speed", "lateral_speed", "turn_rate")] for c in clips])
    limit = space.speed_limit()
    grid = np.linspace(0.0, max(float(limit(0.0)), 1e-3), 64)
    slowest = np.zeros(len(clips))
    slowest[_slowest_walk(clips)] = 1.0
    ahead = np.zeros(len(grid))
    w, slow, _, _ = _weights(space, idle, velocities, grid, ahead, ahead)
    durations = np.array([c.keys[2] - c.keys[0] for c in clips])
    return grid, pacing.straight_cadences(_moving(w, idle, slowest) @ durations, slow)


def _settle_phases(b: LocomotionBinding, w) -> np.ndarray:
    """(F, 2) phases past a landing of the left foot (phase 0) and of the right (0.5) at which a stop
    holds the gait: :data:`SETTLE_PHASE`, or earlier where the trailing foot's stance share would start
    to fall before it (its toe off less the stance ramp), so the stop's last frame does not move the
    trailing foot (its stance share lays the feet down). ``w`` (F, N): the moving clips' weights."""
    out = np.full((len(w), 2), SETTLE_PHASE)
    stepping = np.nonzero(b.stepping)[0]
    if not stepping.size:
        return out
    ws = w[:, stepping]
    events = ((ws / np.maximum(ws.sum(axis=1, keepdims=True), 1e-9)) @ b.events[stepping].reshape(-1, 8)).reshape(-1, 2, 4)
    # Toe off of the trailing foot after each landing: the right foot's after the left strike (0), the left's after 0.5.
    trailing = np.stack((np.mod(events[:, 1, 3], 1.0), np.mod(events[:, 0, 3] - 0.5, 1.0)), axis=1)
    return np.clip(np.minimum(out, trailing - STANCE_RAMP - SETTLE_MARGIN), 0.0, SETTLE_PHASE)


def _settle_frames(dt: float) -> float:
    """How many frames of ``dt`` seconds the idle takes to fade in (:data:`SETTLE_S`), not rounded."""
    return SETTLE_S / dt


def _clock(st: LocomotionState, slow, stopping, spinning, period, dt, idle: bool, settle_at, pace=None) -> tuple[np.ndarray, ...]:
    """The blend's phase (F,) in [0, 1), each frame's step of it to the next frame (F,) (from that
    frame's own cadence: the same whichever frames are evaluated with it), stride factor (F,), idle
    share (F,) and how far it has come to rest (F,) (the idle share's easing, with an idle or not) for moving shares
    ``slow`` (F,) of the slowest walk, the steering's ``stopping`` (F,) flags, ``spinning`` (F,)
    flags (the root turns on the spot) and cycle durations ``period`` (F,) seconds; updates ``st``.

    Walking, cadence and stride are both the slowest walk's times the square root of ``slow``, the
    cadence further times the pacing's factor and the stride over it (:mod:`.pacing`, the speed kept;
    ``pace``: None, or a :class:`~.pacing.StopPacing`, and each frame's speed (0 where not on the way
    to the path's last point), distance to that point, its bearing and the speed asked (F,) each), each frame's from
    the phase it is at.
    Stopping (below :data:`STAND_FRACTION`, or braking for the end of a path), the cadence does not
    fall below :data:`STOP_CADENCE` (reached at :data:`CADENCE_RAMP` per second) and the strides,
    ``slow`` over the cadence, shrink to nothing, until each foot has landed once more (without an
    idle twice, :data:`STOP_LANDINGS`) with the pelvis over the point it stops at (below
    :data:`STILL_FRACTION`): both then stand under the body; the phase holds in the double support
    after that landing, ``settle_at(i)`` (2,) past a left (phase 0) or right (0.5) landing at frame i
    (see :func:`_settle_phases`; asked only where a stop holds), and the idle fades in over :data:`SETTLE_S`. Turning on the spot, it
    steps the same way and settles again once the turn is over."""
    f = len(slow)
    stop = (slow < STAND_FRACTION) | stopping
    rate = np.sqrt(slow)
    stride = rate.copy()
    advance = np.zeros(f)
    settled = np.zeros(f, dtype=bool)
    bounds = _runs(stop, spinning)
    done = st.phase  # the (unwrapped) phase at the start of each run
    for a, e in zip(bounds[:-1], bounds[1:]):
        if not stop[a]:
            if pace is not None and pace[1][a:e].any():
                factor = pace[0].factors(pace[1][a:e], pace[2][a:e], pace[3][a:e], done, dt * rate[a:e] / period[a:e], pace[4][a:e])
                rate[a:e] *= factor
                stride[a:e] /= factor
            advance[a:e] = dt * rate[a:e] / period[a:e]
            st.settled, st.landings, st.to_go = False, -1, -1.0
        elif st.settled and not spinning[a]:
            rate[a:e] = 0.0
            stride[a:e] = slow[a:e] / STOP_CADENCE
            settled[a:e] = True
        else:
            if st.landings < 0:  # the stop (or the turn on the spot) begins
                st.landings, st.floor, st.stop_age = 0, float(rate[a]) if not st.settled else 0.0, 0.0
            if spinning[a]:
                st.settled, st.landings, st.to_go = False, 0, -1.0
            age = st.stop_age + dt * np.arange(e - a)
            r = np.maximum(rate[a:e], np.minimum(STOP_CADENCE, st.floor + CADENCE_RAMP * age))
            step = dt * r / period[a:e]
            ph = done + np.cumsum(step)  # after each frame's step
            before = ph - step
            goal = done + st.to_go if st.to_go >= 0.0 else None
            if goal is None and not spinning[a]:
                # Strikes (phases 0 and 0.5) with the character nearly still: the foot lands by the body.
                # Only landings with the body at the point it stands at count (a foot landing while the
                # pelvis still comes over it would be left out of the stance, short of or past its place).
                landed = (np.floor(2.0 * ph) > np.floor(2.0 * before)) & (slow[a:e] < STILL_FRACTION)
                count = st.landings + np.cumsum(landed)
                ready = landed & (count >= (2 if idle else STOP_LANDINGS))
                if ready.any():
                    j = int(np.argmax(ready))
                    strike = np.floor(2.0 * ph[j]) / 2.0  # the landing's phase: a left (whole) or right (half) strike
                    goal = strike + settle_at(a + j)[int(round(2.0 * strike)) % 2]
                st.landings = int(count[-1])
            stride[a:e] = slow[a:e] / np.maximum(r, 1e-9)  # no cadence yet (a stop from standing): no stride
            if goal is not None:
                over = ph >= goal
                if over.any():
                    j = int(np.argmax(over))
                    step[j] = goal - before[j]
                    step[j + 1:] = 0.0
                    r[j + 1:] = 0.0
                    settled[a + j + 1:e] = True
                    st.settled, st.to_go = True, -1.0
                else:
                    st.to_go = float(goal - ph[-1])
            st.stop_age = float(age[-1] + dt)
            rate[a:e] = r
            advance[a:e] = step
        done += float(advance[a:e].sum())
    phase = _before(st.phase, advance)
    st.phase = float((phase[-1] + advance[-1]) % 1.0)
    # The idle's share follows the settled flag at 1 / SETTLE_S per second, counted in whole frames
    # from 0 or from the fade's length (exact in floating point), so that every partition of the
    # frames into blocks gives the same shares to the bit: a share of exactly one half decides
    # whether a foot holds (:func:`~infuse.footing.anchors`).
    full = _settle_frames(dt)
    left = np.empty(f)
    edges = _runs(settled)
    for a, e in zip(edges[:-1], edges[1:]):
        ramp = st.idle_frames_left + (-1.0 if settled[a] else 1.0) * np.arange(1, e - a + 1)
        left[a:e] = np.minimum(np.maximum(ramp, 0.0), full)
        st.idle_frames_left = float(left[e - 1])
    rest = footing.smoothstep(1.0 - left / full)
    return phase % 1.0, advance, np.where(stop, np.minimum(stride, 1.0), stride), rest if idle else np.zeros(f), rest


def _clocks(states: list, slow, stopping, spinning, period, dt, idle: bool, settle_at, paces: list,
            counts: list) -> tuple[np.ndarray, ...]:
    """:func:`_clock` for walks' frames stacked (R,) (``counts`` (W,) frames each, their ``states`` and
    ``paces``), ``settle_at(r)`` asked of a stacked row ``r``: the walks whose frames are each one run of
    the clock (walking, or in one stop or turn on the spot throughout: a block of one frame always) and
    not paced, all at once (:func:`_clocks_together`), any other on its own."""
    f, n = counts[0], len(counts)
    if counts.count(f) < n:
        ends = list(itertools.accumulate(counts))
        return tuple(np.concatenate(c) for c in zip(*(
            _clock(st, slow[e - c:e], stopping[e - c:e], spinning[e - c:e], period[e - c:e], dt, idle,
                   lambda i, a=e - c: settle_at(a + i), pace) for st, pace, c, e in zip(states, paces, counts, ends))))
    stop = ((slow < STAND_FRACTION) | stopping).reshape(n, f)
    spin = spinning.reshape(n, f)
    together = ~stop.any(axis=1) | ((stop == stop[:, :1]) & (spin == spin[:, :1])).all(axis=1)
    for k, pace in enumerate(paces):
        if pace is not None and pace[1].any():
            together[k] = False
    if together.all():
        return tuple(x.reshape(-1) for x in _clocks_together(states, slow.reshape(n, f), stop, spin, period.reshape(n, f), dt,
                                                             idle, settle_at, 0))
    out = np.empty((5, n, f))
    for k in np.flatnonzero(~together).tolist():
        a = k * f
        out[:, k] = _clock(states[k], slow[a:a + f], stopping[a:a + f], spinning[a:a + f], period[a:a + f], dt, idle,
                           lambda i, a=a: settle_at(a + i), paces[k])
    for k in np.flatnonzero(together).tolist():  # walk by walk: their rows would be gathered and scattered again
        out[:, k] = np.array(_clocks_together([states[k]], slow[None, k * f:k * f + f], stop[k:k + 1], spin[k:k + 1],
                                              period[None, k * f:k * f + f], dt, idle, settle_at, k * f))[:, 0]
    return tuple(out.reshape(5, -1))


def _clocks_together(states: list, slow, stop, spin, period, dt, idle: bool, settle_at, first: int) -> tuple[np.ndarray, ...]:
    """:func:`_clock` for walks (W,) of F frames each, their arrays (W, F) (``slow``, the ``stop`` flags (the
    slowest walk's share below :data:`STAND_FRACTION`, or the steering stopping), ``spin`` flags and
    ``period``), each walk's frames one run of the clock (walking, or in one stop or turn on the spot
    throughout), none paced; ``settle_at(first + k * F + i)`` asked for walk k's frame i. Updates the
    ``states``; returns (W, F) arrays as :func:`_clock` does, the same to the bit."""
    w, f = slow.shape
    phase0 = np.array([st.phase for st in states])
    rate = np.sqrt(slow)
    stride = rate.copy()
    advance = dt * rate / period  # walking: the cadence's (the other walks' rows are set below)
    settled = np.zeros((w, f), dtype=bool)
    stopped, spinning = stop[:, 0].tolist(), spin[:, 0].tolist()
    stepping, resting = [], []
    for k, st in enumerate(states):
        if not stopped[k]:
            st.settled, st.landings, st.to_go = False, -1, -1.0
        elif st.settled and not spinning[k]:  # standing after its stop: the phase holds
            resting.append(k)
        else:
            stepping.append(k)
            if st.landings < 0:  # the stop (or the turn on the spot) begins
                st.landings, st.floor, st.stop_age = 0, float(rate[k, 0]) if not st.settled else 0.0, 0.0
            if spinning[k]:
                st.settled, st.landings, st.to_go = False, 0, -1.0
    if resting:
        still = np.array(resting)
        rate[still] = 0.0
        stride[still] = slow[still] / STOP_CADENCE
        advance[still] = 0.0
        settled[still] = True
    if stepping:
        # The steps of a stop or a turn on the spot (see :func:`_clock`), the stepping walks' rows at once.
        on = slice(None) if len(stepping) == w else np.array(stepping)  # every walk (a view), or those
        walks = [states[k] for k in stepping]
        age = np.array([st.stop_age for st in walks])[:, None] + dt * np.arange(f)
        r = np.maximum(rate[on], np.minimum(STOP_CADENCE, np.array([st.floor for st in walks])[:, None] + CADENCE_RAMP * age))
        step = dt * r / period[on]
        # After each frame's step, and the landings up to it (a sum over one frame is that frame's).
        ph = phase0[on][:, None] + (step if f == 1 else np.cumsum(step, axis=1))
        before = ph - step
        landed = (np.floor(2.0 * ph) > np.floor(2.0 * before)) & (slow[on] < STILL_FRACTION)
        count = np.array([st.landings for st in walks])[:, None] + (landed if f == 1 else np.cumsum(landed, axis=1))
        ready = (landed & (count >= (2 if idle else STOP_LANDINGS))).any(axis=1).tolist()
        goals = []
        for m, (k, st) in enumerate(zip(stepping, walks)):
            goal = phase0[k] + st.to_go if st.to_go >= 0.0 else None
            if goal is None and not spinning[k]:
                if ready[m]:
                    j = int(np.argmax(landed[m] & (count[m] >= (2 if idle else STOP_LANDINGS))))
                    strike = np.floor(2.0 * ph[m, j]) / 2.0  # the landing's phase: a left (whole) or right (half) strike
                    goal = strike + settle_at(first + k * f + j)[int(round(2.0 * strike)) % 2]
                st.landings = int(count[m, -1])
            goals.append(goal)
        stride[on] = slow[on] / np.maximum(r, 1e-9)  # no cadence yet (a stop from standing): no stride
        for m, (k, st, goal) in enumerate(zip(stepping, walks, goals)):
            if goal is not None:
                over = ph[m] >= goal
                if over.any():
                    j = int(np.argmax(over))
                    step[m, j] = goal - before[m, j]
                    step[m, j + 1:] = 0.0
                    r[m, j + 1:] = 0.0
                    settled[k, j + 1:] = True
                    st.settled, st.to_go = True, -1.0
                else:
                    st.to_go = float(goal - ph[m, -1])
        for st, aged in zip(walks, (age[:, -1] + dt).tolist()):
            st.stop_age = aged
        rate[on] = r
        advance[on] = step
    phase = _before_each(phase0, advance.reshape(-1), [f] * w).reshape(w, f)
    for st, at in zip(states, ((phase[:, -1] + advance[:, -1]) % 1.0).tolist()):
        st.phase = at
    # The idle's share (see :func:`_clock`), counted in whole frames.
    full = _settle_frames(dt)
    if f == 1 or (settled == settled[:, :1]).all():
        ramp = np.array([st.idle_frames_left for st in states])[:, None] + \
            np.where(settled[:, :1], -1.0, 1.0) * np.arange(1, f + 1)
        left = np.minimum(np.maximum(ramp, 0.0), full)
        for st, frames_left in zip(states, left[:, -1].tolist()):
            st.idle_frames_left = frames_left
    else:
        left = np.empty((w, f))
        for k, st in enumerate(states):
            edges = _runs(settled[k])
            for a, e in zip(edges[:-1], edges[1:]):
                ramp = st.idle_frames_left + (-1.0 if settled[k, a] else 1.0) * np.arange(1, e - a + 1)
                left[k, a:e] = np.minimum(np.maximum(ramp, 0.0), full)
                st.idle_frames_left = float(left[k, e - 1])
    rest = footing.smoothstep(1.0 - left / full)
    return phase % 1.0, advance, np.where(stop, np.minimum(stride, 1.0), stride), rest if idle else np.zeros((w, f)), rest


def _before(start: float, steps: np.ndarray) -> np.ndarray:
    """(F,) ``start`` plus the ``steps`` (F,) taken before each frame (none before the first)."""
    out = np.empty(len(steps))
    out[0] = 0.0
    if len(steps) > 1:
        np.cumsum(steps[:-1], out=out[1:])
    out += start
    return out


def _runs(*flags: np.ndarray) -> list[int]:
    """Where the runs of frames alike in every one of ``flags`` (F,) each begin, then F: ``[0, ..., F]``."""
    if len(flags[0]) == 1:  # a block of one frame: one run
        return [0, 1]
    change = flags[0][1:] != flags[0][:-1]
    for other in flags[1:]:
        change = change | (other[1:] != other[:-1])
    return [0, *(np.flatnonzero(change) + 1).tolist(), len(flags[0])]


def mean_rotations(motion) -> np.ndarray:
    """A cycle's mean local rotations (J, 4) (its closing frame left out), each joint's frames turned to its first's side."""
    rot = continuous_rotations(motion)[:max(motion.num_frames - 1, 1)]
    sides = ((rot * rot[:1]).reshape(-1, 4) @ _ONES4).reshape(rot.shape[:2])  # (F, J) dot products with the first frame
    return quat.normalize(np.where((sides < 0.0)[..., None], -rot, rot).mean(axis=0))


#: Running sums of weighted poses (:func:`_accumulate`): rotations (4, F, J), root (3, F), joint translations (3, F, J) or None.
Sums = tuple[np.ndarray, np.ndarray, np.ndarray | None]


def _accumulate(acc: Sums | None, rot: np.ndarray, root: np.ndarray, jt: np.ndarray | None, weight: np.ndarray) -> Sums:
    """Add a pose (component-major: rotations (4, F, J), root (3, F), joint translations (3, F, J) or
    None) weighted by ``weight`` (F,) to the running sums ``acc`` (None to start), each rotation
    turned to the sum's side."""
    wj = weight[:, None]
    if acc is None:
        return rot * wj, root * weight, None if jt is None else jt * wj
    r0, p0, j0 = acc
    r0 += rot * (np.where((r0 * rot).sum(axis=0) < 0.0, -1.0, 1.0) * wj)
    p0 = p0 + root * weight
    if jt is not None and j0 is not None:
        j0 = j0 + jt * wj
    return r0, p0, j0


def _scatter(before: np.ndarray, active: np.ndarray, values: np.ndarray, frames: int) -> np.ndarray:
    """(F, ...) arrays: ``values`` on the ``active`` frames, ``before`` (F or 1, ...) on the others."""
    out = np.array(np.broadcast_to(before, (frames,) + values.shape[1:]))
    out[active] = values
    return out


def _slow_fall(x: np.ndarray, before: np.ndarray, step: float | np.ndarray) -> np.ndarray:
    """([R,] F, K) ``x`` ([R,] F, K) falling by at most ``step`` a frame (a number, or each frame's ([R,] F, 1)),
    from ``before`` ([R,] K) a frame before the first; rising as ``x`` does. Each frame's value is the
    largest of ``x`` at it and of every earlier value less the steps since (R: runs of frames side by side)."""
    if np.ndim(step):
        fallen = np.cumsum(np.broadcast_to(step, x.shape), axis=-2)  # the steps down to each frame from before the first
        out: np.ndarray = np.maximum(np.maximum.accumulate(x + fallen, axis=-2) - fallen, before[..., None, :] - fallen)
        return out
    if x.shape[-2] == 1:  # one frame: the same, without the running maximum of one value
        return np.maximum(x, before[..., None, :] - step)
    k = np.arange(x.shape[-2])[:, None]
    return np.maximum(np.maximum.accumulate(x + step * k, axis=-2) - step * k, before[..., None, :] - step * (k + 1))

