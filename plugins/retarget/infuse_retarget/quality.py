"""Quality figures of one retargeted clip against its source (built on :mod:`infuse.metrics`).

:func:`evaluate` runs the plain transfer, the paper's warped-feet IK and the contact-pinned IK on
one clip and measures each against the source, with the source's contact flags:

- foot skate, cm per metre walked (source, plain, paper, final), over the source's contacts of the
  points both feet have (a target foot without a ball has nothing to hold the source's ball contacts);
- bone-direction agreement on the body's limbs, degrees (plain, final): the bones a default pose
  sets (upper arm, forearm, thigh, shin) and the hip-to-hip and shoulder-to-shoulder lines, which
  stand for the pelvis and chest orientation. The trunk's, shoulder girdle's and feet's bones keep
  each rig's build (see :mod:`.alignment`), so their directions differ between rigs by design;
- popping, degrees: every mapped joint's largest change of global orientation between frames
  (:func:`infuse.metrics.popping`), final output against source, and the joint that comes closest
  to (or goes furthest past) the bound, 1.5 x the source's largest turn + 10 degrees;
- foot penetration and float relative to the ground, cm (source, plain, final);
- root speed relative to the source's speed times the leg scale;
- the largest distance left to a reachable IK goal, mm, and the share of goals out of reach
  (constraints only: a swinging ball of the foot is a preference, not a goal).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import metrics
from infuse.canonical import BODY_NAMES
from infuse.contacts import FootContacts, lowest_points
from infuse.kinematics import motion_fk
from infuse.motion import Motion

from .alignment import SWUNG
from .retarget import RetargetResult, retarget_clip
from .transfer import RetargetPlan

#: Body joints whose bones' directions are compared: the limbs, which the alignment lines up.
POSE_NAMES = tuple(n for n in BODY_NAMES if n in SWUNG)


@dataclass(frozen=True)
class Quality:
    """Figures for one (clip, target) pair; see the module docstring. Lengths in cm, angles in degrees."""

    frames: int
    scale: float
    skate_source: float
    skate_plain: float
    skate_paper: float
    skate_final: float
    bones_plain: float
    bones_final: float
    bones_worst: float
    penetration_source: float
    penetration_plain: float
    penetration_final: float
    float_source: float
    float_plain: float
    float_final: float
    speed_ratio: float
    residual_mm: float
    unreachable: float
    popping_plain: metrics.Popping
    popping_final: metrics.Popping

    def skate_limit(self) -> float:
        """The foot-skate target for this pair: source x 1.1 + 0.5 cm/m."""
        return self.skate_source * 1.1 + 0.5


def _matched_contacts(plan: RetargetPlan, result: RetargetResult) -> tuple[FootContacts, np.ndarray]:
    """The source's contacts restricted to points the target has (a target foot without a ball has
    no counterpart for the source's ball), and the target joints playing them."""
    keep, joints = [], []
    for k, (j, foot) in enumerate(zip(result.contacts.points, result.contacts.foot_of_point)):
        src, tgt = plan.source.feet[foot], plan.target.feet[foot]
        if j == src.ankle:
            keep.append(k)
            joints.append(tgt.ankle)
        elif tgt.ball is not None:
            keep.append(k)
            joints.append(tgt.ball)
    c = result.contacts
    matched = FootContacts(c.points[keep], c.foot_of_point[keep], c.flags[:, keep], c.ground, c.leg_length, c.lowest)
    return matched, np.array(joints, dtype=np.int64)


def _measure(plan: RetargetPlan, result: RetargetResult, motion: Motion):
    g, p = motion_fk(motion)
    matched, points = _matched_contacts(plan, result)
    skate = metrics.foot_skate(p, matched, plan.target.index["base"], points).per_metre
    bones = metrics.bone_directions(result.source_positions, plan.source_joints, p, plan.target.index, POSE_NAMES)
    lowest = lowest_points(plan.target.skeleton, plan.target.feet, g, p)
    ground = metrics.ground_contact(lowest, result.contacts.foot_flags(), result.ground)
    speed = metrics.mean_speed(p[:, plan.target.index["base"]], motion.fps)
    return skate, bones, ground, speed, g


def evaluate(plan: RetargetPlan, motion: Motion) -> Quality:
    """Retarget ``motion`` three ways with ``plan`` and measure each (see the module docstring)."""
    final = retarget_clip(plan, motion, ik="contacts")
    paper = retarget_clip(plan, motion, ik="paper")
    c = final.contacts
    ps = final.source_positions
    src_base = plan.source.index["base"]
    skate_src = metrics.foot_skate(ps, _matched_contacts(plan, final)[0], src_base).per_metre
    ground_src = metrics.ground_contact(c.lowest, c.foot_flags(), c.ground)
    speed_src = metrics.mean_speed(ps[:, src_base], motion.fps)
    skate_plain, bones_plain, ground_plain, _, g_plain = _measure(plan, final, final.plain)
    skate_paper = _measure(plan, paper, paper.motion)[0]
    skate_final, bones_final, ground_final, speed, g_final = _measure(plan, final, final.motion)
    g_source = motion_fk(motion)[0]
    mapped = plan.common
    reached = [r[final.reachable[k] & final.hard[k]] for k, r in final.residual.items()]
    residual = max((float(r.max()) for r in reached if r.size), default=0.0)
    total = sum(int(h.sum()) for h in final.hard.values())
    unreachable = sum(int((final.hard[k] & ~r).sum()) for k, r in final.reachable.items()) / max(total, 1)
    return Quality(
        frames=motion.num_frames, scale=plan.scale,
        skate_source=skate_src, skate_plain=skate_plain, skate_paper=skate_paper, skate_final=skate_final,
        bones_plain=bones_plain.mean, bones_final=bones_final.mean, bones_worst=bones_final.worst,
        penetration_source=ground_src.penetration, penetration_plain=ground_plain.penetration,
        penetration_final=ground_final.penetration,
        float_source=ground_src.float, float_plain=ground_plain.float, float_final=ground_final.float,
        speed_ratio=speed / (speed_src * plan.scale) if speed_src > 1e-9 else float("nan"),
        residual_mm=1000.0 * residual, unreachable=unreachable,
        popping_plain=metrics.popping(g_source, plan.source_joints, g_plain, plan.target.index, mapped),
        popping_final=metrics.popping(g_source, plan.source_joints, g_final, plan.target.index, mapped),
    )


def reach_error(plan: RetargetPlan, motion: Motion, source_positions: np.ndarray, extended: float = 0.9) -> float:
    """How far a retargeted hand reaches differently from the source, percent of arm length.

    For each arm, the wrist's offset from its shoulder divided by the arm length (shoulder to elbow
    to wrist at rest) is compared between the source (``source_positions`` (F, Js, 3)) and
    ``motion``, over frames where the source arm is extended beyond ``extended``; NaN if never.
    """
    _, p = motion_fk(motion)
    errors = []
    for side in "lr":
        names = [f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist"]
        if not all(n in plan.common for n in names):
            continue
        s = [plan.source_joints[n] for n in names]
        t = [plan.target.index[n] for n in names]
        arm_s = sum(np.linalg.norm(plan.source.rig.positions[b] - plan.source.rig.positions[a]) for a, b in zip(s, s[1:]))
        arm_t = sum(np.linalg.norm(plan.target.rig.positions[b] - plan.target.rig.positions[a]) for a, b in zip(t, t[1:]))
        src = (source_positions[:, s[2]] - source_positions[:, s[0]]) / arm_s
        out = (p[:, t[2]] - p[:, t[0]]) / arm_t
        mask = np.linalg.norm(src, axis=1) > extended
        if mask.any():
            errors.append(np.linalg.norm(src - out, axis=1)[mask].mean())
    return 100.0 * float(np.mean(errors)) if errors else float("nan")
