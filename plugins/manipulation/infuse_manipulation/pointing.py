"""The ``pointing`` controller: a hand points at a target, the body turning when the target is behind.

Aim: the ray from the pointing arm's shoulder joint (the head of the upper arm) through the index
fingertip passes through the target. The fingertip is put on that ray by two-joint arm IK, the hand
turned so that the wrist-to-fingertip line lies along the ray with the palm down, the index finger
straight and the other fingers curled (:mod:`.hands`; a rig without fingers points its wrist).

Reach: how far along the ray follows from how far the target is, as people point. At the stroke the
elbow opens to 168° for a target 1.5 arm lengths (shoulder to fingertip) or more away, the arm nearly
straight, and to 140° for one within an arm's length, interpolated between; at ready it is 20° more
bent. A target within reach keeps the fingertip 8 cm short of it. The arm is then turned about the
shoulder-wrist line so that the elbow hangs below it and a little to the arm's own side.

Phases (seconds from the activity's start): the arm rises from the pose below until ``ready``
(the blend-in), reaches out furthest at ``stroke``, holds until ``relax`` and returns by the end (the
blend-out). Targets move with the frames they are sampled at.

Body turn: a target more than 100° to the pointing hand's side, or more than 35° across the body (its
azimuth about the chest, measured from the pelvis's forward), is brought within that range by turning
the spine (70 % of the turn, shared by its joints) and the pelvis (30 %, the feet held where they were
by leg IK), 80° at most in all.

It runs on the gaze layer, after the gazes, so that a gaze turning the chest does not move the ray off
its target.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.layers import smoothstep
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk
from infuse.runtime.swing import local_offsets, swing

from .hands import POINTING_SHAPE, Hand, bind_hand, reference_locals, reference_tip, set_shape
from .targets import own_positions, resolve_target

HANDS = ("auto", "left", "right", "both")
#: Comfortable azimuths of a pointing arm about the chest, radians (positive: to the character's left),
#: for the right hand; the left hand's are mirrored.
RIGHT_RANGE = (np.radians(-100.0), np.radians(35.0))
#: Most the body turns, radians, and the pelvis's share of the turn.
MAX_TURN = np.radians(80.0)
PELVIS_SHARE = 0.3
#: Elbow angle (between upper arm and forearm: 180° straight), radians, at the stroke for a target at or
#: beyond FAR arm lengths from the shoulder, and for one at or within NEAR; in between, interpolated.
ELBOW_FAR, ELBOW_NEAR = np.radians(168.0), np.radians(140.0)
FAR, NEAR = 1.5, 1.0
#: How much more the elbow is bent at ready than at the stroke, radians.
ELBOW_READY_BEND = np.radians(20.0)
#: Where the elbow goes about the shoulder-wrist line: down, and this much toward the arm's own side.
ELBOW_OUTWARD = 0.5
#: How far short of a near target the fingertip stops, metres.
CLEARANCE_M = 0.08
_SPINE = ("spine1", "spine2", "spine3")


@dataclass(frozen=True, eq=False)
class PointingArm:
    """What aiming one arm needs, from the reference pose (the character's own frame, metres): its
    ``chain`` (shoulder, elbow, wrist), its ``hand``, the lengths of its ``segments`` (upper arm, forearm,
    wrist to fingertip; metres) and their sum ``length``;
    the pointing direction, the palm normal and their cross product as the columns of ``frame`` (3, 3);
    the wrist's global rotation ``wrist_reference`` (4,), the fingertip in the wrist's frame ``tip_local``
    (3,), and the character's ``body`` frame (4,)."""

    chain: tuple[int, int, int]
    hand: Hand
    segments: tuple[float, float, float]
    length: float
    frame: np.ndarray
    wrist_reference: np.ndarray
    tip_local: np.ndarray
    body: np.ndarray


@dataclass(frozen=True, eq=False)
class PointingBinding:
    """Pointing bound to one character: its ``arms`` by side (those with a mapped shoulder, elbow and wrist);
    the ``spine`` joints (K,) that turn the body and their ``spine_aligned`` frames (K, 4); the pelvis
    ``base`` and its ``base_aligned`` frame (4,) (None without one); the ``legs`` (hip, knee, ankle) that
    keep the feet down as the pelvis turns; the ``hips`` (left, right; None where unmapped); and the
    ``chest`` joint the target's azimuth is measured about (the top spine joint, else the pelvis)."""

    arms: dict[str, PointingArm]
    spine: np.ndarray
    spine_aligned: np.ndarray
    base: int | None
    base_aligned: np.ndarray | None
    legs: list[tuple[int, int, int]]
    hips: tuple[int | None, int | None]
    chest: int | None


@dataclass
class PointingState:
    """What a pointing activity keeps between blocks: the ``hands`` that point, chosen on its first frame."""

    hands: tuple[str, ...] | None = None


class Pointing(Controller):
    """Point at ``target`` (a point, ``"character:joint"``, a runtime target's name, or a
    :class:`~infuse.runtime.targets.Target`) with ``hand`` (``"left"``, ``"right"``, ``"both"`` or
    ``"auto"``: the hand on the target's side).

    ``ready_s``, ``stroke_s``, ``relax_s``: phase times in seconds from the start (see the module doc);
    ``duration_s``: the whole movement; ``extension``: scales the arm's reach (1: as in the module doc);
    ``turn``: whether the body may turn.
    """

    kind = "pointing"
    layer = Layer.GAZE
    mode = Mode.OVERRIDE
    priority = 100

    def __init__(self, target, hand: str = "auto", ready_s: float = 0.6, stroke_s: float | None = None,
                 relax_s: float | None = None, duration_s: float = 2.6, extension: float = 1.0, turn: bool = True):
        if hand not in HANDS:
            raise UsageError(f"pointing hand must be one of {', '.join(HANDS)}, got {hand!r}")
        times = [float(v) for v in (ready_s, stroke_s if stroke_s is not None else ready_s,
                                    relax_s if relax_s is not None else duration_s - 0.6, duration_s)]
        if not all(np.isfinite(times)) or times[0] < 0 or np.any(np.diff(times) < -1e-9):
            raise UsageError(f"pointing phases must satisfy 0 <= ready <= stroke <= relax <= end, got {times}")
        if not (np.isfinite(extension) and 0.3 <= extension <= 1.05):
            raise UsageError(f"pointing extension must lie in [0.3, 1.05], got {extension}")
        self.target, self.hand, self.turn = target, hand, bool(turn)
        self.ready_s, self.stroke_s, self.relax_s, self.duration_s = times
        self.blend_in_s = self.ready_s
        self.blend_out_s = self.duration_s - self.relax_s
        self.extension = float(extension)

    def describe(self) -> str:
        return f"pointing ({self.hand} hand)"

    def bind(self, rig, report) -> PointingBinding:
        arms = {}
        for side in ("left", "right"):
            s = side[0]
            chain = [rig.joint(f"{s}_{n}") for n in ("shoulder", "elbow", "wrist")]
            hand = bind_hand(rig, side)
            if None in chain or hand is None:
                continue
            if not hand.has_fingers:
                report(f"no fingers are mapped on the {side} hand: the wrist points")
            arms[side] = _arm(rig, hand, chain)
        if not arms:
            raise MissingJointsError(rig.character.asset.path, f"{rig.name}: no mapped shoulder, elbow and wrist: it cannot point")
        spine = [j for j in (rig.joint(n) for n in _SPINE) if j is not None]
        legs = [tuple(rig.joint(f"{s}_{n}") for n in ("hip", "knee", "ankle")) for s in "lr"]
        legs = [leg for leg in legs if None not in leg]
        base = rig.joint("base")
        return PointingBinding(arms=arms, spine=np.array(spine, dtype=np.int64), spine_aligned=rig.aligned[spine],
                               base=base, base_aligned=None if base is None else rig.aligned[base], legs=legs,
                               hips=(rig.joint("l_hip"), rig.joint("r_hip")), chest=spine[-1] if spine else base)

    def evaluate_one(self, job, block) -> None:
        b: PointingBinding = job.binding
        st, rig = job.state_of(PointingState), job.rig
        active = np.nonzero((job.local_times >= -1e-9) & (job.weight > 0))[0]
        if not active.size:
            return
        runtime = job.activity.runtime
        target = resolve_target(runtime, self.target)
        goal = own_positions(rig, target.positions(block.times, block))[active]  # (F, 3)
        weight = job.weight[active]
        t = job.local_times[active]
        pose = job.pose
        sk = rig.skeleton
        rot = pose.local_rotations[active].copy()
        root = pose.root_translations[active]
        jt = None if pose.joint_translations is None else pose.joint_translations[active]
        if st.hands is None:
            st.hands = self._hands(b, sk, rot[:1], root[:1], None if jt is None else jt[:1], goal[:1])
            close = self._too_close(b, sk, rot[:1], root[:1], jt, goal[:1], st.hands)
            if close:
                job.report(close)
        hands = st.hands
        changed: set[int] = set()
        if self.turn and b.chest is not None and None not in b.hips:
            changed |= self._turn(b, sk, rot, root, jt, goal, weight, hands)
        stroke = self._stroke_share(t)
        for side in hands:
            arm = b.arms[side]
            self._aim(arm, sk, rot, root, jt, goal, weight, stroke)
            changed |= set(arm.chain)
        joints = np.array(sorted(changed), dtype=np.int64)
        full = pose.local_rotations[:, joints].copy()
        full[active] = rot[:, joints]
        pose.set_rotations(joints, full)
        for side in hands:
            w = np.zeros(len(job.weight))
            w[active] = weight
            set_shape(pose, b.arms[side].hand, POINTING_SHAPE, w)

    # -- the parts ---------------------------------------------------------------------------------
    def _hands(self, b: PointingBinding, sk, rot, root, jt, goal) -> tuple[str, ...]:
        """The pointing hands: as asked, or the side of the target (the body's frame at the first frame)."""
        arms = b.arms
        if self.hand == "both":
            return tuple(s for s in ("left", "right") if s in arms)
        if self.hand in arms:
            return (self.hand,)
        if self.hand != "auto" or len(arms) == 1:
            return (next(iter(arms)),)
        l_hip, r_hip = b.hips
        if l_hip is None or r_hip is None:
            return ("right",)
        _, pos = chain_fk(sk, rot, root, jt, [l_hip, r_hip])
        left = pos[0, 0] - pos[0, 1]
        middle = 0.5 * (pos[0, 0] + pos[0, 1])
        return ("left",) if np.dot(goal[0] - middle, left) >= 0.0 else ("right",)

    def _too_close(self, b: PointingBinding, sk, rot, root, jt, goal, hands) -> str | None:
        arm = b.arms[hands[0]]
        _, pos = chain_fk(sk, rot, root, None if jt is None else jt[:1], [arm.chain[0]])
        distance = float(np.linalg.norm(goal[0] - pos[0, 0]))
        if distance < 2.0 * CLEARANCE_M:
            return f"the pointing target is {distance * 100:.0f} cm from the shoulder: too close to point at"
        return None

    def _stroke_share(self, t: np.ndarray) -> np.ndarray:
        """(F,) in [0, 1]: 0 until ready, rising to 1 at the stroke, back to 0 by relax."""
        rise = smoothstep((t - self.ready_s) / max(self.stroke_s - self.ready_s, 1e-6))
        fall = smoothstep((self.relax_s - t) / max(self.relax_s - self.stroke_s, 1e-6))
        bump = np.where(t <= self.stroke_s, rise, fall)
        return np.where(t < self.ready_s, 0.0, bump)

    def _reach(self, arm: PointingArm, distance: np.ndarray, stroke: np.ndarray) -> np.ndarray:
        """(F,) metres from the shoulder to the fingertip along the ray, for a target ``distance`` (F,)
        metres away at ``stroke`` (F,) (see :meth:`_stroke_share`): the elbow's angle follows from how far
        the target is (nearly straight for a far one), the hand lies along the ray, and a target within
        reach keeps the fingertip short of it."""
        upper, fore, hand = arm.segments
        far = np.clip((distance / arm.length - NEAR) / (FAR - NEAR), 0.0, 1.0)
        elbow = ELBOW_NEAR + (ELBOW_FAR - ELBOW_NEAR) * far - ELBOW_READY_BEND * (1.0 - stroke)
        wrist = np.sqrt(upper * upper + fore * fore - 2.0 * upper * fore * np.cos(elbow))  # law of cosines
        reach = self.extension * (wrist + hand)
        return np.minimum(reach, np.maximum(distance - CLEARANCE_M, 0.35 * arm.length))

    def _turn(self, b: PointingBinding, sk, rot, root, jt, goal, weight, hands) -> set[int]:
        """Turn the spine and pelvis (in ``rot``, in place) toward a target outside the arm's range;
        returns the joints changed."""
        l_hip, r_hip = b.hips
        _, pos = chain_fk(sk, rot, root, jt, [l_hip, r_hip, b.chest])
        left = pos[:, 0] - pos[:, 1]
        left[:, 1] = 0.0
        left /= np.maximum(np.linalg.norm(left, axis=1, keepdims=True), 1e-9)
        forward = np.cross(left, np.array([0.0, 1.0, 0.0]))
        d = goal - pos[:, 2]
        azimuth = np.arctan2(np.sum(d * left, axis=1), np.sum(d * forward, axis=1))  # (F,) positive: left
        low, high = RIGHT_RANGE
        if hands == ("left",):
            low, high = -high, -low
        elif len(hands) == 2:
            low, high = -0.5 * (high - low), 0.5 * (high - low)
        excess = azimuth - np.clip(azimuth, low, high)
        wrapped = azimuth - 2.0 * np.pi * np.sign(azimuth)  # the same direction, the other way round
        other = wrapped - np.clip(wrapped, low, high)
        excess = np.where(np.abs(other) < np.abs(excess), other, excess)
        turn = np.clip(excess, -MAX_TURN, MAX_TURN) * weight  # (F,) radians, positive: to the left
        if not np.any(np.abs(turn) > 1e-6):
            return set()
        changed: set[int] = set()
        pelvis = PELVIS_SHARE if b.base is not None and len(b.legs) == 2 else 0.0
        spine = b.spine
        if spine.size:
            each = (1.0 - pelvis) * turn / spine.size
            offsets = local_offsets(b.spine_aligned, swing(each[:, None], 0.0))
            rot[:, spine] = quat.multiply(rot[:, spine], offsets)
            changed |= set(spine.tolist())
        else:
            pelvis = 1.0
        if pelvis and b.base is not None:
            legs = np.array(b.legs, dtype=np.int64)
            feet_rot, feet_pos = chain_fk(sk, rot, root, jt, legs[:, 2])
            base = b.base
            offset = local_offsets(b.base_aligned, swing(pelvis * turn, 0.0))
            rot[:, base] = quat.multiply(rot[:, base], offset)
            if len(legs) == 2:
                solve_limb(sk, rot, root, jt, legs, feet_pos, end_rotation=feet_rot, distance=False)
                changed |= set(legs.ravel().tolist())
            changed.add(base)
        return changed

    def _aim(self, arm: PointingArm, sk, rot, root, jt, goal, weight, stroke) -> None:
        """Arm IK (in ``rot``, in place): the fingertip on the shoulder-target ray, the hand along it."""
        shoulder, elbow, wrist = arm.chain
        parent = int(sk.parents[shoulder])
        parent = parent if parent >= 0 else shoulder  # a root shoulder: no offset, the body frame's side
        g_rot, g_pos = chain_fk(sk, rot, root, jt, [shoulder, wrist, parent])
        s = g_pos[:, 0]
        outward = self._outward(arm, g_pos[:, 0] - g_pos[:, 2])
        to_goal = goal - s
        distance = np.linalg.norm(to_goal, axis=1)
        u = to_goal / np.maximum(distance, 1e-9)[:, None]
        reach = self._reach(arm, distance, stroke)
        tip = s + reach[:, None] * u
        hint = np.array([0.0, -1.0, 0.0]) - 0.3 * outward  # palm down, a little inward
        palm = hint - np.sum(hint * u, axis=1, keepdims=True) * u
        palm /= np.maximum(np.linalg.norm(palm, axis=1, keepdims=True), 1e-9)
        target_frame = np.stack((u, palm, np.cross(u, palm)), axis=2)  # (F, 3, 3) columns
        turn = quat.from_matrix(target_frame @ arm.frame.T)
        wanted = quat.multiply(turn, arm.wrist_reference)  # (F, 4) the wrist's global rotation
        wrist_goal = tip - quat.rotate(wanted, arm.tip_local)
        end = quat.slerp(g_rot[:, 1], wanted, weight)
        solve_limb(sk, rot, root, jt, (shoulder, elbow, wrist), wrist_goal, weight=weight, end_rotation=end,
                   distance=False)
        self._swivel(arm, sk, rot, root, jt, np.array([0.0, -1.0, 0.0]) + ELBOW_OUTWARD * outward, weight)

    @staticmethod
    def _outward(arm: PointingArm, from_parent: np.ndarray) -> np.ndarray:
        """(F, 3) unit horizontal direction toward the arm's side, as the body stands now: the shoulder
        away from its parent joint (``from_parent`` (F, 3)), else the reference body frame's side."""
        side = quat.rotate(arm.body, np.array([1.0 if arm.hand.side == "left" else -1.0, 0.0, 0.0]))
        flat = from_parent * np.array([1.0, 0.0, 1.0])
        norm = np.linalg.norm(flat, axis=1, keepdims=True)
        return np.where(norm > 1e-6, flat / np.maximum(norm, 1e-9), side)

    @staticmethod
    def _swivel(arm: PointingArm, sk, rot, root, jt, toward: np.ndarray, weight: np.ndarray) -> None:
        """Turn the arm (in ``rot``, in place) about the line from the shoulder to the wrist so that the
        elbow lies on the side of that line toward ``toward`` (3,), by ``weight`` (F,); the wrist keeps its
        place and global rotation."""
        shoulder, elbow, wrist = arm.chain
        g_rot, g_pos = chain_fk(sk, rot, root, jt, [shoulder, elbow, wrist, int(sk.parents[wrist])])
        line = g_pos[:, 2] - g_pos[:, 0]
        line /= np.maximum(np.linalg.norm(line, axis=1, keepdims=True), 1e-9)
        now = g_pos[:, 1] - g_pos[:, 0]
        now -= np.sum(now * line, axis=1, keepdims=True) * line
        wanted = toward - np.sum(toward * line, axis=1, keepdims=True) * line
        angle = np.arctan2(np.sum(line * np.cross(now, wanted), axis=1), np.sum(now * wanted, axis=1))
        # A straight arm has no elbow side to turn.
        angle = np.where(np.linalg.norm(now, axis=1) > 1e-4 * arm.length, angle, 0.0) * weight
        turn = quat.from_axis_angle(line, angle)  # (F, 4) global
        s_rot, w_rot, parent_rot = g_rot[:, 0], g_rot[:, 2], g_rot[:, 3]
        rot[:, shoulder] = quat.multiply(rot[:, shoulder], quat.multiply(quat.conjugate(s_rot), quat.multiply(turn, s_rot)))
        rot[:, wrist] = quat.multiply(quat.conjugate(quat.multiply(turn, parent_rot)), w_rot)


def _arm(rig, hand: Hand, chain) -> PointingArm:
    """What aiming one arm needs (see :class:`PointingArm`)."""
    from infuse.kinematics import forward_kinematics

    sk = rig.skeleton
    locals_ = reference_locals(rig)
    g_rot, g_pos = forward_kinematics(sk, locals_[None], sk.rest_translations[None, 0], None)
    g_rot, g_pos = g_rot[0], g_pos[0]
    shoulder, elbow, wrist = chain
    tip = reference_tip(rig, hand)
    along = tip - g_pos[wrist]
    if np.linalg.norm(along) < 1e-6:  # no fingers: the forearm's direction
        along = g_pos[wrist] - g_pos[elbow]
    f = along / np.linalg.norm(along)
    palm = hand.palm - np.dot(hand.palm, f) * f
    palm /= max(np.linalg.norm(palm), 1e-9)
    upper, fore, hand_m = (float(np.linalg.norm(b - a)) for a, b in
                           ((g_pos[shoulder], g_pos[elbow]), (g_pos[elbow], g_pos[wrist]), (g_pos[wrist], tip)))
    segments = (upper, fore, hand_m)
    return PointingArm(chain=(shoulder, elbow, wrist), hand=hand, segments=segments, length=sum(segments),
                       frame=np.stack((f, palm, np.cross(f, palm)), axis=1), wrist_reference=g_rot[wrist],
                       tip_local=quat.rotate(quat.conjugate(g_rot[wrist]), tip - g_pos[wrist]), body=rig.body)

