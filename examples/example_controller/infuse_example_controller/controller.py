"""The shrug: both shoulders rise, hold and fall back, on any mapped character.

The lift s(t) in [0, 1] over the shrug's ``duration_s`` seconds rises as a half cosine over the first
``rise_fraction`` of it, holds at 1, and falls as a half cosine over the last ``fall_fraction``. At
``amount`` 1 and the top of the shrug each clavicle (sternoclavicular, else acromioclavicular) rolls
``LIFT_DEG`` up about the character's forward axis, and each upper arm rolls back by as much, so the
arms keep hanging while the shoulders rise. Angles are given in the joints' aligned frames (see
:mod:`infuse.runtime.swing`), so they mean the same on every skeleton.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.swing import local_offsets, swing

#: Clavicle roll at amount 1, degrees.
LIFT_DEG = 15.0


def shrug_curve(t, duration_s: float, rise_fraction: float = 0.25, fall_fraction: float = 0.35) -> np.ndarray:
    """(F,) lift in [0, 1] at ``t`` seconds from the shrug's start; 0 before it and after ``duration_s``."""
    x = np.asarray(t, dtype=np.float64) / duration_s
    rise = 0.5 - 0.5 * np.cos(np.pi * np.clip(x / rise_fraction, 0.0, 1.0))
    fall = 0.5 - 0.5 * np.cos(np.pi * np.clip((1.0 - x) / fall_fraction, 0.0, 1.0))
    return np.where((x >= 0.0) & (x <= 1.0), np.minimum(rise, fall), 0.0)


@dataclass(frozen=True, eq=False)
class ShrugBinding:
    """A shrug bound to one character: the clavicle and upper-arm ``joints`` (K,) it rolls, their ``aligned``
    frames (K, 4), and each one's ``rolls`` (K,) radians at the top of a shrug of amount 1 (+ lifts the left)."""

    joints: np.ndarray
    aligned: np.ndarray
    rolls: np.ndarray


class Shrug(Controller):
    """Shrug both shoulders by ``amount`` (0..1, default 1) over ``duration_s`` seconds (default 1), rising
    over the first ``rise_fraction`` of it and falling over the last ``fall_fraction``."""

    kind = "shrug"
    layer = Layer.POSTURE
    mode = Mode.ADDITIVE
    blend_in_s = 0.0   # the curve itself starts and ends at rest
    blend_out_s = 0.0

    def __init__(self, amount: float = 1.0, duration_s: float = 1.0, rise_fraction: float = 0.25,
                 fall_fraction: float = 0.35):
        if not (np.isfinite(amount) and 0.0 <= amount <= 1.0):
            raise UsageError(f"shrug amount must lie in [0, 1], got {amount}")
        if not (np.isfinite(duration_s) and duration_s > 0.1):
            raise UsageError(f"shrug duration must be over 0.1 s, got {duration_s}")
        if not (0.0 < rise_fraction and 0.0 < fall_fraction and rise_fraction + fall_fraction <= 1.0):
            raise UsageError("shrug rise and fall fractions must be positive and add up to at most 1")
        self.amount = float(amount)
        self.duration_s = float(duration_s)  # an activity given no end lasts this long
        self.rise_fraction, self.fall_fraction = float(rise_fraction), float(fall_fraction)

    def describe(self) -> str:
        return f"shrug ({self.amount:g})"

    def bind(self, rig, report) -> ShrugBinding:
        """Per character: the clavicle and upper-arm joints, and the roll of each."""
        joints, rolls = [], []
        for side, sign in (("l", 1.0), ("r", -1.0)):
            clavicle = rig.joint(f"{side}_sternoclavicular")
            clavicle = rig.joint(f"{side}_acromioclavicular") if clavicle is None else clavicle
            if clavicle is None:
                continue
            joints.append(clavicle)
            rolls.append(sign)
            shoulder = rig.joint(f"{side}_shoulder")
            if shoulder is not None:  # keep the arm hanging
                joints.append(shoulder)
                rolls.append(-sign)
        if not joints:
            raise MissingJointsError(rig.name, "no clavicle is mapped; it cannot shrug")
        if len(joints) < 4:
            report("a clavicle or an upper arm is not mapped; the shrug is partial")
        return ShrugBinding(joints=np.array(joints), aligned=rig.aligned[joints],
                            rolls=np.radians(LIFT_DEG) * np.array(rolls))

    def evaluate_one(self, job, block) -> None:
        """Vectorized over the block's frames: one roll per joint per frame."""
        b: ShrugBinding = job.binding
        lift = self.amount * shrug_curve(job.local_times, self.duration_s, self.rise_fraction, self.fall_fraction)
        roll = lift[:, None] * b.rolls[None, :]  # (F, K)
        offsets = local_offsets(b.aligned, swing(0.0, 0.0, roll))
        job.pose.set_rotations(b.joints, offsets, job.weight, job.mode)


def shrug_from_bml(parameters: dict, runtime, character: str, activation=None) -> Shrug:
    """A shrug from a scheduled BML activation: its ``amount``, and the times the scheduler gave it: at
    the top from ``ready`` to ``relax``, over from ``start`` to ``end``."""
    amount = float(parameters.get("amount", 1.0))
    if activation is None:
        return Shrug(amount, float(parameters.get("duration_s", 1.0)))
    start, end = activation.start, activation.end
    duration = end - start
    ready = activation.time("ready")
    relax = activation.time("relax")
    rise = (ready - start) / duration if ready is not None and duration > 0 else 0.25
    fall = (end - relax) / duration if relax is not None and duration > 0 else 0.35
    return Shrug(amount, duration, max(rise, 1e-3), max(fall, 1e-3))
