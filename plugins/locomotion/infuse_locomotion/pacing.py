"""Pacing a walk's last strides so that its stop clip begins on time: at the clip's gait phase, with as
far left to go as the clip travels.

A stop clip (:mod:`.transitions`) begins at one gait phase, and the walk reaches that phase once a
stride; at a fixed cadence the distance left then is wherever the walk's start put it, so a clip
whose travel may be scaled by :data:`~.transitions.STOP_SCALES` either way fits only if that window
is longer than a stride. Instead, on its way to its last point the walk changes its cadence, its
speed kept: its steps grow shorter and quicker (up to :data:`FASTER`) or longer and slower (down to
:data:`SLOWER`), so that the stop's phase comes where the distance left is the clip's travel
(scaled by at most :data:`SCALES` either way; a walk that lines up already keeps its cadence). Of
the strides to go the walk takes the whole number that needs the least change, and works it out
again every frame from the phase it is at (a factor once chosen holds: the distance and the phase
left both shrink at its rate). A walk still speeding up (from standing, after a turn on the spot) is
paced for the steps it will take as it does: up to the speed it is asked for at the steering's
acceleration, its cadence rising with its speed, not at the speed it has now (a short walk covers
most of its way speeding up, in shorter steps than it ends with). The controller shortens or
lengthens the steps by leg IK (:meth:`~.controller.Locomotion._shorten`).

Phases are cycles (left strike 0, right strike 0.5), distances metres, speeds m/s, times seconds.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import transitions

#: Least and greatest cadence factor (phase rate over the blend's at that speed, the speed kept): the
#: steps are shorter by its inverse. Quicker, shorter steps are easier than longer ones.
FASTER = 1.45
SLOWER = 0.9
#: A walk is paced while its last point lies within this (radians) of its facing: it turns onto it
#: within the strides paced (the stop itself begins within :data:`~.transitions.STOP_BEARING`).
BEARING = math.radians(45.0)
#: The stop clip's travel may be scaled by up to this either way where pacing brings it (a margin within
#: :data:`~.transitions.STOP_SCALES`).
SCALES = 1.15


@dataclass
class StopPacing:
    """What pacing needs: the stops' gait phases at their start ``phases`` (K,), the ground travel of
    each to where the steering takes over ``travels`` (K,) m, their speeds at their start ``speeds``
    (K,) m/s; the straight walk's cadence (cycles per second) ``cadences`` (S,) at speeds ``grid``
    (S,) m/s; ``phase``, the walk's gait phase where it is asked for a factor; ``accel``, the
    steering's acceleration (m/s²) up to the speed the walk is asked for."""

    phases: np.ndarray
    travels: np.ndarray
    speeds: np.ndarray
    grid: np.ndarray
    cadences: np.ndarray
    phase: float = 0.0
    accel: float = math.inf

    def cadence(self, speed: float) -> float:
        """Cycles per second of the straight walk at ``speed`` m/s."""
        return float(np.interp(speed, self.grid, self.cadences))

    def cycles_over(self, speed: float, cruise: float, dist: np.ndarray) -> np.ndarray:
        """Cycles (at the blend's own cadence) the walk steps over the next ``dist`` (D,) metres, going
        at ``speed`` m/s and speeding up to ``cruise`` m/s at :attr:`accel` (D,)."""
        dist = np.asarray(dist, dtype=np.float64)
        if cruise <= speed + 1e-6 or not math.isfinite(self.accel):
            return dist * self.cadence(speed) / speed
        v = np.linspace(speed, cruise, 33)
        run = (v * v - speed * speed) / (2.0 * self.accel)  # metres to each speed
        rate = np.interp(v, self.grid, self.cadences) / self.accel  # cycles per m/s gained
        cycles = np.concatenate(([0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(v))))
        return np.where(dist <= run[-1], np.interp(dist, run, cycles),
                        cycles[-1] + (dist - run[-1]) * self.cadence(cruise) / cruise)

    def factor(self, speed: float, dist: float, bearing: float, cruise: float | None = None) -> float:
        """The cadence factor for a walk at ``speed`` m/s (speeding up to ``cruise`` m/s, if faster)
        with ``dist`` m to its last point, ``bearing`` radians off its facing: for the stop begun nearest
        the speed it will have, where it heads for the point within :data:`BEARING` and will walk at
        about that stop's speed (:data:`~.transitions.STOP_SPEEDS`); 1 where no stop fits (too near
        already)."""
        if speed <= 1e-6 or self.phases.size == 0 or abs(bearing) >= BEARING:
            return 1.0
        cruise = speed if cruise is None else max(float(cruise), speed)
        ratios = np.abs(np.log(np.maximum(self.speeds, 1e-9) / cruise))
        k = int(np.argmin(ratios))
        if ratios[k] >= math.log(transitions.STOP_SPEEDS):
            return 1.0
        travel = float(self.travels[k])
        # Metres left to where the stop may begin, the clip's travel scaled within SCALES either way.
        most, least = dist - travel / SCALES, dist - travel * SCALES
        if most <= 0.0:
            return 1.0
        # Cycles the walk steps (at the blend's own cadence) to where the stop may begin.
        c_most, c_least = (float(c) for c in self.cycles_over(speed, cruise, np.array([most, max(least, 0.0)])))
        if c_most <= 1e-9:
            return 1.0
        to_phase = (float(self.phases[k]) - self.phase) % 1.0
        # Strides to go (whole ones beyond the next time it passes the phase): the factors that bring
        # it there with as far left as the scaled clip travels, within the cadence's bounds; the
        # nearest 1 of them (1 itself where it lines up already).
        n = np.arange(int(c_most * FASTER) + 2)
        cycles = to_phase + n
        low = np.maximum(cycles / c_most, SLOWER)
        high = np.minimum(cycles / c_least, FASTER) if c_least > 0.0 else np.full(len(n), FASTER)
        fits = np.nonzero(low <= high)[0]
        if not fits.size:
            return 1.0
        nearest = np.clip(1.0, low[fits], high[fits])
        return float(nearest[np.argmin(np.abs(np.log(nearest)))])

    def factors(self, speed: np.ndarray, dist: np.ndarray, bearing: np.ndarray, phase: float, advance: np.ndarray,
                cruise: np.ndarray | None = None) -> np.ndarray:
        """(F,) each frame's cadence factor (:meth:`factor`; 1 where ``speed`` (F,) is 0: not on the
        way to the last point), from the gait's ``phase`` at the first frame, each frame's phase
        carried on by its ``advance`` (F,) (the blend's, cycles) times its factor: frame by frame,
        as the factor turns on the phase it is at. ``dist`` (F,) m, ``bearing`` (F,) radians,
        ``cruise`` (F,) m/s the speed asked (default ``speed``)."""
        out = np.ones(len(speed))
        for j in np.flatnonzero(speed > 0.0).tolist():
            self.phase = (phase + float(np.dot(out[:j], advance[:j]))) % 1.0
            out[j] = self.factor(float(speed[j]), float(dist[j]), float(bearing[j]), None if cruise is None else float(cruise[j]))
        return out


def straight_cadences(periods: np.ndarray, slow: np.ndarray) -> np.ndarray:
    """Cycles per second of a straight walk from the blend's cycle durations
    ``periods`` (S,) s and moving shares ``slow`` (S,) (below the slowest walk the cadence falls with
    their square root)."""
    return np.sqrt(np.clip(slow, 0.0, 1.0)) / np.maximum(periods, 1e-3)


def pacing_for(stops: list, fps: float, grid: np.ndarray, cadences: np.ndarray, phase: float,
               accel: float = math.inf, marks: list[tuple[float | None, float]] | None = None) -> StopPacing | None:
    """A :class:`StopPacing` for the stop clips ``stops`` (whose phase at their start is known) at
    ``fps``, with the straight walk's ``cadences`` (S,) at speeds ``grid`` (S,), from the gait's
    ``phase``, the walk speeding up at ``accel`` m/s²; None without stops. ``marks``: each stop's
    phase at its start and travel (m) at ``fps`` where already known (else worked out here)."""
    if not stops:
        return None
    if marks is None:
        marks = [(transitions.stop_phase(c), transitions.stop_travel(c, fps)) for c in stops]
    return StopPacing(phases=np.array([m[0] for m in marks]), travels=np.array([m[1] for m in marks]),
                      speeds=np.array([c.parameters["speed_start"] for c in stops]), grid=np.asarray(grid),
                      cadences=np.asarray(cadences), phase=float(phase), accel=float(accel))

