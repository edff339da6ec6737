"""The ``reach`` controller: reach examples blended by target position, then IK to the exact target.

The target (a point, a runtime target or a scene object's name) is expressed in the body frame the
character has when the reach starts (origin on the ground under the pelvis, +Z its facing, +X its
left). Its barycentric weights in the hand's tessellation blend the examples, each time-warped so
their strokes coincide; the blend drives the spine, the arm and the hand. The wrist is then carried
to the exact target by two-joint arm IK, the correction growing from the start to the stroke.
``action``: ``"touch"`` (reach and return), ``"grab"`` (from the stroke the object named ``obj``
follows the hand: the runtime target of that name becomes a :class:`HeldTarget`, until
:meth:`Reach.release`), ``"put"`` (the held object ``obj`` is left at the target at the stroke: the
hand takes it there, wherever in the hand it is held).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Controller, Layer, Mode, sample_motion
from infuse.runtime.layers import smoothstep
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk
from infuse.runtime.targets import PointTarget, Target, as_target

ACTIONS = ("touch", "grab", "put")
#: Furthest an object may be from the wrist for the hand putting it down to be holding it, metres.
HELD_WITHIN_M = 0.15
_UPPER = ("spine1", "spine2", "spine3", "spine4", "spine5", "skullbase")


def _mean_stroke(pack) -> float:
    """Mean stroke time (seconds) of a reaching pack's reach examples."""
    from infuse.packs import BlendSpace, load_pack

    if isinstance(pack, BlendSpace):
        strokes = [c.stroke for c in pack.clips.values() if c.role == "reach"]
    else:
        strokes = [c["stroke"] for c in load_pack(pack).require_built()["clips"] if c["role"] == "reach"]
    if not strokes:
        raise UsageError("the reaching pack has no reach examples")
    return float(np.mean(strokes))


class HeldTarget(Target):
    """A scene object held in a character's hand: its world position follows the wrist, at the offset
    (in the wrist's frame) it had when grabbed; from ``release_s`` (global seconds, once set) it stays
    where the hand let it go."""

    def __init__(self, character: str, wrist: int, offset: np.ndarray, fallback: np.ndarray,
                 release_s: float | None = None):
        self.character, self.wrist = character, wrist
        self.offset = np.asarray(offset, dtype=np.float64)
        self.last = np.asarray(fallback, dtype=np.float64)
        self.release_s = release_s
        self.left_at: np.ndarray | None = None  # (3,) where it was let go, once that frame is evaluated
        self.left_s: float | None = None  # the time of that frame

    def positions(self, times, block=None) -> np.ndarray:
        times = np.asarray(times, dtype=np.float64)
        gone = np.zeros(len(times), dtype=bool) if self.release_s is None else times >= self.release_s - 1e-9
        if block is not None and len(times) == len(block) and self.character in block.poses:
            rot, pos = block.pose(self.character).chain_pose([self.wrist])
            out = pos[:, 0] + quat.rotate(rot[:, 0], self.offset)
            first = int(np.argmax(gone))
            if gone.any() and (self.left_at is None or times[first] == self.left_s):  # the frame it is let go
                self.left_at, self.left_s = out[first], float(times[first])  # (again once the pose is final)
            if self.left_at is not None:
                out[gone] = self.left_at
            self.last = out[-1]
            return out
        out = np.broadcast_to(self.last, (len(times), 3)).copy()
        if self.left_at is not None:
            out[gone] = self.left_at
        return out


@dataclass(frozen=True, eq=False)
class ReachBinding:
    """A reach bound to one character: the reaching pack's ``space`` (a :class:`~infuse.packs.BlendSpace`
    infused on it), the ``arms`` (shoulder, elbow, wrist) by hand of the hands both the pack and the
    character have, and the ``stroke`` time (seconds from the start)."""

    space: Any
    arms: dict[str, tuple[int, int, int]]
    stroke: float


@dataclass(frozen=True, eq=False)
class ReachFrame:
    """The character's body frame when a reach starts, in its own frame: the pelvis ``base`` (3,) metres,
    the ``heading`` of the hips (radians about +Y) and the height of the ``ground`` under the feet, metres."""

    base: np.ndarray
    heading: float
    ground: float


@dataclass
class ReachState:
    """What a reach activity keeps between blocks: its body ``frame`` and ``hand`` (from its first frame),
    whether its target was ``outside`` the hand's examples (reported once), where the object was when the
    hand ``taken_at`` it (world, (3,) metres), the object's offset ``carry`` (3,) from the wrist while it is
    put down, and whether the grab or put is ``done``."""

    frame: ReachFrame | None = None
    hand: str | None = None
    outside: bool = False
    taken_at: np.ndarray | None = None
    carry: np.ndarray | None = None
    done: bool = False


class Reach(Controller):
    """Reach ``target`` with ``hand`` ("left", "right" or "auto": the side the target is on).

    ``pack``: a reaching pack (name, folder or BlendSpace); ``action``/``obj``: see the module doc;
    ``hold_s``: seconds held at the stroke before the activity ends (and blends out); ``stroke_s``: when
    the wrist arrives, seconds from the start (default: the pack's, the mean of its reach examples').
    """

    kind = "reach"
    layer = Layer.POSTURE
    mode = Mode.OVERRIDE
    blend_in_s = 0.2
    blend_out_s = 0.6

    def __init__(self, target, hand: str = "auto", pack="reaching", action: str = "touch", obj: str | None = None,
                 hold_s: float = 0.4, stroke_s: float | None = None):
        if hand not in ("auto", "left", "right"):
            raise UsageError(f"hand must be left, right or auto, got {hand!r}")
        if action not in ACTIONS:
            raise UsageError(f"action must be one of {', '.join(ACTIONS)}, got {action!r}")
        if action in ("grab", "put") and not obj:
            raise UsageError(f"a {action} names the object (obj=)")
        self.target, self.hand, self.pack, self.action, self.obj = target, hand, pack, action, obj
        self.hold_s = float(hold_s)
        self.release_s: float | None = None
        self.held: HeldTarget | None = None  # the object's target once taken
        if stroke_s is not None and not (np.isfinite(stroke_s) and stroke_s > 0):
            raise UsageError(f"a reach's stroke must be a positive number of seconds, got {stroke_s}")
        # Stroke times are the pack's (retargeting keeps timing), so the natural length is known now.
        self.stroke_s = _mean_stroke(pack) if stroke_s is None else float(stroke_s)
        self.duration_s = self.stroke_s + self.hold_s + self.blend_out_s  # the weight falls to 0 at the end

    def describe(self) -> str:
        return f"reach ({self.action})"

    def release(self, at_s: float) -> None:
        """Let go at ``at_s`` (global seconds) of the object a ``"grab"`` takes: it stays where the hand is then."""
        self.release_s = float(at_s)
        if self.held is not None:
            self.held.release_s = self.release_s

    def bind(self, rig, report) -> ReachBinding:
        from infuse.packs import space_on  # packs load lazily: importing a plugin stays cheap

        space = space_on(rig, self.pack)
        if space.kind != "reach":
            raise UsageError(f"pack {space.pack!r} is not a reaching pack")
        hands: dict[str, tuple[int, int, int]] = {}
        for hand in ("left", "right"):
            shoulder, elbow, wrist = (rig.joint(f"{hand[0]}_{n}") for n in ("shoulder", "elbow", "wrist"))
            if hand in space.tessellations and shoulder is not None and elbow is not None and wrist is not None:
                hands[hand] = (shoulder, elbow, wrist)
        if not hands:
            raise UsageError("the character has no mapped shoulder, elbow and wrist for the pack's hands")
        return ReachBinding(space=space, arms=hands, stroke=self.stroke_s)

    def _target_world(self, runtime, times, block) -> np.ndarray:
        t = runtime.target(self.target) if isinstance(self.target, str) else as_target(self.target)
        return t.positions(times, block)

    def evaluate_one(self, job, block) -> None:
        b: ReachBinding = job.binding
        st, rig = job.state_of(ReachState), job.rig
        active = np.nonzero((job.local_times >= -1e-9) & (job.weight > 0))[0]
        if not active.size:
            return
        runtime = job.activity.runtime
        world = self._target_world(runtime, block.times, block)
        if st.taken_at is not None:  # the object is in the hand now: the goal stays where the hand took it
            world = np.broadcast_to(st.taken_at, world.shape).copy()
        own = quat.rotate(quat.conjugate(rig.rotation), world - rig.position)
        pose = job.pose
        sk = rig.skeleton
        if st.frame is None:  # the body frame when the reach starts
            g_rot, g_pos = chain_fk(sk, pose.local_rotations[active[:1]], pose.root_translations[active[:1]],
                                    None if pose.joint_translations is None else pose.joint_translations[active[:1]],
                                    [rig.joint("base"), rig.joint("l_hip"), rig.joint("r_hip")])
            left = g_pos[0, 1] - g_pos[0, 2]
            heading = float(np.arctan2(-left[2], left[0]))
            st.frame = ReachFrame(g_pos[0, 0], heading, self._ground(rig, pose, active[0]))
        frame = st.frame
        rel = own[active[0]] - np.array([frame.base[0], frame.ground, frame.base[2]])
        c, s = np.cos(frame.heading), np.sin(frame.heading)
        point = np.array([c * rel[0] - s * rel[2], rel[1], s * rel[0] + c * rel[2]])
        hand = self.hand if self.hand != "auto" else ("left" if point[0] >= 0 else "right")
        if hand not in b.arms:
            hand = next(iter(b.arms))
        if st.hand is None:
            st.hand = hand
        hand = st.hand
        weights, inside = b.space.weights(hand, point[None])
        if not inside[0] and not st.outside:
            st.outside = True
            job.report(f"reach target {np.round(point, 2).tolist()} is outside the {hand} hand's examples; the nearest blend and IK are used")
        clips = b.space.group(hand)
        stroke = b.stroke
        t = job.local_times[active]
        side = hand[0]
        canonical = rig.mapping.inverse()
        moved = [rig.joint(n) for n in _UPPER] + [j for j, name in enumerate(sk.names)
                                                 if canonical.get(name, "").startswith(f"{side}_")
                                                 and canonical[name].split("_", 1)[1] not in
                                                 ("hip", "knee", "ankle", "forefoot", "toe")]
        joints = np.array([j for j in moved if j is not None and j > 0], dtype=np.int64)
        blend = np.zeros((len(t), len(joints), 4))
        for i in np.nonzero(weights[0] > 1e-6)[0]:
            clip = clips[i]
            local = np.clip(t * clip.stroke / stroke, 0.0, clip.duration)
            r, _, _, _ = sample_motion(clip.motion, local, loop=False)
            r = r[:, joints] * weights[0, i]
            blend += np.where(np.sum(blend * r, axis=-1, keepdims=True) < 0, -r, r)  # on the side of the blend so far
        full = np.array(pose.local_rotations[:, joints])
        full[active] = quat.normalize(blend)
        weight = np.zeros(len(job.weight))
        weight[active] = job.weight[active]
        pose.set_rotations(joints, full, weight, job.mode)
        arm = b.arms[hand]
        rot = pose.local_rotations[active]
        jt = None if pose.joint_translations is None else pose.joint_translations[active]
        wrot, wpos = chain_fk(sk, rot, pose.root_translations[active], jt, [arm[2]])
        goal_pt = own[active]
        if self.action == "put":  # the object, held off the wrist, goes to the target (IK keeps the wrist's turn)
            goal_pt = goal_pt - self._carried(runtime, block, rig.name, active, arm[2], wrot[:, 0], st,
                                              t >= stroke - 1e-9)
        ramp = smoothstep(t / max(stroke, 1e-6))[:, None]
        goal = wpos[:, 0] + ramp * (goal_pt - wpos[:, 0])
        solve_limb(sk, rot, pose.root_translations[active], jt, arm, goal, weight=job.weight[active])
        pose.local_rotations[active] = rot
        pose._fk = None
        self._act(job, st, block, t, active, arm, world)

    def _carried(self, runtime, block, character, active, wrist, wrist_rotations, st: ReachState, put) -> np.ndarray:
        """(A, 3) where the object being put down is from the wrist on the active frames (metres, the
        character's own frame; ``wrist_rotations`` (A, 4) the wrist's global turn there): where the hand
        holds it before the stroke (``put`` false), as it was just before from the stroke on; nothing
        where it is not in the hand (further than :data:`HELD_WITHIN_M`)."""
        carry = np.zeros((len(active), 3))
        before = ~put
        if before.any():
            held = runtime.target(self.obj).positions(block.times, block)[active[before]]
            hand_rot, hand_pos = block.pose(character).chain_pose([wrist])  # the pose below, world
            in_hand = quat.rotate(quat.conjugate(hand_rot[active[before], 0]), held - hand_pos[active[before], 0])
            in_hand[np.linalg.norm(in_hand, axis=-1) > HELD_WITHIN_M] = 0.0
            carry[before] = quat.rotate(wrist_rotations[before], in_hand)
            st.carry = carry[before][-1]
        carry[put] = np.zeros(3) if st.carry is None else st.carry
        return carry

    @staticmethod
    def _ground(rig, pose, frame: int) -> float:
        """Height of the lowest foot joint in the pose below (the ground the examples were measured on)."""
        feet = [j for j in (rig.joint(n) for n in ("l_ankle", "r_ankle", "l_forefoot", "r_forefoot", "l_toe", "r_toe")) if j is not None]
        if not feet:
            return 0.0
        jt = None if pose.joint_translations is None else pose.joint_translations[frame:frame + 1]
        _, pos = chain_fk(rig.skeleton, pose.local_rotations[frame:frame + 1], pose.root_translations[frame:frame + 1], jt, feet)
        return float(pos[0, :, 1].min())

    def _act(self, job, st: ReachState, block, t, active, arm, world) -> None:
        """Grab or put down the object once the stroke is reached."""
        if self.action == "touch" or st.done:
            return
        reached = np.nonzero(t >= job.binding.stroke - 1e-9)[0]
        if not reached.size:
            return
        runtime = job.activity.runtime
        f = active[reached[0]]
        if self.action == "grab":
            rot, pos = job.pose.chain_pose([arm[2]])
            obj = runtime.target(self.obj).positions(block.times[f:f + 1], None)[0]
            offset = quat.rotate(quat.conjugate(rot[f, 0]), obj - pos[f, 0])
            st.taken_at = np.array(world[f])
            self.held = HeldTarget(job.rig.name, arm[2], offset, obj, self.release_s)
            runtime.add_target(self.obj, self.held)
        else:
            x, y, z = (float(v) for v in world[f])
            runtime.add_target(self.obj, PointTarget((x, y, z)))
        st.done = True
