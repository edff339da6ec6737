"""A gesture aimed at a target: the arm swung about its shoulder so the hand faces the target over the stroke.

The hand faces a target with the axis that faces forward at the gesture's authored stroke: its fingers
(an offer, "this big": the wrist-to-middle-knuckle line) or its palm (a wave, a palm out: the normal of
the plane of the wrist and the index and little knuckles). Each frame the whole arm turns about its
shoulder by the shortest arc taking that axis onto the line from the wrist to the target (twice, the
wrist having moved with the first turn), weighted from nothing at ``ready`` to all of it at
``strokeStart``, held to ``strokeEnd`` and back to nothing at ``relax``. Positions are in the
character's own frame (metres).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from infuse import quaternions as quat
from infuse.runtime import sample_motion
from infuse.runtime.layers import smoothstep
from infuse.runtime.pose import chain_fk
from infuse.runtime.targets import as_target

#: Turns of the arm per frame: the second corrects for the wrist moved by the first.
ITERATIONS = 2


@dataclass(frozen=True)
class AimedArm:
    """One arm a gesture aims: joint indices of its ``shoulder`` (the upper arm) and that joint's
    ``parent``, the ``wrist``, the ``tip`` the fingers point to (the middle knuckle, or the wrist itself
    with the elbow as ``base`` on a rig without fingers), the ``index`` and ``little`` knuckles (None
    without fingers), whether the ``palm`` (not the fingers) faces the target, and ``sign`` (+1 for a
    right hand, -1 for a left) making the knuckles' cross product the palm's normal."""

    shoulder: int
    parent: int
    wrist: int
    base: int
    tip: int
    index: int | None
    little: int | None
    palm: bool
    sign: float

    def joints(self) -> list[int]:
        return [self.parent, self.shoulder, self.base, self.tip] + [j for j in (self.index, self.little) if j is not None]


def _axes(arm: AimedArm, g_pos: np.ndarray, columns: list[int]) -> np.ndarray:
    """(F, 3) the hand's facing axis (unit) from global positions (F, K, 3) of ``columns``."""
    at = {j: g_pos[:, k] for k, j in enumerate(columns)}
    fingers = at[arm.tip] - at[arm.base]
    fingers = fingers / np.maximum(np.linalg.norm(fingers, axis=-1, keepdims=True), 1e-9)
    if not arm.palm:
        return fingers
    normal = arm.sign * np.cross(fingers, at[arm.little] - at[arm.index])
    return normal / np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-9)


def bind_arm(rig, side: str, motion, stroke_s: float) -> AimedArm | None:
    """The :class:`AimedArm` of the ``side`` ("l" or "r") hand of a gesture ``motion`` (its clip on the
    character) whose authored stroke is at ``stroke_s``; None when the arm is not mapped."""
    joint = {name: rig.joint(f"{side}_{name}") for name in ("shoulder", "elbow", "wrist", "middle1", "index1", "pinky1")}
    if joint["shoulder"] is None or joint["wrist"] is None or joint["elbow"] is None:
        return None
    fingers = joint["middle1"] is not None
    hand = fingers and joint["index1"] is not None and joint["pinky1"] is not None
    parent = int(rig.skeleton.parents[joint["shoulder"]])
    arm = AimedArm(joint["shoulder"], parent, joint["wrist"], joint["wrist"] if fingers else joint["elbow"],
                   joint["middle1"] if fingers else joint["wrist"], joint["index1"] if hand else None,
                   joint["pinky1"] if hand else None, False, 1.0 if side == "r" else -1.0)
    if not hand:
        return arm
    rot, root, jt, _ = sample_motion(motion, np.array([stroke_s]), loop=False)
    columns = arm.joints()
    _, g_pos = chain_fk(rig.skeleton, rot, root, jt, columns)
    forward = quat.rotate(rig.body, np.array([0.0, 0.0, 1.0]))
    fingers_forward = float(_axes(arm, g_pos, columns)[0] @ forward)
    palm_forward = float(_axes(replace(arm, palm=True), g_pos, columns)[0] @ forward)
    return replace(arm, palm=palm_forward > fingers_forward)


def aim_weight(local_times: np.ndarray, phases: dict, held: bool) -> np.ndarray:
    """(F,) how much of the turn toward the target is taken at ``local_times`` (F,) seconds from the
    gesture's start; ``held``: kept after the stroke's end (another gesture follows on from it)."""
    up = smoothstep((local_times - phases["ready"]) / max(phases["strokeStart"] - phases["ready"], 1e-6))
    if held:
        return up
    down = 1.0 - smoothstep((local_times - phases["strokeEnd"]) / max(phases["relax"] - phases["strokeEnd"], 1e-6))
    return np.minimum(up, down)


def aim_arms(job, block, arms: tuple[AimedArm, ...], target, weight: np.ndarray) -> None:
    """Turn each arm of ``arms`` about its shoulder in ``job.pose`` so its hand faces ``target`` (a
    runtime target's name, ``"character:joint"``, a point or a Target) by ``weight`` (F,)."""
    rig, pose = job.rig, job.pose
    resolved = job.activity.runtime.target(target) if isinstance(target, str) else as_target(target)
    world = np.broadcast_to(resolved.positions(block.times, block), (len(block.times), 3))
    goal = quat.rotate(quat.conjugate(rig.rotation), world - rig.position)  # (F, 3) own frame
    rot = pose.local_rotations.copy()
    root, jt = pose.root_translations, pose.joint_translations
    for arm in arms:
        columns = arm.joints()
        for _ in range(ITERATIONS):
            g_rot, g_pos = chain_fk(rig.skeleton, rot, root, jt, columns)
            turn = quat.between(_axes(arm, g_pos, columns), goal - g_pos[:, columns.index(arm.wrist)])
            turn = quat.slerp(quat.identity((len(turn),)), turn, weight)
            rot[:, arm.shoulder] = quat.multiply(quat.conjugate(g_rot[:, 0]), quat.multiply(turn, g_rot[:, 1]))
    shoulders = np.array([arm.shoulder for arm in arms], dtype=np.int64)
    pose.set_rotations(shoulders, rot[:, shoulders])
