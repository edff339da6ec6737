"""Blinks: when (human rates per activity) and how (the closure curve), on whatever eyelids a character has.

- Rates (Bentivoglio et al. 1997), blinks per minute: ``rest`` 17, ``conversation`` 26, ``reading`` 4.5.
  Intervals are gamma distributed (shape 3: blinks neither come in bursts nor like a metronome) with
  that mean, never shorter than a blink plus 0.1 s; a seeded generator makes runs repeatable.
- The closure curve (SmartBody): 0 at 0 s, fully closed at 0.083 s, 0.33 at 0.167 s, open at 0.25 s,
  linear in between; ``amount`` scales it.
- Outputs, the first the character has: eyelid morph targets (ARKit / Ready Player Me ``eyeBlinkLeft``
  and ``eyeBlinkRight``, VRM ``blinkLeft``/``blinkRight`` or ``Blink_L``/``Blink_R``, or one ``blink``
  target for both eyes); else eyelid joints (canonical ``upper_eyelid_*``/``lower_eyelid_*``, or joints
  named like upper/lower eyelids), the upper lid pitched down by ``eyelid_angle_deg`` when closed and the
  lower lid up by a third of it. A character with neither is reported once and left alone.
"""
from __future__ import annotations

import re
import zlib
from dataclasses import dataclass

import numpy as np

from infuse.errors import UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.controller import table_columns
from infuse.runtime.swing import local_offsets, swing

RATES_PER_MIN = {"rest": 17.0, "conversation": 26.0, "reading": 4.5}
#: (seconds, closure) points of one blink.
CLOSURE_CURVE = ((0.0, 0.0), (0.083, 1.0), (0.167, 0.33), (0.25, 0.0))
INTERVAL_SHAPE = 3.0

_LEFT_TARGETS = ("eyeBlinkLeft", "blinkLeft", "Blink_L", "EyeBlink_L", "eyeBlink_L", "EyesClosed_L", "eye_close_L")
_RIGHT_TARGETS = ("eyeBlinkRight", "blinkRight", "Blink_R", "EyeBlink_R", "eyeBlink_R", "EyesClosed_R", "eye_close_R")
_BOTH_TARGETS = ("blink", "Blink", "eyeBlink", "eyesClosed", "EyesClosed", "eye_close", "Eye_Blink")


def closure(t, curve=CLOSURE_CURVE) -> np.ndarray:
    """Eyelid closure in [0, 1] at ``t`` seconds from a blink's start (0 outside the blink)."""
    times, values = np.array(curve).T
    t = np.asarray(t, dtype=np.float64)
    return np.where((t >= 0.0) & (t <= times[-1]), np.interp(t, times, values), 0.0)


class BlinkSchedule:
    """Blink start times (seconds from the activity's start), generated on demand from a seed."""

    def __init__(self, mean_interval_s: float, minimum_s: float, seed=None):
        self.mean_interval_s = mean_interval_s
        self.minimum_s = minimum_s
        self.rng = np.random.default_rng(seed)
        self.starts = np.zeros(0)
        self._next = float(self._intervals(1)[0] * self.rng.uniform())  # the first blink comes part way into an interval

    def _intervals(self, n: int) -> np.ndarray:
        scale = self.mean_interval_s / INTERVAL_SHAPE
        return np.maximum(self.rng.gamma(INTERVAL_SHAPE, scale, n), self.minimum_s)

    def until(self, t_s: float) -> np.ndarray:
        """Every blink start up to ``t_s`` seconds."""
        while self._next <= t_s:
            steps = np.cumsum(self._intervals(64))
            new = self._next + np.concatenate(([0.0], steps[:-1]))
            self.starts = np.concatenate((self.starts, new))
            self._next = float(self._next + steps[-1])
        return self.starts

    def around(self, t_s: float) -> tuple[float, float]:
        """Seconds of the last blink start at or before ``t_s`` (-inf: none) and of the first after it."""
        starts = self.until(t_s)
        k = int(np.searchsorted(starts, t_s, side="right"))
        return (float(starts[k - 1]) if k else -np.inf), (float(starts[k]) if k < len(starts) else self._next)


@dataclass(frozen=True, eq=False)
class EyelidJoints:
    """Eyelid joints a blink pitches: ``joints`` (K,), their ``aligned`` frames (K, 4) and ``pitch`` (K,)
    radians of each lid when fully closed (upper lids down, lower lids up)."""

    joints: np.ndarray
    aligned: np.ndarray
    pitch: np.ndarray


@dataclass(frozen=True, eq=False)
class BlinkBinding:
    """Blinks bound to one character: its own ``schedule`` of blinks, the eyelid ``morphs`` (morph columns,
    left and right or one for both; empty when it has none) and its eyelid ``lids`` (None when morphs close
    the eyes, or when it has neither)."""

    schedule: BlinkSchedule
    morphs: tuple[int, ...] = ()
    lids: EyelidJoints | None = None


class Blink(Controller):
    """Blink at a human rate: ``activity`` (rest, conversation, reading) or ``rate_per_min``;
    ``seed`` for the random intervals; ``amount`` (0..1) how far the lids close."""

    kind = "blink"
    layer = Layer.FACE
    mode = Mode.ADDITIVE
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, activity: str = "rest", rate_per_min: float | None = None, seed: int | None = 0,
                 amount: float = 1.0, eyelid_angle_deg: float = 30.0, curve=CLOSURE_CURVE):
        if rate_per_min is None:
            if activity not in RATES_PER_MIN:
                raise UsageError(f"blink activity {activity!r}: expected one of {', '.join(RATES_PER_MIN)}")
            rate_per_min = RATES_PER_MIN[activity]
        if not (np.isfinite(rate_per_min) and 0.1 <= rate_per_min <= 120):
            raise UsageError(f"blink rate must lie in [0.1, 120] per minute, got {rate_per_min}")
        if not 0.0 <= amount <= 1.0:
            raise UsageError("blink amount must lie in [0, 1]")
        self.activity, self.rate_per_min, self.seed = activity, float(rate_per_min), seed
        self.amount, self.eyelid_angle_deg, self.curve = float(amount), float(eyelid_angle_deg), tuple(curve)
        self.blink_s = float(self.curve[-1][0])

    def describe(self) -> str:
        return f"blink ({self.rate_per_min:g}/min)"

    def bind(self, rig, report) -> BlinkBinding:
        # Each character draws its own blinks from the seed, so a crowd does not blink in step.
        seed = None if self.seed is None else (int(self.seed), zlib.crc32(rig.name.encode("utf-8")))
        schedule = BlinkSchedule(60.0 / self.rate_per_min, self.blink_s + 0.1, seed)
        left, right = rig.morph_named(*_LEFT_TARGETS), rig.morph_named(*_RIGHT_TARGETS)
        if left and right:
            return BlinkBinding(schedule, morphs=(rig.morph_index[left], rig.morph_index[right]))
        both = rig.morph_named(*_BOTH_TARGETS)
        if both:
            return BlinkBinding(schedule, morphs=(rig.morph_index[both],))
        lids = _eyelid_joints(rig)
        if lids:
            joints = np.array([j for j, _ in lids])
            pitch = np.radians([self.eyelid_angle_deg * share for _, share in lids])
            return BlinkBinding(schedule, lids=EyelidJoints(joints=joints, aligned=rig.aligned[joints], pitch=pitch))
        report("has no eyelid morph targets or joints: blinks are not shown")
        return BlinkBinding(schedule)

    def level(self, schedule: BlinkSchedule, t: np.ndarray) -> np.ndarray | None:
        """(F,) eyelid closure at ``t`` (F,) seconds from the activity's start, ``amount`` included; None
        when no blink falls on them (the closure is 0)."""
        starts = schedule.until(float(t[-1]))
        # The blinks that may overlap the times (sorted starts: a slice), then exactly those that do.
        starts = starts[np.searchsorted(starts, t[0] - self.blink_s - 1e-6):np.searchsorted(starts, t[-1], side="right")]
        starts = starts[(starts <= t[-1]) & (starts + self.blink_s >= t[0])]
        if not len(starts):
            return None
        level = np.zeros(len(t))
        for start in starts:  # at most a few blinks fall in a block
            level = np.maximum(level, closure(t - start, self.curve))
        level *= self.amount
        return level

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """Every character's blinks at once: the closure (N, F), then the eyelid morph targets and joints
        of all characters side by side."""
        batch = jobs.memo(_Batch.of)
        if batch is None:
            return super().evaluate(jobs, block)
        level = np.zeros(jobs.local_times.shape)
        closed = False
        for n, job in enumerate(jobs):
            times, quiet = job.local_times, job.state_of(BlinkQuiet)
            if quiet.after_s < times[0] and times[-1] < quiet.before_s:
                continue  # no blink falls on these times
            closing = job.controller.level(job.binding.schedule, times)
            if closing is not None:
                level[n], closed = closing, True
            last, following = job.binding.schedule.around(float(times[-1]))
            quiet.after_s, quiet.before_s = last + job.controller.blink_s, following
        table = block.table
        if not closed:  # every eye open: adding nothing leaves the pose as it is (morph weights stay in [0, 1])
            table.morph_written[batch.morph_columns] = True
            return
        level, weight = level.T, jobs.weights.T  # (F, N)
        table.set_morphs(batch.morph_columns, level[:, batch.morph_rows], weight[:, batch.morph_rows], Mode.ADDITIVE)
        if batch.lid_columns.size:
            angles = level[:, batch.lid_rows] * batch.lid_pitch
            table.add_offsets(batch.lid_columns, local_offsets(batch.lid_aligned, swing(np.zeros_like(angles), angles)),
                              weight[:, batch.lid_rows], [job.pose for job in jobs])

    def evaluate_one(self, job, block) -> None:
        b: BlinkBinding = job.binding
        t = job.local_times
        level = self.level(b.schedule, t)
        level = np.zeros(len(t)) if level is None else level
        if b.morphs:
            values = np.repeat(level[:, None], len(b.morphs), axis=1)
            job.pose.set_morphs(b.morphs, values, job.weight, job.mode)
        if b.lids is not None:
            angles = level[:, None] * b.lids.pitch[None]
            delta = swing(np.zeros_like(angles), angles)
            job.pose.set_rotations(b.lids.joints, local_offsets(b.lids.aligned, delta), job.weight, job.mode)


@dataclass
class BlinkQuiet:
    """When an activity's eyelids are still open, kept from block to block: after ``after_s`` (the last
    blink's end) and before ``before_s`` (the next blink's start), seconds from the activity's start."""

    after_s: float = np.inf
    before_s: float = -np.inf


@dataclass(frozen=True, eq=False)
class _Batch:
    """Blink jobs side by side: the table's eyelid morph columns (K,) and the job of each (K,); the
    table's eyelid joints (L,), the job of each, their aligned frames (L, 4) and closed pitch (L,)."""

    morph_columns: np.ndarray
    morph_rows: np.ndarray
    lid_columns: np.ndarray
    lid_rows: np.ndarray
    lid_aligned: np.ndarray
    lid_pitch: np.ndarray

    @classmethod
    def of(cls, jobs) -> "_Batch | None":
        """The batch of ``jobs``; None unless each is additive on a character of its own."""
        if any(job.mode is not Mode.ADDITIVE for job in jobs):
            return None
        morphs = table_columns(jobs, [job.binding.morphs for job in jobs], morphs=True)
        lids = [job.binding.lids for job in jobs]
        joints = table_columns(jobs, [np.zeros(0, dtype=np.int64) if b is None else b.joints for b in lids])
        if morphs is None or joints is None:
            return None
        present = [b for b in lids if b is not None]
        return cls(*morphs, *joints, np.concatenate([b.aligned for b in present]) if present else np.zeros((0, 4)),
                   np.concatenate([b.pitch for b in present]) if present else np.zeros(0))


def _eyelid_joints(rig) -> list[tuple[int, float]]:
    """(joint, pitch share) of the eyelids: upper lids close downward (-1), lower lids upward (+1/3)."""
    found = []
    for canonical, share in (("upper_eyelid_left", -1.0), ("upper_eyelid_right", -1.0),
                             ("lower_eyelid_left", 1 / 3), ("lower_eyelid_right", 1 / 3)):
        if rig.joint(canonical) is not None:
            found.append((rig.joint(canonical), share))
    if found:
        return found
    for index, name in enumerate(rig.skeleton.names):  # the mapping may leave these optional joints out
        key = name.lower()
        if re.search(r"eye_?lid|(?:^|[_.\-\s:|])lid(?:$|[_.\-\s])", key) and not re.search(r"(end|tip|nub)$", key):
            if "upper" in key or "up" in re.split(r"[_.\-\s]", key) or "top" in key:
                found.append((index, -1.0))
            elif "lower" in key or "low" in re.split(r"[_.\-\s]", key) or "bottom" in key:
                found.append((index, 1 / 3))
    return found


def blink_from_bml(parameters: dict, runtime, character: str, activation=None) -> Blink:
    """ASAP's blink emitter: ``mean_interval_s`` between blinks sets the rate (else the resting rate)."""
    interval = float(parameters.get("mean_interval_s") or 0.0)
    return Blink(rate_per_min=float(np.clip(60.0 / interval, 0.1, 120.0)) if interval > 0 else None)


def idle_settings(index: int, seed: int) -> dict:
    """A scene's idle blinking of its ``index``-th character: conversational rate, each character its own
    draw of intervals from the scene's ``seed``."""
    return {"activity": "conversation", "seed": seed + 101 * index}
