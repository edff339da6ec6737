"""The saccade model (Lee, Badler and Badler 2002, "Eyes Alive") as data and a seeded event generator.

- Magnitude A (degrees) = -6.9 ln(f / 15.7), f uniform in [0, 15), at most 10 (listening) or 12
  (talking, thinking).
- Direction (degrees, 0 = the character's right, 90 = up): one of eight 45-degree bins with the
  published frequencies, uniform within the bin (centred on the bin angle).
- Duration D = 25 ms + 2.4 ms/degree × the movement's amplitude; the eyes follow the ease-out
  weight sqrt(1 - (r - 1)²), r the elapsed share of D.
- Gaze state and interval: after each saccade the eyes are in mutual gaze (on the gaze target) with
  the mode's probability, else away; the time to the next saccade is Gaussian (mean, spread, in
  frames at 30 fps) for that state, drawn again when below :data:`MIN_INTERVAL_FRAMES`.

A saccade away moves the eyes to (A, direction) from the gaze direction; a saccade to mutual gaze
brings them back to it. The *think* mode is not in the published tables: infuse takes the talking
magnitudes, 20% mutual gaze, long fixations away (the listening mode's mutual fixations) and short
glances back (the talking mode's away fixations).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DIRECTION_BINS_DEG = np.arange(0.0, 360.0, 45.0)
DIRECTION_PERCENT = np.array([15.54, 6.46, 17.69, 7.44, 16.80, 7.89, 20.38, 7.79])
FRAMES_PER_S = 30.0  # the unit of the published interval statistics
MIN_INTERVAL_FRAMES = 2.0
MAGNITUDE_SCALE_DEG = 6.9
MAGNITUDE_F_MAX = 15.0
MAGNITUDE_F_REF = 15.7
DURATION_BASE_S = 0.025
DURATION_PER_DEG_S = 0.0024


@dataclass(frozen=True)
class SaccadeMode:
    """One mode: the share of mutual gaze, the (mean, spread) interval in frames at 30 fps after a
    saccade into mutual gaze and away, and the largest magnitude in degrees."""

    mutual_fraction: float
    mutual_frames: tuple[float, float]
    away_frames: tuple[float, float]
    max_magnitude_deg: float


MODES: dict[str, SaccadeMode] = {
    "talk": SaccadeMode(0.41, (93.9, 94.9), (27.8, 24.0), 12.0),
    "listen": SaccadeMode(0.75, (237.5, 47.1), (13.0, 7.1), 10.0),
    "think": SaccadeMode(0.20, (27.8, 24.0), (237.5, 47.1), 12.0),
}


def magnitude_cdf(a, max_magnitude_deg: float) -> np.ndarray:
    """P(A <= a) of the model's magnitude (degrees), the clamp at ``max_magnitude_deg`` included."""
    a = np.asarray(a, dtype=np.float64)
    f = MAGNITUDE_F_REF * np.exp(-a / MAGNITUDE_SCALE_DEG)  # A <= a  <=>  f >= this
    cdf = np.clip((MAGNITUDE_F_MAX - f) / MAGNITUDE_F_MAX, 0.0, 1.0)
    return np.where(a >= max_magnitude_deg, 1.0, cdf)


def direction_cdf(theta_deg) -> np.ndarray:
    """P(direction <= theta) for directions measured from -22.5 degrees (the right bin's lower edge)
    to 337.5 degrees; bins are uniform within themselves."""
    theta = np.asarray(theta_deg, dtype=np.float64)
    p = DIRECTION_PERCENT / DIRECTION_PERCENT.sum()
    edges = np.concatenate(([-22.5], DIRECTION_BINS_DEG + 22.5))
    return np.interp(theta, edges, np.concatenate(([0.0], np.cumsum(p))))


class SaccadeSchedule:
    """Saccade events of one mode, generated on demand from a seed.

    Arrays (one entry per saccade): ``times`` (seconds from the start), ``mutual`` (bool, the gaze
    state it leads to), ``magnitudes`` and ``directions`` (degrees, drawn for every saccade; used by
    saccades away), ``offsets`` (heading, pitch) in degrees from the gaze direction (heading positive
    to the character's left), ``amplitudes`` (degrees moved), ``durations`` (seconds) and
    ``intervals`` (seconds to the next saccade).
    """

    def __init__(self, mode: SaccadeMode, seed=None, max_magnitude_deg: float | None = None):
        self.mode = mode
        self.max_magnitude_deg = mode.max_magnitude_deg if max_magnitude_deg is None else float(max_magnitude_deg)
        self.rng = np.random.default_rng(seed)
        self.times = np.zeros(0)
        self.mutual = np.zeros(0, dtype=bool)
        self.magnitudes = np.zeros(0)
        self.directions = np.zeros(0)
        self.offsets = np.zeros((0, 2))
        self.amplitudes = np.zeros(0)
        self.durations = np.zeros(0)
        self.intervals = np.zeros(0)
        first = self._intervals(np.array([self.rng.uniform() < mode.mutual_fraction]))[0]
        self._next_time = float(first * self.rng.uniform())  # start part way into a fixation
        self._last_offset = np.zeros(2)

    # -- draws ---------------------------------------------------------------------------------------
    def draw_magnitudes(self, n: int) -> np.ndarray:
        f = self.rng.uniform(0.0, MAGNITUDE_F_MAX, n)
        a = -MAGNITUDE_SCALE_DEG * np.log(np.maximum(f, 1e-300) / MAGNITUDE_F_REF)
        return np.minimum(a, self.max_magnitude_deg)

    def draw_directions(self, n: int) -> np.ndarray:
        p = DIRECTION_PERCENT / DIRECTION_PERCENT.sum()
        bins = self.rng.choice(len(p), size=n, p=p)
        return np.mod(DIRECTION_BINS_DEG[bins] + self.rng.uniform(-22.5, 22.5, n), 360.0)

    def _intervals(self, mutual: np.ndarray) -> np.ndarray:
        """Seconds to the next saccade after reaching each state (Gaussian in frames, redrawn below the minimum)."""
        mean = np.where(mutual, self.mode.mutual_frames[0], self.mode.away_frames[0])
        spread = np.where(mutual, self.mode.mutual_frames[1], self.mode.away_frames[1])
        frames = self.rng.normal(mean, spread)
        low = frames < MIN_INTERVAL_FRAMES
        while np.any(low):
            frames[low] = self.rng.normal(mean[low], spread[low])
            low = frames < MIN_INTERVAL_FRAMES
        return frames / FRAMES_PER_S

    def _extend(self, n: int = 256) -> None:
        mutual = self.rng.uniform(size=n) < self.mode.mutual_fraction
        magnitudes = self.draw_magnitudes(n)
        directions = self.draw_directions(n)
        rad = np.radians(directions)
        away = np.stack((-magnitudes * np.cos(rad), magnitudes * np.sin(rad)), axis=1)  # heading + is left
        offsets = np.where(mutual[:, None], 0.0, away)
        previous = np.vstack((self._last_offset, offsets[:-1]))
        amplitudes = np.linalg.norm(offsets - previous, axis=1)
        intervals = self._intervals(mutual)
        times = self._next_time + np.concatenate(([0.0], np.cumsum(intervals[:-1])))
        self._next_time = float(times[-1] + intervals[-1])
        self._last_offset = offsets[-1]
        for name, values in (("times", times), ("mutual", mutual), ("magnitudes", magnitudes), ("directions", directions),
                             ("offsets", offsets), ("amplitudes", amplitudes), ("durations", saccade_duration(amplitudes)),
                             ("intervals", intervals)):
            setattr(self, name, np.concatenate((getattr(self, name), values)))

    def until(self, t_s: float) -> int:
        """Generate saccades up to ``t_s`` seconds; returns how many there are."""
        while self._next_time <= t_s:
            self._extend()
        return len(self.times)

    def next_after(self, t_s: float) -> float:
        """Seconds of the first saccade after ``t_s`` (generated as needed)."""
        count = self.until(t_s)
        after = int(np.searchsorted(self.times[:count], t_s, side="right"))
        return float(self.times[after]) if after < count else self._next_time

    def sample(self, n: int) -> "SaccadeSchedule":
        """Generate at least ``n`` saccades (for statistics); returns self."""
        while len(self.times) < n:
            self._extend()
        return self


def saccade_duration(amplitude_deg) -> np.ndarray:
    """Seconds a saccade of ``amplitude_deg`` takes: 25 ms + 2.4 ms per degree."""
    return DURATION_BASE_S + DURATION_PER_DEG_S * np.asarray(amplitude_deg, dtype=np.float64)


def ease_out(r) -> np.ndarray:
    """Share of a saccade's way covered after the share ``r`` of its duration: sqrt(1 - (r - 1)²)."""
    r = np.minimum(np.maximum(np.asarray(r, dtype=np.float64), 0.0), 1.0)  # np.clip, at half its cost on a few values
    return np.sqrt(1.0 - (r - 1.0) ** 2)
