"""The saccade controller: quick eye jumps around the gaze direction, per :mod:`infuse_saccade.model`.

It runs in the GAZE layer after the gaze (a higher priority), moving the eyes from wherever the gaze
left them, and keeps them within the eye limits (heading 40°, pitch 35° up and down by default).
While the character speaks (:meth:`Runtime.speech_intervals`) and for ``resume_s`` (2 s) after, it
makes no saccades: the eyes return to the gaze direction when speech starts.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.controller import table_columns
from infuse.runtime.swing import EllipseClamp, clamp_ellipse, swing, swing_angles

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

    def events(self, schedule: SaccadeSchedule, t_last: float, pauses=()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The saccades the eyes make up to ``t_last`` seconds from the start, with none inside ``pauses``
        ((start, end) seconds) and a return to the gaze direction at each pause start: times (E,), the
        offsets (E, 2) (heading, pitch) degrees each moves to, and those it starts from (E, 2)."""
        count = schedule.until(t_last)
        times, offsets = schedule.times[:count], schedule.offsets[:count]
        keep = times <= t_last
        if len(pauses):
            starts, ends = np.asarray(pauses, dtype=np.float64).reshape(-1, 2).T
            keep &= ~np.any((times >= starts[:, None]) & (times < ends[:, None]), axis=0)
        back = np.array([s for s, e in pauses if s <= t_last])
        times = np.concatenate((times[keep], back))
        offsets = np.concatenate((offsets[keep], np.zeros((len(back), 2))))
        order = np.argsort(times, kind="stable")
        times, offsets = times[order], offsets[order]
        return times, offsets, np.concatenate((np.zeros((1, 2)), offsets[:-1]))

    def offsets(self, schedule: SaccadeSchedule, t: np.ndarray, pauses=()) -> np.ndarray:
        """(F, 2) eye offsets (heading, pitch) in degrees at ``t`` seconds from the start, with no
        saccade inside ``pauses`` ((start, end) seconds) and a return to the gaze direction at each pause start."""
        times, offsets, before = self.events(schedule, float(t[-1]), pauses)
        if len(times) == 0:
            return np.zeros((len(t), 2))
        durations = saccade_duration(np.hypot(*(offsets - before).T))
        last = np.searchsorted(times, t, side="right") - 1
        started = last >= 0
        k = np.maximum(last, 0)
        progress = ease_out((t - times[k]) / durations[k])[:, None]
        return np.where(started[:, None], before[k] + progress * (offsets[k] - before[k]), 0.0)

    def follow(self, state: "SaccadeState", schedule: SaccadeSchedule, t: np.ndarray, pauses: list) -> np.ndarray | None:
        """The eye offsets at ``t`` as :meth:`offsets`, (F, 2) degrees, when the saccade ``state`` holds
        for them is not enough to say them (then ``state`` is brought up to their last time); None
        when it is (:meth:`SaccadeState.path` gives them)."""
        first, last = float(t[0]), float(t[-1])
        if state.pauses == pauses and state.start_s <= first and last < state.until_s:
            return None
        times, offsets, before = self.events(schedule, last, pauses)
        k = int(np.searchsorted(times, last, side="right")) - 1
        later = [s for s, _ in pauses if s > last]
        state.pauses, state.until_s = pauses, min([schedule.next_after(last)] + later)
        if k < 0:
            state.start_s, state.offset, state.before, state.duration_s = -np.inf, np.zeros(2), np.zeros(2), np.ones(1)
        else:
            state.start_s, state.offset, state.before = float(times[k]), offsets[k], before[k]
            state.duration_s = saccade_duration(np.hypot(*(offsets[k:k + 1] - before[k:k + 1]).T))
        state.held = (state.start_s, float(state.duration_s[0]), *state.offset.tolist(), *state.before.tolist())
        return self.offsets(schedule, t, pauses)

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """Every character's saccades at once: each one's last saccade events looked up (a few
        operations per character), then the eye turns of all characters side by side."""
        batch = jobs.memo(_Batch.of)
        if batch is None:
            return super().evaluate(jobs, block)
        if not batch.seeing:  # no character with eyes
            return
        speaking = block.runtime.speaking()
        # Each character's saccade in progress, where it holds for the whole block (else the path itself).
        held, paths = [], {}
        for n, k in enumerate(batch.seeing):
            job = jobs[k]
            start, saccades, state = job.activity.start_s, job.controller, job.state_of(SaccadeState)
            pauses = [(s - start, e - start + saccades.resume_s) for s, e in speaking.get(job.rig.name, ())]
            path = saccades.follow(state, job.binding.schedule, job.local_times, pauses)
            held.append(state.held)
            if path is not None:
                paths[n] = path
        times = jobs.local_times[batch.seeing]
        degrees = batch.over.path(held, times)
        if paths:
            degrees = np.array(degrees)
        for n, path in paths.items():
            degrees[n] = path
        radians = np.radians(degrees) * jobs.weights[batch.seeing][..., None]  # (N', F, 2)
        rows = batch.rows
        turn = _apply_per_eye(batch.to_turn, block.table.local_rotations[:, batch.columns])
        heading, pitch, roll = swing_angles(turn)
        heading, pitch = batch.clamp(heading + radians[rows, :, 0].T, pitch + radians[rows, :, 1].T)
        block.table.set_rotations(batch.columns, _apply_per_eye(batch.from_turn, swing(heading, pitch, roll)), None,
                                  Mode.OVERRIDE, [jobs[k].pose for k in batch.seeing])

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


@dataclass(eq=False)
class SaccadeState:
    """The saccade a character's eyes follow, kept from block to block while nothing changes it: it
    started at ``start_s`` seconds from the activity's start (-inf: none yet; the eyes stay on the gaze),
    moves from ``before`` to ``offset`` ((heading, pitch) degrees) over ``duration_s`` (1,) seconds, and
    holds until ``until_s`` (the next saccade or pause), as long as the ``pauses`` stay as they are;
    ``held``: the same as a row of :meth:`path`'s ``held``."""

    pauses: list | None = None
    until_s: float = -np.inf
    start_s: float = np.inf
    duration_s: np.ndarray = field(default_factory=lambda: np.ones(1))
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))
    before: np.ndarray = field(default_factory=lambda: np.zeros(2))
    held: tuple = (-np.inf, 1.0, 0.0, 0.0, 0.0, 0.0)

    @staticmethod
    def path(held: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(N, F, 2) offsets in degrees at ``t`` (N, F) seconds of N saccades in progress, ``held`` (N, 6):
        start (-inf: none, 0 offsets), duration, offset (2) and the offset before (2); as
        :meth:`Saccades.offsets` works them out. A row of no duration (a placeholder, or a saccade of
        none) is at its offset from its start on: no division by zero, no NaN."""
        start, duration = held[:, :1], held[:, 1:2]
        offset, before = held[:, None, 2:4], held[:, None, 4:6]
        elapsed = t - start
        share = np.divide(elapsed, duration, out=np.where(elapsed >= 0.0, 1.0, 0.0), where=duration > 0.0)
        progress = ease_out(share)[..., None]
        return np.where(np.isfinite(start)[..., None], before + progress * (offset - before), 0.0)


class _Over:
    """The offsets (N, 2) degrees that saccades whose way is over hold, kept with what says those saccades
    (``held``, the rows of :meth:`SaccadeState.path`) while every one of them is over: a block in which no
    eye moves (most blocks) takes them as they are."""

    def __init__(self):
        self.held: list | None = None
        self.offsets = np.zeros((0, 2))

    def path(self, held: list, times: np.ndarray) -> np.ndarray:
        """:meth:`SaccadeState.path` of ``held`` (N rows of 6) at ``times`` (N, F) seconds, (N, F, 2) degrees (read
        only when kept)."""
        if held == self.held and all(_over(row, t) for row, t in zip(held, times[:, 0].tolist())):
            return np.broadcast_to(self.offsets[:, None], times.shape + (2,))
        degrees = SaccadeState.path(np.array(held, dtype=np.float64).reshape(-1, 6), times)
        over = all(_over(row, t) for row, t in zip(held, times[:, -1].tolist()))
        self.held, self.offsets = (held, degrees[:, -1].copy()) if over else (None, self.offsets)
        return degrees


def _over(row: tuple, t: float) -> bool:
    """Whether the saccade of ``row`` (a row of :meth:`SaccadeState.path`'s ``held``) is over at ``t`` seconds
    and ever after (none yet: its offsets are 0), as :meth:`SaccadeState.path` works out its share of the way."""
    start, duration = row[0], row[1]
    if not np.isfinite(start):
        return True
    return (t - start) / duration >= 1.0 if duration > 0.0 else t - start >= 0.0


@dataclass(frozen=True, eq=False)
class _Batch:
    """Saccade jobs side by side: ``seeing`` (N',) the jobs whose characters have eyes; per eye (K = 2 N')
    its table ``columns``, its job among ``seeing`` (``rows``), ``to_turn`` and ``from_turn`` (K, 4, 4)
    and the ``clamp`` of its limits: (heading, up, down) radians, each (K,)."""

    seeing: list
    columns: np.ndarray
    rows: np.ndarray
    to_turn: np.ndarray
    from_turn: np.ndarray
    clamp: EllipseClamp
    over: _Over = field(default_factory=_Over)

    @classmethod
    def of(cls, jobs) -> "_Batch | None":
        """The batch of ``jobs``; None when two share a character."""
        seeing = [k for k, job in enumerate(jobs) if job.binding is not None]
        chosen = [jobs[k] for k in seeing]
        placed = table_columns(jobs, [np.zeros(0, dtype=np.int64) if job.binding is None else job.binding.eyes for job in jobs])
        if placed is None:
            return None
        columns, rows = placed
        rows = np.searchsorted(seeing, rows)  # from jobs to the jobs that see
        if not chosen:
            return cls(seeing, columns, rows, np.zeros((0, 4, 4)), np.zeros((0, 4, 4)), EllipseClamp(*(np.zeros(0),) * 3))
        limits = np.concatenate([np.repeat(job.controller.eye_limits[None], len(job.binding.eyes), axis=0) for job in chosen])
        return cls(seeing, columns, rows, np.concatenate([job.binding.to_turn for job in chosen]),
                   np.concatenate([job.binding.from_turn for job in chosen]), EllipseClamp(*limits.T))


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
