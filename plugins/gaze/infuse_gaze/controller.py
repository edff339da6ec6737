"""The gaze controller: a character looks at a target with its eyes, head and spine.

``Gaze(target, influence="WAIST", priority="eyes", offset_angle_deg=0, offset_direction=None, ...)``
is played by the :class:`~infuse.runtime.Runtime` in the GAZE layer, additively on the pose below.
Targets are anything :func:`infuse.runtime.as_target` takes: a point, an (F, 3) track, a function of
time, or ``"character:joint"`` (``"character:face"`` means the eyes, or the head); a plain name is
resolved by the runtime when evaluated (a named scene object, or a character's face). The blend weight
scales the turn *before* smoothing and speed limits, so blending in and out obeys the speeds too.

Characters without eyes gaze with the head and spine (the head then points at the target); this
and other gaps are reported once per character.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingFeatureError, UsageError
from infuse.runtime import Controller, Layer, Mode, as_target
from infuse.runtime.pose import ancestors, chain_fk
from infuse.runtime.swing import direction_angles, local_offsets, swing
from infuse.runtime.targets import JointTarget

from .model import (
    DEFAULT_INFLUENCE, EYES, GROUP_NAMES, GROUPS, INFLUENCES, OFFSET_DIRECTIONS, SLOT_GROUPS, SLOT_PARENTS, SLOTS,
    group_name, smoothing_factor,
)
from .solver import SolverInput, rotation_matrices, solve

def offset_vector(angle_deg: float, direction) -> tuple[float, float]:
    """(heading, pitch) radians of an offset of ``angle_deg`` toward ``direction``: a BML word
    (RIGHT, UPLEFT...) or a polar angle in degrees (0 = the character's right, 90 = up)."""
    if direction is None or angle_deg == 0:
        return 0.0, 0.0
    if isinstance(direction, str):
        key = direction.strip().upper()
        if key not in OFFSET_DIRECTIONS:
            raise UsageError(f"offset direction {direction!r}: expected one of {', '.join(OFFSET_DIRECTIONS)} or degrees")
        polar = OFFSET_DIRECTIONS[key]
    else:
        polar = float(direction)
    a, p = np.radians(angle_deg), np.radians(polar)
    return float(-a * np.cos(p)), float(a * np.sin(p))  # heading is positive to the left


class Gaze(Controller):
    """Look at ``target`` (see the module doc).

    - ``influence``: EYES, HEAD, SHOULDER, WAIST or WHOLE (how far down the chain the turn reaches),
      or ``groups``: the group names that move (overrides ``influence``; e.g. SmartBody's joint range);
    - ``priority``: the group that points exactly at the target (default the eyes): groups below it
      share the turn, groups above take what is left;
    - ``offset_angle_deg`` and ``offset_direction``: look beside the target;
    - ``limits``: {group: (heading, up, down, roll) degrees}, ``smooth``: {group: 0..1},
      ``speed_deg_s``: {group: degrees per second} override the model's values (:data:`GROUPS`).
    """

    kind = "gaze"
    layer = Layer.GAZE
    mode = Mode.ADDITIVE
    blend_in_s = 0.3
    blend_out_s = 0.5

    def __init__(self, target, influence: str | None = None, priority: str = "eyes", offset_angle_deg: float = 0.0,
                 offset_direction=None, groups=None, limits: Mapping | None = None, smooth: Mapping | None = None,
                 speed_deg_s: Mapping | None = None):
        self.target = as_target(target) if not (isinstance(target, str) and target.count(":") == 0) else target
        influence = (influence or DEFAULT_INFLUENCE).upper()
        if influence not in INFLUENCES:
            raise UsageError(f"gaze influence {influence!r}: expected one of {', '.join(INFLUENCES)}")
        self.influence = influence
        self.moving = tuple(group_name(g) for g in groups) if groups else INFLUENCES[influence]
        self.priority_group = group_name(priority)
        self.offset = offset_vector(float(offset_angle_deg), offset_direction)
        settings = list(GROUPS)
        for table, apply in ((limits, lambda g, v: g.with_changes(heading_deg=v[0], up_deg=v[1], down_deg=v[2], roll_deg=v[3])),
                             (smooth, lambda g, v: g.with_changes(smooth=float(v))),
                             (speed_deg_s, lambda g, v: g.with_changes(speed_deg_s=float(v)))):
            for key, value in (table or {}).items():
                i = GROUP_NAMES.index(group_name(key))
                settings[i] = apply(settings[i], value)
        for g in settings:
            if g.speed_deg_s <= 0 or not 0 <= g.smooth < 1 or min(g.heading_deg, g.up_deg, g.down_deg, g.roll_deg) < 0:
                raise UsageError(f"gaze group {g.name!r}: speeds must be > 0, smooth in [0, 1), limits >= 0")
        self.settings = tuple(settings)
        # Evaluated after its end until the slowest group is back: its largest turn at its speed.
        self.settle_s = max(g.heading_deg / g.speed_deg_s for g in self.settings) + 0.5

    def describe(self) -> str:
        return f"gaze ({self.influence.lower()})"

    # -- binding -------------------------------------------------------------------------------------
    def bind(self, rig, report):
        slots = np.array([rig.joint(s) if rig.joint(s) is not None else -1 for s in SLOTS])
        present = slots >= 0
        has_eyes = bool(present[7] and present[8])
        if present[7] != present[8]:
            report("only one eye is mapped; gaze leaves the eyes still")
            present[7:9] = False
            slots[7:9] = -1
        if not present[6] and not has_eyes:
            if not present[4] and not present[5]:
                raise MissingFeatureError(f"{rig.name}: cannot gaze: neither eyes nor a head or neck joint is mapped")
            report("no head joint is mapped; gaze points the neck")
        counts = np.array([sum(present[s] for s in range(len(SLOTS)) if SLOT_GROUPS[s] == g) for g in range(len(GROUPS))])
        counts[EYES] = 1 if has_eyes else 0
        available = {GROUP_NAMES[g] for g in range(len(GROUPS)) if counts[g] > 0}
        moving = [g for g in self.moving if g in available]
        if "eyes" in self.moving and not has_eyes:
            report("has no eyes: gaze turns the head and spine instead")
            if self.moving == ("eyes",):
                moving = [g for g in INFLUENCES["HEAD"] if g in available]
        if not moving:
            raise MissingFeatureError(f"{rig.name}: none of the gaze groups {', '.join(self.moving)} is mapped")
        priority = GROUP_NAMES.index(self.priority_group)
        ranks = [GROUP_NAMES.index(g) for g in moving]
        if priority not in ranks:  # the nearest moving group below it, else the lowest above it
            below = [r for r in ranks if r < priority]
            priority = max(below) if below else min(ranks)
        active = np.zeros(len(GROUPS), dtype=bool)
        active[ranks] = True
        fractions = np.ones(len(GROUPS))
        p_rank = sum(1 for r in ranks if r < priority)
        for r in ranks:
            if r <= priority:
                i_rank = sum(1 for q in ranks if q < r)
                fractions[r] = 1.0 / (p_rank + 1 - i_rank)
        # An absent slot repeats its parent slot, aligned frame included (the world's is the body frame).
        chain_aligned = np.empty((len(SLOTS), 4))
        for s, parent in enumerate(SLOT_PARENTS):
            if present[s]:
                chain_aligned[s] = rig.aligned[slots[s]]
            else:
                chain_aligned[s] = chain_aligned[parent] if parent >= 0 else rig.body
        return {"slots": slots, "present": present, "counts": counts, "active": active, "fractions": fractions,
                "eyes_lead": bool(priority == EYES and has_eyes), "chain_aligned": chain_aligned}

    # -- evaluation ----------------------------------------------------------------------------------
    @classmethod
    def evaluate(cls, jobs, block) -> None:
        frames = len(block)
        dt = block.dt
        count = len(jobs)
        n_slots, n_groups = len(SLOTS), len(GROUPS)
        chain_rot = np.empty((count, frames, n_slots, 3, 3))
        chain_pos = np.empty((count, frames, n_slots, 3))
        origin_local = np.empty((count, frames, n_slots, 3))
        forward_angles = np.empty((count, frames, n_slots, 2))
        targets = np.empty((count, frames, 3))
        limits = np.empty((count, n_groups, 4))
        smoothing = np.empty((count, n_groups))
        max_step = np.empty((count, n_groups))
        refine = []
        index_of_rig = {job.rig.name: k for k, job in enumerate(jobs)}
        same_chain: dict[tuple, list[int]] = {}
        for k, job in enumerate(jobs):
            b, pose = job.binding, job.pose
            if job.mode is Mode.OVERRIDE:  # the gaze joints start from their rest rotation, not the pose below
                joints = b["slots"][b["present"]]
                rest = pose.rig.skeleton.rest_rotations[joints]
                pose.set_rotations(joints, np.broadcast_to(rest, (frames,) + rest.shape), job.weight)
            same_chain.setdefault((id(pose.rig.skeleton), tuple(b["slots"]), b["eyes_lead"]), []).append(k)
            target = job.controller.target
            if isinstance(target, str):  # a named scene object, resolved now that the runtime knows it
                target = block.runtime.target(target)
            targets[k] = target.positions(block.times, block)
            if isinstance(target, JointTarget) and target.character in index_of_rig:
                other = index_of_rig[target.character]
                slots = _slots_of(target, jobs[other], block)
                if slots:
                    refine.append((k, other, slots))
            for g, settings in enumerate(job.controller.settings):
                limits[k, g] = settings.limits_rad
                smoothing[k, g] = smoothing_factor(settings.smooth, dt)
                max_step[k, g] = np.radians(settings.speed_deg_s) * dt
        for members in same_chain.values():  # characters on one skeleton share the forward kinematics
            parts = _chain_frames([jobs[k] for k in members])
            for array, part in zip((chain_rot, chain_pos, origin_local, forward_angles), parts):
                array[members] = part
        inp = SolverInput(
            chain_rot=chain_rot, chain_pos=chain_pos, origin_local=origin_local, forward_angles=forward_angles,
            present=np.stack([j.binding["present"] for j in jobs]), counts=np.stack([j.binding["counts"] for j in jobs]),
            targets=targets, weights=np.stack([j.weight for j in jobs]),
            active=np.stack([j.binding["active"] for j in jobs]), fractions=np.stack([j.binding["fractions"] for j in jobs]),
            limits=limits, smoothing=smoothing, max_step=max_step,
            offsets=np.array([j.controller.offset for j in jobs]), refine=tuple(refine))
        groups_state = np.stack([j.state.get("groups", np.zeros((n_groups, 2))) for j in jobs])
        eyes_state = np.stack([j.state.get("eyes", np.zeros((2, 2))) for j in jobs])
        last = None
        if refine and all("positions" in j.state for j in jobs):
            last = np.stack([j.state["positions"] for j in jobs])
        offsets, positions = solve(inp, groups_state, eyes_state, last)
        for k, job in enumerate(jobs):
            job.state["groups"] = groups_state[k]
            job.state["eyes"] = eyes_state[k]
            job.state["positions"] = positions[k, -1]
            b = job.binding
            present = b["present"]
            hv = offsets[k][:, present]
            job.pose.add_offsets(b["slots"][present], local_offsets(b["chain_aligned"][present], swing(hv[..., 0], hv[..., 1])))


def _chain_frames(jobs):
    """For characters on one skeleton with one chain, from the pose below: each slot's aligned frame
    (C, F, S, 3, 3) and position (C, F, S, 3) relative to its parent slot's aligned frame, the gaze
    origin in each slot's aligned frame (C, F, S, 3), and the heading and pitch (C, F, S, 2) of where
    the priority joint points, seen from each slot."""
    b = jobs[0].binding
    slots, present = b["slots"], b["present"]
    skeleton = jobs[0].pose.rig.skeleton
    joints = slots[present]
    columns = ancestors(skeleton, joints)
    local = np.stack([j.pose.local_rotations[:, columns] for j in jobs])
    root = np.stack([j.pose.root_translations for j in jobs])
    moved = [j.pose.joint_translations for j in jobs]
    translations = None
    if any(t is not None for t in moved):
        rest = skeleton.rest_translations[columns]
        translations = np.stack([np.broadcast_to(rest, local.shape[:2] + rest.shape) if t is None else t[:, columns] for t in moved])
    rot, pos = chain_fk(skeleton, local, root, translations, joints, columns)
    for c, job in enumerate(jobs):  # into the world: where each character stands
        rot[c], pos[c] = job.rig.place(rot[c], pos[c])
    lead = local.shape[:2]
    g_rot = np.empty(lead + (len(SLOTS), 4))
    g_pos = np.empty(lead + (len(SLOTS), 3))
    g_rot[..., present, :] = rot
    g_pos[..., present, :] = pos
    for s, parent in enumerate(SLOT_PARENTS):  # an absent slot repeats its parent (the world: identity, origin)
        if not present[s]:
            g_rot[..., s, :] = g_rot[..., parent, :] if parent >= 0 else quat.IDENTITY
            g_pos[..., s, :] = g_pos[..., parent, :] if parent >= 0 else 0.0
    aligned = np.stack([j.binding["chain_aligned"] for j in jobs])[:, None]  # (C, 1, S, 4)
    frames_w = quat.multiply(g_rot, aligned)  # each slot's aligned frame in the pose below
    parents = np.array(SLOT_PARENTS)
    parent_w = np.where((parents >= 0)[:, None], frames_w[..., np.maximum(parents, 0), :], quat.IDENTITY)
    parent_p = np.where((parents >= 0)[:, None], g_pos[..., np.maximum(parents, 0), :], 0.0)
    inverse_parent = quat.conjugate(parent_w)
    chain_rot = rotation_matrices(quat.multiply(inverse_parent, frames_w))
    chain_pos = quat.rotate(inverse_parent, g_pos - parent_p)
    eyes = [7, 8] if present[7] and present[8] else []
    lead_slots = eyes if b["eyes_lead"] else [6]
    origin = g_pos[..., eyes or [6], :].mean(axis=-2)
    forward = quat.rotate(frames_w[..., lead_slots, :], np.array([0.0, 0.0, 1.0])).mean(axis=-2)
    inverse = quat.conjugate(frames_w)
    origin_local = quat.rotate(inverse, origin[..., None, :] - g_pos)
    heading, pitch = direction_angles(quat.rotate(inverse, np.broadcast_to(forward[..., None, :], g_pos.shape)))
    return chain_rot, chain_pos, origin_local, np.stack((heading, pitch), axis=-1)


def _slots_of(target: JointTarget, job, block) -> tuple[int, ...]:
    """The chain slots of gazing character ``job`` whose mean is ``target``, if they all are slots."""
    _, joints = target.resolve(block.runtime)
    slots = list(job.binding["slots"])
    return tuple(slots.index(j) for j in joints) if all(j in slots for j in joints) else ()
