"""The saccade controller: quick eye jumps around the gaze direction, per :mod:`infuse_saccade.model`.

It runs in the GAZE layer after the gaze (a higher priority), moving the eyes from wherever the gaze
left them, and keeps them within the eye limits (heading 40°, pitch 35° up and down by default).
While the character speaks (:meth:`Runtime.speech_intervals`) and for ``resume_s`` (2 s) after, it
makes no saccades: the eyes return to the gaze direction when speech starts.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.swing import clamp_ellipse, swing, swing_angles

from .model import MODES, SaccadeSchedule, ease_out, saccade_duration

RESUME_S = 2.0


@dataclass(frozen=True, eq=False)
class SaccadeBinding:
    """Saccades bound to one character: its ``eyes`` (2,) joints, left then right, its own ``schedule`` of
    saccades, and per eye the (4, 4) matrices on (x, y, z, w) columns taking a local rotation to its turn from
    rest in the eye's aligned frame, ``to_turn`` (2, 4, 4), and back, ``from_turn`` (2, 4, 4)."""

    eyes: np.ndarray
    schedule: SaccadeSchedule
    to_turn: np.ndarray
    from_turn: np.ndarray


class Saccades(Controller):
    """Saccades in ``mode`` talk, listen or think (see the model); ``seed`` makes them repeatable
    (each character draws its own from it); ``max_magnitude_deg`` overrides the mode's limit;
    ``eye_limits_deg`` = (heading, up, down)."""

    kind = "saccade"
    layer = Layer.GAZE
    mode = Mode.ADDITIVE
    priority = 10  # after the gaze, whose eye direction it moves around
    blend_in_s = 0.2
    blend_out_s = 0.2

    def __init__(self, mode: str = "talk", seed: int | None = 0, max_magnitude_deg: float | None = None,
                 eye_limits_deg=(40.0, 35.0, 35.0), resume_s: float = RESUME_S):
        if mode not in MODES:
            raise UsageError(f"saccade mode {mode!r}: expected one of {', '.join(MODES)}")
        if max_magnitude_deg is not None and not (np.isfinite(max_magnitude_deg) and max_magnitude_deg > 0):
            raise UsageError("the saccade magnitude limit must be a positive number of degrees")
        self.saccade_mode = mode
        self.seed = seed
        self.max_magnitude_deg = max_magnitude_deg
        self.eye_limits = np.radians(np.asarray(eye_limits_deg, dtype=np.float64))
        self.resume_s = float(resume_s)

    def describe(self) -> str:
        return f"saccades ({self.saccade_mode})"

    def schedule(self, character: str = "") -> SaccadeSchedule:
        """The saccade events this controller plays for ``character`` (reproducible from the seed)."""
        seed = None if self.seed is None else (int(self.seed), zlib.crc32(character.encode("utf-8")))
        return SaccadeSchedule(MODES[self.saccade_mode], seed, self.max_magnitude_deg)

    def bind(self, rig, report) -> SaccadeBinding | None:
        eyes = [rig.joint("eyeball_left"), rig.joint("eyeball_right")]
        if None in eyes:
            report("has no eyes: saccades are not shown")
            return None
        aligned, rest = rig.aligned[eyes], rig.skeleton.rest_rotations[eyes]
        # Both ways between an eye's local rotation L and its turn T from rest in its aligned frame A are
        # linear in the quaternion's components: T = A⁻¹ rest⁻¹ L A and L = rest A T A⁻¹, (2, 4, 4)
        # matrices acting on (x, y, z, w) columns.
        placed = quat.multiply(rest, aligned)  # rest A
        return SaccadeBinding(eyes=np.array(eyes), schedule=self.schedule(rig.name),
                              to_turn=quat.left_matrix(quat.conjugate(placed)) @ quat.right_matrix(aligned),
                              from_turn=quat.left_matrix(placed) @ quat.right_matrix(quat.conjugate(aligned)))

    def offsets(self, schedule: SaccadeSchedule, t: np.ndarray, pauses=()) -> np.ndarray:
        """(F, 2) eye offsets (heading, pitch) in degrees at ``t`` seconds from the start, with no
        saccade inside ``pauses`` ((start, end) seconds) and a return to the gaze direction at each pause start."""
        count = schedule.until(float(t[-1]))
        times, offsets = schedule.times[:count], schedule.offsets[:count]
        keep = times <= t[-1]
        if len(pauses):
            starts, ends = np.asarray(pauses, dtype=np.float64).reshape(-1, 2).T
            keep &= ~np.any((times >= starts[:, None]) & (times < ends[:, None]), axis=0)
        back = np.array([s for s, e in pauses if s <= t[-1]])
        times = np.concatenate((times[keep], back))
        offsets = np.concatenate((offsets[keep], np.zeros((len(back), 2))))
        order = np.argsort(times, kind="stable")
        times, offsets = times[order], offsets[order]
        if len(times) == 0:
            return np.zeros((len(t), 2))
        before = np.concatenate((np.zeros((1, 2)), offsets[:-1]))
        durations = saccade_duration(np.hypot(*(offsets - before).T))
        last = np.searchsorted(times, t, side="right") - 1
        started = last >= 0
        k = np.maximum(last, 0)
        progress = ease_out((t - times[k]) / durations[k])[:, None]
        return np.where(started[:, None], before[k] + progress * (offsets[k] - before[k]), 0.0)

    def evaluate_one(self, job, block) -> None:
        b: SaccadeBinding | None = job.binding
        if b is None:
            return
        start = job.activity.start_s
        pauses = [(s - start, e - start + self.resume_s) for s, e in block.runtime.speech_intervals(job.rig.name)]
        offsets = np.radians(self.offsets(b.schedule, job.local_times, pauses)) * job.weight[:, None]
        # The eyes' current turn from rest (the gaze's), in their aligned frames, plus the saccade.
        turn = _apply_per_eye(b.to_turn, job.pose.local_rotations[:, b.eyes])
        heading, pitch, roll = swing_angles(turn)
        heading, pitch = clamp_ellipse(heading + offsets[:, :1], pitch + offsets[:, 1:], *self.eye_limits)
        job.pose.set_rotations(b.eyes, _apply_per_eye(b.from_turn, swing(heading, pitch, roll)))


def _apply_per_eye(matrices: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Matrices (2, 4, 4), one per eye, times quaternions (F, 2, 4) (columns): one product per eye."""
    return np.swapaxes(np.swapaxes(q, 0, 1) @ np.swapaxes(matrices, -1, -2), 0, 1)


def saccade_from_bml(parameters: dict, runtime, character: str, activation=None) -> Saccades | None:
    """SmartBody's ``<saccade mode=... finish=...>``: ``finish`` stops the character's running saccades at
    the activation's start and plays nothing (None)."""
    if parameters.get("enabled") is False:
        at = activation.start if activation is not None else None
        for activity in runtime.activities:
            if activity.rig.name == character and isinstance(activity.controller, Saccades) and activity.end_s is None:
                runtime.stop(activity, at)
        return None
    return Saccades(parameters.get("mode") or "talk", max_magnitude_deg=parameters.get("angle_limit_deg"))
