"""Breathing: a slow, asymmetric rise and fall of the chest and shoulders.

The breath curve b(t) in [0, 1] (0 exhaled, 1 inhaled) is a raised cosine over each cycle of
60 / ``rate_bpm`` seconds, with the inhalation taking ``inhale_fraction`` of it (0.4: breathing
in is quicker than breathing out). At ``depth`` 1 a full breath

- pitches the spine up (it extends): spine1 0.5°, spine2 1°, spine3 2° (whichever exist);
- rolls each clavicle (sternoclavicular, else acromioclavicular) 3° so the shoulders rise;
- pitches the neck (spine4, else skullbase) down by the spine's total, so the head stays level.

Depth scales all of these (default 0.5: a calm breath of about 1° of chest lift).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.controller import table_columns
from infuse.runtime.swing import SWING_AXES, local_axes, local_turns

#: Degrees at depth 1: pitch of each spine joint, roll of the clavicles.
SPINE_PITCH_DEG = {"spine1": 0.5, "spine2": 1.0, "spine3": 2.0}
CLAVICLE_ROLL_DEG = 3.0


def breath_curve(t, rate_bpm: float, inhale_fraction: float = 0.4, phase: float = 0.0) -> np.ndarray:
    """(F,) breath level in [0, 1] at ``t`` seconds: 0 fully exhaled (cycle start), 1 at the end of inhaling."""
    cycle = np.mod(np.asarray(t, dtype=np.float64) * rate_bpm / 60.0 + phase, 1.0)
    # Warp the cycle so that the first ``inhale_fraction`` of it is the rising half of a cosine.
    warped = np.where(cycle < inhale_fraction, 0.5 * cycle / inhale_fraction,
                      0.5 + 0.5 * (cycle - inhale_fraction) / (1.0 - inhale_fraction))
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * warped)


@dataclass(frozen=True, eq=False)
class BreathingBinding:
    """Breathing bound to one character: the ``joints`` (K,) a breath turns (spine, neck, clavicles), each
    about one axis of its aligned frame given in its local frame, ``axes`` (K, 3), by ``angles`` (K,) radians
    at a full breath of depth 1."""

    joints: np.ndarray
    axes: np.ndarray
    angles: np.ndarray


class Breathing(Controller):
    """Breathe at ``rate_bpm`` breaths per minute (default 14) and ``depth`` (0..2, default 0.5);
    ``phase`` (cycles, 0..1) offsets the cycle so characters do not breathe in step."""

    kind = "breathing"
    layer = Layer.POSTURE
    mode = Mode.ADDITIVE
    blend_in_s = 1.0
    blend_out_s = 1.0

    def __init__(self, rate_bpm: float = 14.0, depth: float = 0.5, inhale_fraction: float = 0.4, phase: float = 0.0):
        if not (np.isfinite(rate_bpm) and 1.0 <= rate_bpm <= 60.0):
            raise UsageError(f"breathing rate must lie in [1, 60] breaths per minute, got {rate_bpm}")
        if not (np.isfinite(depth) and 0.0 <= depth <= 2.0):
            raise UsageError(f"breathing depth must lie in [0, 2], got {depth}")
        if not 0.1 <= inhale_fraction <= 0.9:
            raise UsageError("inhale_fraction must lie in [0.1, 0.9]")
        self.rate_bpm, self.depth, self.inhale_fraction, self.phase = float(rate_bpm), float(depth), float(inhale_fraction), float(phase)

    def describe(self) -> str:
        return f"breathing ({self.rate_bpm:g}/min)"

    def bind(self, rig, report) -> BreathingBinding:
        turns: list[tuple[int, float, float, float]] = []  # joint, heading, pitch, roll (degrees)
        for name, degrees in SPINE_PITCH_DEG.items():
            spine = rig.joint(name)
            if spine is not None:
                turns.append((spine, 0.0, degrees, 0.0))
        if not turns:
            raise MissingJointsError(rig.name, "no spine joint is mapped to breathe with")
        neck = rig.joint("spine4") if rig.joint("spine4") is not None else rig.joint("skullbase")
        if neck is not None:  # keep the head level
            turns.append((neck, 0.0, -sum(pitch for _, _, pitch, _ in turns), 0.0))
        clavicles = 0
        for side, sign in (("l", 1.0), ("r", -1.0)):
            joint = rig.joint(f"{side}_sternoclavicular")
            joint = rig.joint(f"{side}_acromioclavicular") if joint is None else joint
            if joint is not None:
                turns.append((joint, 0.0, 0.0, sign * CLAVICLE_ROLL_DEG))
                clavicles += 1
        if clavicles < 2:
            report("clavicles are not mapped; breathing moves the spine only")
        # Each joint turns about one axis of its aligned frame (pitch or roll): a full breath's angle about it.
        joints = [joint for joint, *_ in turns]
        angles = np.radians(np.array([angles for _, *angles in turns]))  # (K, 3)
        axis = np.argmax(np.abs(angles), axis=1)
        return BreathingBinding(joints=np.array(joints), axes=local_axes(rig.aligned[joints], SWING_AXES[axis]),
                                angles=angles[np.arange(len(joints)), axis])

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """Every character's breath at once: the levels (N, F), then the turns of all their joints side by side."""
        batch = jobs.memo(_Batch.of)
        if batch is None:
            return super().evaluate(jobs, block)
        level = batch.depth * breath_curve(jobs.local_times, batch.rate_bpm, batch.inhale_fraction, batch.phase)  # (N, F)
        turns = local_turns(batch.axes, level.T[:, batch.rows] * batch.angles)
        block.table.add_offsets(batch.columns, turns, jobs.weights.T[:, batch.rows], [job.pose for job in jobs])

    def evaluate_one(self, job, block) -> None:
        b: BreathingBinding = job.binding
        level = self.depth * breath_curve(job.local_times, self.rate_bpm, self.inhale_fraction, self.phase)
        job.pose.set_rotations(b.joints, local_turns(b.axes, level[:, None] * b.angles), job.weight, job.mode)


@dataclass(frozen=True, eq=False)
class _Batch:
    """Breathing jobs side by side: per job (N, 1) ``depth``, ``rate_bpm``, ``inhale_fraction``, ``phase``;
    per joint (K,) table ``columns``, the ``rows`` (job) each belongs to, ``axes`` (K, 3) and ``angles``."""

    depth: np.ndarray
    rate_bpm: np.ndarray
    inhale_fraction: np.ndarray
    phase: np.ndarray
    columns: np.ndarray
    rows: np.ndarray
    axes: np.ndarray
    angles: np.ndarray

    @classmethod
    def of(cls, jobs) -> "_Batch | None":
        """The batch of ``jobs``; None unless each is additive on a character of its own."""
        if any(job.mode is not Mode.ADDITIVE for job in jobs):
            return None
        placed = table_columns(jobs, [job.binding.joints for job in jobs])
        if placed is None:
            return None
        settings = np.array([(g.depth, g.rate_bpm, g.inhale_fraction, g.phase) for g in (job.controller for job in jobs)])
        columns, rows = placed
        return cls(depth=settings[:, 0:1], rate_bpm=settings[:, 1:2], inhale_fraction=settings[:, 2:3], phase=settings[:, 3:4],
                   columns=columns, rows=rows, axes=np.concatenate([job.binding.axes for job in jobs]),
                   angles=np.concatenate([job.binding.angles for job in jobs]))


def breathing_from_bml(parameters: dict, runtime, character: str, activation=None) -> Breathing:
    """ASAP's breathing emitter: ``mean_interval_s`` between breaths sets the rate."""
    interval = float(parameters.get("mean_interval_s") or 0.0)
    return Breathing(rate_bpm=float(np.clip(60.0 / interval, 1.0, 60.0)) if interval > 0 else 14.0)


def idle_settings(index: int, seed: int) -> dict:
    """A scene's idle breathing of its ``index``-th character: the resting rate, each character at its own
    phase of the cycle so that they do not breathe in step."""
    return {"phase": (0.37 * index) % 1.0}
