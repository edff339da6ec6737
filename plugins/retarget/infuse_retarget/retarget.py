"""Retarget a clip: plain transfer, then constraint enforcement on the feet (and optionally the hands).

``ik`` selects the constraint stage (paper, section 4.2 and beyond):

- ``"none"``: the plain transfer (rotations and scaled root).
- ``"paper"``: each ankle follows the paper's warped trajectory ``p(0) + s·(p_s(t) − p_s(0))``
  through the whole clip, enforced by the two-bone leg IK of :mod:`infuse.runtime.limb_ik` on
  hip–knee–ankle (the knee bent by the law of cosines, the hip turned by the shortest arc), and the ball of
  the foot rides on it as the transferred foot carries it (a warped path of its own would drag a
  foot built unlike the source's along the source foot's geometry).
- ``"contacts"`` (default): the same IK, but foot contacts are detected on the source (speed and
  height normalized by leg length) and planted points are pinned exactly, at the height they rest
  at in the plain transfer, with the correction gliding between contacts; the ball of the foot
  rides on the ankle, heading square to the foot's side-to-side axis and lifting off as the
  source's ball does, and is left where the transferred foot carries it once the source's ball is
  well off the ground. A target foot without a ball joint has a tip all the same (the joint or end
  site below its ankle farthest from it); where the tip would go below the level the foot is
  planted at, the foot pitches up about its ankle (:func:`tip_above`).

``limb_scaling`` adds per-limb scaling by extension for the arms: a straightening source arm
brings the target's wrist to the source's reach scaled by the arm-length ratio.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from infuse import contacts as contact_detection, footing, quaternions as quat
from infuse.errors import UsageError
from infuse.kinematics import forward_kinematics
from infuse.motion import Motion
from infuse.runtime import limb_ik
from infuse.skeleton import Skeleton

from . import cq, goals, ik
from .transfer import RetargetPlan, Transferred

IK_MODES = ("none", "paper", "contacts")
#: Canonical hinge axes in the T-pose frame: knees bend about +X, elbows about -Y (left) / +Y (right).
HINGES = {"l_knee": (1.0, 0.0, 0.0), "r_knee": (1.0, 0.0, 0.0), "l_elbow": (0.0, -1.0, 0.0), "r_elbow": (0.0, 1.0, 0.0)}
#: The canonical side-to-side axis of a foot (the knee's hinge): the ball heads square to it.
LATERAL = np.array([1.0, 0.0, 0.0])
#: Heights (source leg lengths above its planted height) of the source's ball of the foot between
#: which the target ball's goal hands over from its height above the ground to the transferred
#: foot: from the contact detector's height threshold (``infuse.contacts``) to a third of the leg.
GROUND_LIFT = (0.06, 0.3)
#: Seconds over which a ball contact's hold on the ankle goal fades in and out.
BLEND_SECONDS = 0.12
#: Degrees per second at which a foot without a ball joint, pitched up about its ankle to keep
#: its tip off the ground, pitches back (:func:`tip_above`).
TIP_PITCH_SPEED = 150.0
#: Share of the leg's length (thigh + shin) below which a point under the ankle is no foot tip.
MIN_TIP = 0.1
#: The hinge of a limb never straightens past this (radians): no hyperextended knees.
MIN_FLEXION = np.radians(1.0)


@dataclass
class RetargetResult:
    """A retargeted clip and what it took.

    - ``motion``: the result on the target skeleton; ``plain``: the plain transfer.
    - ``scale``: leg-length ratio (target over source); ``ik``: the mode used.
    - ``contacts``: the source's :class:`infuse.contacts.FootContacts` (``None`` for a plain
      transfer, which does not need them).
    - ``ground``: metres, the target's ground: the level of its lowest foot joints while planted in
      the plain transfer (the source's is ``contacts.ground``).
    - ``source_positions``: (F, Js, 3) the source clip's global joint positions.
    - ``goals`` / ``residual`` / ``reachable`` / ``hard``: per goal joint name, (F, 3) goal
      positions, (F,) distance left after IK (metres), (F,) whether the goal was within the limb's
      reach and (F,) whether it is a constraint rather than a preference (a swinging ball of the
      foot only says where the foot points).
    """

    motion: Motion
    plain: Motion
    scale: float
    ik: str
    contacts: contact_detection.FootContacts | None
    ground: float
    source_positions: np.ndarray
    goals: dict[str, np.ndarray] = field(default_factory=dict)
    residual: dict[str, np.ndarray] = field(default_factory=dict)
    reachable: dict[str, np.ndarray] = field(default_factory=dict)
    hard: dict[str, np.ndarray] = field(default_factory=dict)


def sole_sites(plan: RetargetPlan, state: Transferred, k: int) -> np.ndarray | None:
    """(2, 3, F) where the heel and the tip of target foot ``k`` taken from its mesh
    (:attr:`RetargetPlan.sole_points`) are in a transferred state; ``None`` without them."""
    points = plan.sole_points[k]
    if points is None:
        return None
    ankle = plan.target.feet[k].ankle
    at = plan.positions(state, [ankle])[ankle]
    return np.stack([at + cq.rotate(state.rotations[ankle], p[:, None]) for p in points])


def target_lowest_points(plan: RetargetPlan, state: Transferred) -> np.ndarray:
    """(F, 2) height of each target foot's lowest joint, end site or mesh heel or tip, from a
    transferred state."""
    sk = plan.target.skeleton
    out = []
    for k, foot in enumerate(plan.target.feet):
        pos = plan.positions(state, foot.joints)
        low = np.min(np.stack([pos[j][1] for j in foot.joints]), axis=0)
        if foot.end_sites:
            for e in foot.end_sites:
                p = int(sk.end_site_parents[e])
                site = pos[p] + cq.rotate(state.rotations[p], sk.end_site_offsets[e][:, None])
                low = np.minimum(low, site[1])
        sites = sole_sites(plan, state, k)
        if sites is not None:
            low = np.minimum(low, sites[:, 1].min(axis=0))
        out.append(np.broadcast_to(low, (state.rotations.shape[-1],)))
    return np.stack(out, axis=1)


class _Solver:
    """Runs the IK stages on one transferred state (see the module docstring)."""

    def __init__(self, plan: RetargetPlan, state: Transferred, result: RetargetResult):
        self.plan, self.state, self.result = plan, state, result
        self.names = plan.target.skeleton.names
        self._segments = {}

    def segment(self, names) -> np.ndarray:
        """Target joints driven by any of the canonical ``names``."""
        key = tuple(names)
        if key not in self._segments:
            wanted = set(names)
            computed = self.plan.computed
            self._segments[key] = np.array([j for j, d in enumerate(self.plan.driver) if d in wanted and computed[j]],
                                           dtype=np.int64)
        return self._segments[key]

    def turn(self, names, rotation: np.ndarray) -> None:
        joints = self.segment(names)
        if len(joints):
            self.state.rotations[joints] = cq.mul(rotation, self.state.rotations[joints])

    def limb(self, root: str, middle: str, end: str, goal: np.ndarray, upper_segment, lower_segment):
        """Solve a two-bone limb for ``goal`` (3, F) and turn its segments: joints driven by the
        canonical names ``upper_segment`` (between root and middle) and ``lower_segment`` (below
        the middle joint) by :func:`infuse.runtime.limb_ik.turn_limb`. Returns the lower segment's
        world turn (4, F) and where the end joint ends up (3, F)."""
        plan, state = self.plan, self.state
        tgt = plan.target.index
        pos = plan.positions(state, [tgt[root], tgt[middle], tgt[end]])
        r, m, e = pos[tgt[root]], pos[tgt[middle]], pos[tgt[end]]
        reference = cq.rotate(plan.canonical_delta(state.rotations, middle), np.array(HINGES[middle])[:, None])
        axis, flexion = limb_ik.hinge_axes(r.T, m.T, e.T, reference.T)
        solution = limb_ik.turn_limb(r.T, m.T, e.T, goal.T, axis, flexion, min_flexion=MIN_FLEXION)
        root_turn, middle_turn = np.ascontiguousarray(solution.root.T), np.ascontiguousarray(solution.middle.T)
        self.turn(upper_segment, root_turn)
        self.turn(lower_segment, middle_turn)
        name = self.names[tgt[end]]
        self.result.goals[name] = goal.T
        self.result.residual[name] = solution.residual
        self.result.reachable[name] = solution.reachable
        self.result.hard[name] = np.ones(len(solution.residual), dtype=bool)
        return middle_turn, np.ascontiguousarray(solution.end.T)

    def foot(self, k: int, mode: str) -> None:
        plan, state = self.plan, self.state
        side = "lr"[k]
        src_foot, tgt_foot = plan.source.feet[k], plan.target.feet[k]
        ps = state.source_positions
        ankle_s = ps[src_foot.ankle]
        ball_s = ps[src_foot.ball] if src_foot.ball is not None else None
        ball_t = tgt_foot.ball if ball_s is not None else None
        pos = plan.positions(state, [tgt_foot.ankle] + ([ball_t] if ball_t is not None else []))
        ankle_t = pos[tgt_foot.ankle]
        if mode == "paper":
            ankle_goal = goals.warp(ankle_t[:, 0], ankle_s, plan.scale)
            # The ball rides on the warped ankle as the transferred foot carries it.
            ball_goal = ankle_goal + (pos[ball_t] - ankle_t) if ball_t is not None else None
        else:
            ankle_goal, ball_goal = self._pinned_goals(k, pos, ankle_s, ball_s, ball_t)
        foot = [f"{side}_ankle", f"{side}_forefoot", f"{side}_toe"]
        tip_t = self._tip(k) if ball_t is None and mode != "paper" else None
        shin_turn, ankle = self.limb(f"{side}_hip", f"{side}_knee", f"{side}_ankle", ankle_goal, [f"{side}_hip"],
                                     [f"{side}_knee"] + foot)
        if ball_t is None:
            if tip_t is not None:
                tip = ankle + cq.rotate(shin_turn, tip_t - ankle_t)
                sites = sole_sites(self.plan, self.state, k)
                heel = None if sites is None else ankle + cq.rotate(shin_turn, sites[0] - ankle_t)
                self.turn(foot, tip_above(ankle, tip, self._lateral(k), self._planted_level(k), self.state.fps, heel))
            return
        ball_now = ankle + cq.rotate(shin_turn, pos[ball_t] - ankle_t)
        length = self._foot_length(pos, ankle_t, ball_t)
        if mode != "paper":
            ball_goal = self._near_ground(ball_goal, ball_now, ankle, length, k)
        turn, ball_end = ik.aim(ankle, ball_now, ball_goal, shin_turn)
        self.turn(foot, turn)
        name = self.names[ball_t]
        self.result.goals[name] = ball_goal.T
        self.result.residual[name] = cq.norm(ball_end - ball_goal)
        self.result.reachable[name] = np.abs(cq.norm(ball_goal - ankle) - length) < limb_ik.REACH_MARGIN
        planted = self.result.contacts.flags[:, list(self.result.contacts.points).index(src_foot.ball)]
        self.result.hard[name] = np.ones(len(planted), dtype=bool) if mode == "paper" else planted

    def _pinned_goals(self, k: int, pos: dict, ankle_s: np.ndarray, ball_s, ball_t):
        plan, found = self.plan, self.result.contacts
        s = plan.scale
        tgt_foot = plan.target.feet[k]
        cols = np.nonzero(found.foot_of_point == k)[0]
        ankle_flags = found.flags[:, cols[0]]
        ball_flags = found.flags[:, cols[1]] if len(cols) > 1 else ankle_flags
        ankle_t = np.broadcast_to(pos[tgt_foot.ankle], ankle_s.shape)
        # Planted heights come from the plain transfer (which stands the target on its own ground);
        # the swing lifts off them by the source's lift, scaled.
        ankle_h = footing.planted_height(ankle_t[1], ankle_flags)
        ankle_w = goals.warp(ankle_t[:, 0], ankle_s, s)
        ankle_w[1] = ankle_h + s * (ankle_s[1] - footing.planted_height(ankle_s[1], ankle_flags))
        if ball_t is None:
            return footing.pinned(ankle_w, ankle_flags, ankle_h)[0], None
        length = self._foot_length(pos, ankle_t, ball_t)
        ball_t_path = np.broadcast_to(pos[ball_t], ankle_s.shape)
        ball_h = footing.planted_height(ball_t_path[1], ball_flags)
        height = ball_h + s * (ball_s[1] - footing.planted_height(ball_s[1], ball_flags))
        ball_w = self._ball_on_foot(ankle_w, height, self._lateral(k), length)
        return footing.pinned(ankle_w, ankle_flags, ankle_h, ball_w, ball_flags, ball_h, length, BLEND_SECONDS * self.state.fps)

    def _planted_level(self, k: int) -> float:
        """The height (m) of the lowest point of target foot ``k`` while it is planted, as the legs now
        stand (the leg IK turns the foot with the shin, so this is not the plain transfer's)."""
        lowest = target_lowest_points(self.plan, self.state)[:, k]
        return footing.planted_height(lowest, self.result.contacts.foot_flags()[:, k])

    def _tip(self, k: int) -> np.ndarray | None:
        """(3, F) where the tip of target foot ``k`` is in the current state: the tip its mesh gives
        (:func:`sole_sites`), else of the joints and end sites below its ankle, the one farthest from
        the ankle in the reference pose; ``None`` for a foot with nothing below its ankle farther
        than :data:`MIN_TIP` of the leg's length (an end site on the ankle itself, as OpenNI
        captures have, is no tip)."""
        sites = sole_sites(self.plan, self.state, k)
        if sites is not None:
            return sites[1]
        rig, foot = self.plan.target.rig, self.plan.target.feet[k]
        sk = rig.skeleton
        joints = [j for j in foot.joints if j != foot.ankle]
        parents = [int(sk.end_site_parents[e]) for e in foot.end_sites]
        offsets = [np.asarray(sk.end_site_offsets[e], dtype=np.float64) for e in foot.end_sites]
        reference = [rig.positions[j] for j in joints]
        reference += [rig.positions[p] + quat.rotate(rig.rotations[p], o) for p, o in zip(parents, offsets)]
        leg = _chain_length(rig.positions, [foot.hip, foot.knee, foot.ankle])
        far = np.linalg.norm(np.reshape(reference, (-1, 3)) - rig.positions[foot.ankle], axis=1)
        if not len(far) or far.max() <= MIN_TIP * leg:
            return None
        pick = int(np.argmax(far))
        pos = self.plan.positions(self.state, joints + parents)
        if pick < len(joints):
            return pos[joints[pick]]
        e = pick - len(joints)
        return pos[parents[e]] + cq.rotate(self.state.rotations[parents[e]], offsets[e][:, None])

    def _lateral(self, k: int) -> np.ndarray:
        """(3, F) the side-to-side axis of foot ``k`` as transferred (the canonical +X the ankle carries)."""
        delta = self.plan.canonical_delta(self.state.rotations, f"{'lr'[k]}_ankle")
        return cq.rotate(delta, LATERAL[:, None])

    def _near_ground(self, ball_goal: np.ndarray, ball_now: np.ndarray, ankle: np.ndarray, length: float, k: int) -> np.ndarray:
        """(3, F) the ball goal ``ball_goal`` near the ground, the ball as the transferred foot carries
        it (``ball_now``) once the source's ball is high: the weight of the goal falls from 1 to 0
        as the source ball rises from :data:`GROUND_LIFT` [0] to [1] leg lengths above where it is
        planted. Kept ``length`` from the ``ankle`` (3, F).

        The goal's height follows the source's ball, and off the ground that says nothing of how
        the foot is turned: a running foot kicked up behind the knee points down and back, and a
        goal ahead of the ankle there turned it about by up to 170 degrees in a frame or two.
        """
        found = self.result.contacts
        src_foot = self.plan.source.feet[k]
        flags = found.flags[:, list(found.points).index(src_foot.ball)]
        height = self.state.source_positions[src_foot.ball][1]
        lift = (height - footing.planted_height(height, flags)) / max(found.leg_length, 1e-9)
        w = 1.0 - footing.smoothstep((lift - GROUND_LIFT[0]) / (GROUND_LIFT[1] - GROUND_LIFT[0]))
        toward = ball_now + w * (ball_goal - ball_now) - ankle
        return ankle + length * toward / np.maximum(cq.norm(toward), 1e-12)

    @staticmethod
    def _foot_length(pos: dict, ankle_t: np.ndarray, ball_t: int) -> float:
        return float(cq.norm(pos[ball_t][:, :1] - ankle_t[:, :1])[0])

    @staticmethod
    def _ball_on_foot(ankle: np.ndarray, height: np.ndarray, lateral: np.ndarray, length: float) -> np.ndarray:
        """(3, F) goal for the ball of a foot ``length`` long whose ankle goes to ``ankle`` (3, F): at
        ``height`` (F,) as far as the foot reaches, heading square to the transferred foot's
        ``lateral`` axis (3, F, the canonical +X the foot carries).

        The ball lifts off the ground as the source's does, as the ankle; how steeply the foot
        then points follows from the target's own foot, so a foot longer than the source's, or
        with a lower ankle, does not dig into the ground as it rolls over. The heading comes from
        the foot's side-to-side axis, not from where its ball lies: a foot built with a high ankle
        points its ball straight down, and past, when it rolls over its toes, and the ball's
        horizontal direction then turns about from one frame to the next.
        """
        rise = np.clip(height - ankle[1], -length, length)
        heading = np.stack((-lateral[2], lateral[0]))  # lateral x up, on the ground plane
        heading = heading / np.maximum(np.linalg.norm(heading, axis=0), 1e-12)
        ball = np.empty_like(ankle)
        ball[1] = ankle[1] + rise
        ball[[0, 2]] = ankle[[0, 2]] + np.sqrt(length * length - rise * rise) * heading
        return ball

    def arms(self) -> None:
        plan, state = self.plan, self.state
        src, tgt = plan.source, plan.target
        ps = state.source_positions
        for side in "lr":
            names = [f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist"]
            if not all(n in plan.common for n in names):
                continue
            s_j = [plan.source_joints[n] for n in names]
            t_j = [tgt.index[n] for n in names]
            arm_s = _chain_length(src.rig.positions, s_j)
            arm_t = _chain_length(tgt.rig.positions, t_j)
            pos = plan.positions(state, t_j)
            goal, _ = goals.reach(pos[t_j[0]], ps[s_j[0]], ps[s_j[2]], pos[t_j[2]], arm_t / arm_s, arm_s)
            self.limb(names[0], names[1], names[2], goal, [names[0]], [names[1], f"{side}_forearm"])


def tip_above(ankle: np.ndarray, tip: np.ndarray, lateral: np.ndarray, level: float, fps: float,
              heel: np.ndarray | None = None) -> np.ndarray:
    """(4, F) world turn of a foot about its ``ankle`` (3, F) that keeps its ``tip`` (3, F), and its
    ``heel`` (3, F) when given, on or above ``level`` (m), over a clip at ``fps`` frames per second;
    ``lateral`` (3, F) is the foot's side-to-side axis (the canonical +X it carries; the foot
    points along ``lateral`` x +Y).

    The foot pitches about the horizontal of its side-to-side axis, by the difference between the
    tip's elevation seen from the ankle and the elevation that puts it on ``level``: a rigid foot,
    with no ball joint to bend, rolls up about its ankle rather than digging its tip in. (At toe
    off such a foot may point straight down, where the axis square to the ankle-to-tip line turns
    about from frame to frame; its side-to-side axis does not.) The pitch eases out at most
    :data:`TIP_PITCH_SPEED`, since a tip leaving the ground at toe off would otherwise drop the foot
    by tens of degrees in a frame; easing out late only lifts the tip higher. A heel below
    ``level`` pitches the foot down as far as the tip stays on or above it, easing out alike.
    """
    axis = np.stack((-lateral[0], np.zeros_like(lateral[0]), -lateral[2]))
    axis /= np.maximum(cq.norm(axis), 1e-12)
    forward = np.stack((axis[2], np.zeros_like(axis[0]), -axis[0]))  # +Y x axis: turning about axis raises it
    r = tip - ankle
    ahead, up = cq.dot(r, forward), r[1]
    span = np.maximum(np.hypot(ahead, up), 1e-9)  # the tip's distance from the axis
    have = np.arctan2(up, ahead)
    want = np.arcsin(np.clip((level - ankle[1]) / span, -1.0, 1.0))
    need = np.where(tip[1] < level, np.maximum(want - have, 0.0), 0.0)
    step = np.radians(TIP_PITCH_SPEED) / max(fps, 1e-9) * np.arange(len(need))
    lift = _eased(need, step)
    if heel is not None:
        back = heel - ankle
        behind, up = -cq.dot(back, forward), back[1]
        span = np.maximum(np.hypot(behind, up), 1e-9)
        # Pitching up by lift lowers a point behind the ankle by as much; a heel pitched forward of
        # straight below the ankle is not raised by pitching the foot down.
        elevation = np.arctan2(up, behind) - lift
        sunk = np.arcsin(np.clip((level - ankle[1]) / span, -1.0, 1.0)) - elevation
        sunk = np.where((ankle[1] + span * np.sin(elevation) < level) & (np.cos(elevation) > 0.0), sunk, 0.0)
        room = np.maximum(have + lift - want, 0.0)  # how far the tip can pitch down and stay above
        lift = lift - np.minimum(_eased(np.maximum(sunk, 0.0), step), room)
    return cq.exp(axis * lift)


def _eased(need: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(F,) at least ``need`` (F,) radians, falling at most ``step`` (F,) (the fall per frame times
    the frame number): the maximum over frames s <= t of need[s] - (step[t] - step[s])."""
    return np.maximum.accumulate(need + step) - step


def _chain_length(positions: np.ndarray, joints) -> float:
    return float(sum(np.linalg.norm(positions[b] - positions[a]) for a, b in zip(joints, joints[1:])))


def retarget_clip(plan: RetargetPlan, motion: Motion, ik: str = "contacts", limb_scaling: bool = False,
                  contact_options: dict | None = None) -> RetargetResult:
    """Retarget ``motion`` (on the plan's source skeleton) with the constraint stage ``ik``."""
    if ik not in IK_MODES:
        raise UsageError(f"ik must be one of {', '.join(IK_MODES)}, got {ik!r}")
    plan.check_source(motion)
    gs, ps = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations,
                                motion.joint_translations, joint_major=True)
    state = plan.transfer(motion, fk=(gs, ps))
    plain = plan.to_motion(state, motion)
    source_positions = ps.transpose(2, 0, 1)
    if ik == "none" and not limb_scaling:
        return RetargetResult(plain, plain, plan.scale, ik, None, float("nan"), source_positions)
    found = contact_detection.foot_contacts(motion, plan.source.index, fk=(gs.transpose(2, 0, 1), source_positions),
                                            **(contact_options or {}))
    planted = found.foot_flags()
    lowest = target_lowest_points(plan, state)
    ground = float(np.median(lowest[planted]) if planted.any() else np.percentile(lowest.min(axis=1), 10.0))
    result = RetargetResult(plain, plain, plan.scale, ik, found, ground, source_positions)
    state = Transferred(state.rotations.copy(), state.base, gs, ps, state.ground, state.fps)
    solver = _Solver(plan, state, result)
    if ik != "none":
        for k in (0, 1):
            solver.foot(k, ik)
    if limb_scaling:
        solver.arms()
    result.motion = plan.to_motion(state, motion)
    return result


def retarget(motion: Motion, source_mapping, target_skeleton: Skeleton, target_mapping, *, ik: str = "contacts",
             limb_scaling: bool = False, target_motion: Motion | None = None, source_file=None, target_file=None,
             contact_options: dict | None = None, target_meshes=()) -> Motion:
    """Retarget ``motion`` onto ``target_skeleton`` (mappings: :class:`~infuse.mapping.Mapping` or dicts).

    See the module docstring for ``ik`` and ``limb_scaling``; ``target_motion`` is a clip on the
    target whose most upright frame is its default pose when its rest is not a standing pose;
    ``target_meshes`` the target's skinned meshes (a foot without a ball joint takes its heel and
    tip from them).
    """
    plan = RetargetPlan(motion.skeleton, source_mapping, target_skeleton, target_mapping, source_motion=motion,
                        target_motion=target_motion, source_file=source_file, target_file=target_file,
                        target_meshes=target_meshes)
    return retarget_clip(plan, motion, ik=ik, limb_scaling=limb_scaling, contact_options=contact_options).motion
