"""The ``ik_constraint`` controller: an effector joint kept on a target by IK (SmartBody's ``sbm:constraint``).

The effector is a joint by canonical name or the character's own name. A wrist or an ankle is carried
by two-joint limb IK (shoulder-elbow-wrist, hip-knee-ankle; the hand or foot keeps the orientation the
pose below gives it, or with ``straight_end`` lies in line with the limb as in the reference pose); any other joint (the head, a fingertip) by cyclic coordinate descent over the
joints from ``root`` (default: three joints up, never the pelvis) down to it, vectorized over frames;
a wrist's or ankle's ``root`` at or above the limb (SmartBody names the clavicle) keeps limb IK.
The goal is the target's position plus ``offset_m`` (metres, world axes). The activity's weight is the
constraint's: it fades in over ``blend_in_s`` and out over ``blend_out_s``.

It runs last on the head layer, after gazes and head movements, so whatever turned the body before,
the effector ends on its target.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk

from .hands import reference_locals
from .targets import check_point, own_positions, resolve_target

#: Effectors solved as two-joint limbs: the canonical end joint -> its limb's upper joints.
LIMBS = {f"{s}_wrist": (f"{s}_shoulder", f"{s}_elbow") for s in "lr"} | \
        {f"{s}_ankle": (f"{s}_hip", f"{s}_knee") for s in "lr"}
#: Joints a chain effector moves by default, above it; and the passes of coordinate descent.
CHAIN_JOINTS = 3
CCD_PASSES = 8
#: A goal further than this from where the effector ends is reported out of reach, metres.
REACH_TOLERANCE_M = 0.02


@dataclass(frozen=True, eq=False)
class ConstraintBinding:
    """An IK constraint bound to one character: its effector joint ``end``, and either the two-joint ``limb``
    (upper, middle, end) it is carried by, with the end's ``straight`` local rotation (4,) in the reference
    pose when it lies in line with the limb (None: it keeps the pose below's orientation), or the ``chain``
    (K,) of joints above it that coordinate descent turns, top first."""

    end: int
    limb: tuple[int, int, int] | None = None
    straight: np.ndarray | None = None
    chain: np.ndarray | None = None


@dataclass
class ConstraintState:
    """What a constraint activity keeps between blocks: whether it has ``reported`` its target out of reach."""

    reported: bool = False


class IKConstraint(Controller):
    """Keep ``effector`` on ``target`` (a point, ``"character:joint"``, a runtime target's name or a
    :class:`~infuse.runtime.targets.Target`) shifted by ``offset_m`` (3,) metres; ``root``: the top joint
    of a chain effector (canonical or own name). ``blend_in_s``/``blend_out_s``: the fades, seconds;
    ``purpose``: what the constraint is for, in its report (default: the constraint on the effector);
    ``straight_end``: a limb's end joint takes its reference-pose local rotation (a hand in line with
    the forearm) instead of keeping its orientation; ``handle``: its name, as SmartBody's ``sbm:handle``
    (a later constraint of the same handle on the character replaces it)."""

    kind = "ik_constraint"
    layer = Layer.HEAD
    mode = Mode.OVERRIDE
    priority = 1_000
    blend_in_s = 0.3
    blend_out_s = 0.3

    def __init__(self, effector: str, target, offset_m=(0.0, 0.0, 0.0), root: str | None = None,
                 blend_in_s: float | None = None, blend_out_s: float | None = None, purpose: str | None = None,
                 straight_end: bool = False, handle: str | None = None):
        if not isinstance(effector, str) or not effector.strip():
            raise UsageError("an IK constraint names its effector joint")
        self.effector, self.target, self.root = effector.strip(), target, root
        self.purpose = purpose or f"the constraint on {self.effector!r}"
        self.straight_end = bool(straight_end)
        self.handle = handle
        self.offset_m = np.array(check_point(offset_m, "the constraint's offset"))
        for name, value in (("blend_in_s", blend_in_s), ("blend_out_s", blend_out_s)):
            if value is not None:
                if not (np.isfinite(value) and value >= 0):
                    raise UsageError(f"constraint {name} must be >= 0 seconds, got {value}")
                setattr(self, name, float(value))

    def describe(self) -> str:
        return f"ik constraint ({self.effector})"

    def bind(self, rig, report) -> ConstraintBinding:
        end = _joint(rig, self.effector)
        if end is None:
            raise MissingJointsError(rig.character.asset.path, f"{rig.name} has no joint {self.effector!r} (canonical or own name) to constrain")
        canonical = rig.mapping.inverse().get(rig.skeleton.names[end])
        if canonical in LIMBS:
            upper = [rig.joint(n) for n in LIMBS[canonical]]
            top = None if self.root is None else _joint(rig, self.root)
            # A root at or above the limb's top (a clavicle; or one the rig lacks) still moves only the limb.
            if None not in upper and (top is None or top in _ancestors(rig, upper[0])):
                return ConstraintBinding(end=end, limb=(upper[0], upper[1], end),
                                         straight=reference_locals(rig)[end] if self.straight_end else None)
        chain = _chain(rig, end, self.root)
        if not chain:
            raise MissingJointsError(rig.character.asset.path, f"{rig.name}: joint {self.effector!r} has no joint above it to move")
        return ConstraintBinding(end=end, chain=np.array(chain, dtype=np.int64))

    def evaluate_one(self, job, block) -> None:
        b: ConstraintBinding = job.binding
        rig = job.rig
        active = np.nonzero((job.local_times >= -1e-9) & (job.weight > 0))[0]
        if not active.size:
            return
        target = resolve_target(job.activity.runtime, self.target)
        world = target.positions(block.times, block)[active] + self.offset_m
        goal = own_positions(rig, world)
        pose = job.pose
        sk = rig.skeleton
        rot = pose.local_rotations[active].copy()
        root = pose.root_translations[active]
        jt = None if pose.joint_translations is None else pose.joint_translations[active]
        weight = job.weight[active]
        if b.limb is not None:
            solve_limb(sk, rot, root, jt, b.limb, goal, weight=weight, keep_end=b.straight is None,
                       distance=False)
            joints = np.array(b.limb, dtype=np.int64)
            if b.straight is not None:
                end = b.end
                rot[:, end] = quat.slerp(rot[:, end], np.broadcast_to(b.straight, rot[:, end].shape), weight)
        elif b.chain is not None:
            joints = b.chain
            before = rot[:, joints].copy()
            _ccd(sk, rot, root, jt, joints, b.end, goal)
            rot[:, joints] = quat.slerp(before, rot[:, joints], np.broadcast_to(weight[:, None], before.shape[:2]))
        full = pose.local_rotations[:, joints].copy()
        full[active] = rot[:, joints]
        pose.set_rotations(joints, full)
        reached = chain_fk(sk, rot, root, jt, [b.end])[1][:, 0]
        held = weight >= 1.0 - 1e-9
        miss = np.linalg.norm(reached - goal, axis=1)[held]
        state = job.state_of(ConstraintState)
        if miss.size and miss.max() > REACH_TOLERANCE_M and not state.reported:
            state.reported = True
            job.report(f"{self.purpose}: the target is out of reach by up to {miss.max() * 100:.0f} cm")


def _joint(rig, name: str) -> int | None:
    j = rig.joint(name)
    return rig.skeleton.index.get(name) if j is None else j


def _ancestors(rig, joint: int) -> set[int]:
    """``joint`` and every joint above it."""
    out, j = set(), int(joint)
    while j >= 0:
        out.add(j)
        j = int(rig.skeleton.parents[j])
    return out


def _chain(rig, end: int, root_name: str | None) -> list[int]:
    """The joints a chain effector moves, top first: from ``root_name`` (an ancestor) or
    :data:`CHAIN_JOINTS` up, stopping below the pelvis and the root joint."""
    parents = rig.skeleton.parents
    stop = {rig.joint("base"), 0}
    top = None if root_name is None else _joint(rig, root_name)
    if root_name is not None and top is None:
        raise UsageError(f"{rig.name} has no joint {root_name!r} (the constraint's root)")
    chain, j = [], int(parents[end])
    while j >= 0 and j not in stop:
        chain.append(j)
        if (top is None and len(chain) >= CHAIN_JOINTS) or j == top:
            break
        j = int(parents[j])
    if top is not None and top not in chain:
        raise UsageError(f"joint {root_name!r} is not above the effector")
    return chain[::-1]


def _ccd(sk, rot, root, jt, chain, end, goal) -> None:
    """Cyclic coordinate descent (in ``rot``, in place): each joint of ``chain`` from the bottom up turns
    the effector toward ``goal`` (F, 3); vectorized over frames."""
    for _ in range(CCD_PASSES):
        for j in chain[::-1]:
            g_rot, g_pos = chain_fk(sk, rot, root, jt, [int(j), int(end)])
            to_end = g_pos[:, 1] - g_pos[:, 0]
            to_goal = goal - g_pos[:, 0]
            turn = quat.between(to_end, to_goal)  # global
            # global turn T on joint j: L' = L · (G⁻¹ T G), G the joint's global rotation
            local = quat.multiply(quat.conjugate(g_rot[:, 0]), quat.multiply(turn, g_rot[:, 0]))
            rot[:, j] = quat.multiply(rot[:, j], local)
