"""What a locomotion blend space can realize: speed limits by travel direction, and a coverage table.

A request is a speed (m/s), a travel direction off the facing (radians, + left) and a turn rate (rad/s,
+ left). Its point (velocity along and across the facing, turn rate) is inside the tessellation's hull
or not. The controller realizes any turn rate exactly (what the clips do not show is spun at the
root) and any speed below the slowest example in a direction (a slower cadence with shorter steps),
so what a pack limits is the **top speed** in each direction: above it a request is approximated.

- :func:`speed_limits`: the top speed, and the slowest speed the examples show, in each direction;
- :func:`coverage`: a speed x turn x direction table of which requests the blend shows as they are
  (inside the hull), which it realizes by spinning the root (the turn cut down) or by slowing the
  slowest walk, and which it cannot (faster than the top speed);
- :func:`describe_coverage`: that table as text, turn rates in degrees per second.
"""
from __future__ import annotations

import bisect
import math

import numpy as np

#: Travel directions of the coverage table, degrees (+ left).
DIRECTIONS_DEG = (0.0, 45.0, 90.0, 135.0, 180.0, -135.0, -90.0, -45.0)
#: Turn rates of the coverage table, degrees per second (+ left).
TURNS_DEG_S = (-90.0, -45.0, 0.0, 45.0, 90.0)
#: A line meets a hull of one point when it passes this close to it, in shares of the point's
#: distance from zero (at least one unit).
POINT_TOLERANCE = 0.02
#: Turn rates over the examples' range at which the speed limits are found.
TURN_SAMPLES = 25


class Hull:
    """The hull of a tessellation's examples as half-spaces ``A y + c <= 0`` in its reduced space, for
    exact intervals along lines of requests (the hull is convex, so a line meets it in one interval)."""

    def __init__(self, tessellation):
        self.t = tessellation
        y = tessellation.reduced(tessellation.points)
        d = tessellation.dimension
        if d == 0:
            self.normals, self.offsets = np.zeros((0, 0)), np.zeros(0)
        elif d == 1:
            self.normals = np.array([[1.0], [-1.0]])
            self.offsets = np.array([-y[:, 0].max(), y[:, 0].min()])
        else:
            from scipy.spatial import ConvexHull, QhullError

            try:
                eq = ConvexHull(y).equations
            except QhullError:
                eq = ConvexHull(y, qhull_options="QJ").equations
            self.normals, self.offsets = eq[:, :-1], eq[:, -1]

    def interval(self, base, along) -> tuple[np.ndarray, np.ndarray]:
        """(Q,) lowest and highest ``s`` with ``base + s * along`` inside the hull, for (Q, D) ``base``
        and (Q, D) or (D,) ``along`` in the tessellation's coordinates; lowest > highest where the line
        misses the hull (with no spread at all, the hull is the examples' point, which a line meets
        when it passes within :data:`POINT_TOLERANCE` of its size)."""
        base = np.atleast_2d(np.asarray(base, dtype=np.float64))
        t = self.t
        if t.dimension == 0:  # one example (or several alike): the line's nearest approach, if it passes by
            along = np.broadcast_to(np.asarray(along, dtype=np.float64), base.shape)
            gap = t.points.mean(axis=0) - base
            s = (gap * along).sum(axis=1) / np.maximum((along * along).sum(axis=1), 1e-12)
            miss = np.linalg.norm(gap - s[:, None] * along, axis=1)
            hit = miss <= POINT_TOLERANCE * max(float(np.linalg.norm(t.points.mean(axis=0))), 1.0)
            return np.where(hit, s, np.inf), np.where(hit, s, -np.inf)
        y0 = t.reduced(base)  # (Q, d)
        g = (np.broadcast_to(np.asarray(along, dtype=np.float64), base.shape) / t.scale) @ t.basis  # (Q, d)
        rate = g @ self.normals.T  # (Q, H)
        room = -(y0 @ self.normals.T + self.offsets) + 1e-9  # rate * s <= room
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = room / rate
        hi = np.where(rate > 1e-12, bound, np.inf).min(axis=1)
        lo = np.where(rate < -1e-12, bound, -np.inf).max(axis=1)
        blocked = ((np.abs(rate) <= 1e-12) & (room < 0.0)).any(axis=1)
        return np.where(blocked, np.inf, lo), np.where(blocked, -np.inf, hi)

    def nearest_turns(self, velocity, turn) -> tuple[np.ndarray, np.ndarray]:
        """For (Q, 2) velocities (along, across the facing; m/s) and (Q,) turn rates (rad/s): the turn
        rates nearest them inside the hull at those velocities (just inside its boundary), and (Q,)
        flags of the velocities the hull holds at some turn rate (elsewhere the turn rate is returned
        as it is). For a locomotion tessellation (coordinates forward speed, lateral speed, turn rate)."""
        v = np.atleast_2d(np.asarray(velocity, dtype=np.float64))
        turn = np.asarray(turn, dtype=np.float64)
        base = np.zeros((len(v), 3))
        base[:, :2] = v
        if self.t.dimension == 0:
            lo, hi = self.interval(base, np.array([0.0, 0.0, 1.0]))
        else:  # :meth:`interval` along the turn rate, with what depends on the hull alone worked out once
            normals, offsets, rate, up, down = self._turning()
            room = -(self.t.reduced(base) @ normals + offsets) + 1e-9  # (Q, H): rate * turn <= room
            hi = np.minimum.reduce(room[:, :up] / rate[:up], axis=1, initial=np.inf)
            lo = np.maximum.reduce(room[:, up:down] / rate[up:down], axis=1, initial=-np.inf)
            if down < len(rate):
                blocked = np.logical_or.reduce(room[:, down:] < 0.0, axis=1)
                lo, hi = np.where(blocked, np.inf, lo), np.where(blocked, -np.inf, hi)
        ok = lo <= hi
        margin = 1e-6 * np.minimum(np.abs(hi - lo), 1.0)  # only read where ok
        return np.where(ok, np.minimum(np.maximum(turn, lo + margin), hi - margin), turn), ok  # a clip, for less

    def _turning(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
        """The half-spaces ordered by how the turn rate moves them, as :meth:`interval` tells them apart: those
        it raises, those it lowers, those it leaves level; their normals (d, H) and offsets (H,), how fast each
        one's value grows with the turn rate (H,) (per rad/s, in the reduced space), and where the lowered and
        the level ones begin (made once)."""
        cached = self.__dict__.get("_cached_turning")
        if cached is None:
            rate = ((np.array([0.0, 0.0, 1.0]) / self.t.scale) @ self.t.basis) @ self.normals.T
            up, down = rate > 1e-12, rate < -1e-12
            order = np.concatenate((np.flatnonzero(up), np.flatnonzero(down), np.flatnonzero(np.abs(rate) <= 1e-12)))
            cached = self.__dict__["_cached_turning"] = (self.normals[order].T, self.offsets[order], rate[order],
                                                         int(up.sum()), int(up.sum() + down.sum()))
        return cached


def speed_limits(tessellation, directions, turn: float | None = None, hull: Hull | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(K,) top and (K,) lowest speeds (m/s, at least 0) inside the hull of a locomotion ``tessellation``
    for travel ``directions`` (K,) radians at turn rate ``turn`` rad/s (None: at any turn rate, the
    rest of a turn being spun at the root); both 0 where no speed is inside. ``hull``: its
    :class:`Hull`, if already made."""
    d = np.atleast_1d(np.asarray(directions, dtype=np.float64))
    hull = Hull(tessellation) if hull is None else hull
    along = np.stack((np.cos(d), np.sin(d), np.zeros_like(d)), axis=-1)
    if turn is not None:
        base = np.zeros((len(d), 3))
        base[:, 2] = turn
        lo, hi = hull.interval(base, along)
    else:  # over the examples' turn rates: the (speed, turn) slice is convex, so its speeds are an interval
        turns = np.unique(np.concatenate((np.linspace(*_turn_range(tessellation), TURN_SAMPLES), [0.0])))
        base = np.zeros((len(d), len(turns), 3))
        base[..., 2] = turns
        lo, hi = hull.interval(base.reshape(-1, 3), np.repeat(along, len(turns), axis=0))
        lo, hi = lo.reshape(len(d), -1), hi.reshape(len(d), -1)
        hit = np.maximum(lo, 0.0) <= hi
        lo = np.where(hit, lo, np.inf).min(axis=1)
        hi = np.where(hit, hi, -np.inf).max(axis=1)
    lo = np.maximum(lo, 0.0)
    hit = lo <= hi
    return np.where(hit, np.minimum(hi, 1e3), 0.0), np.where(hit, lo, 0.0)


def _turn_range(tessellation) -> tuple[float, float]:
    w = tessellation.points[:, 2]
    return float(w.min()), float(w.max())


class SpeedLimit:
    """The top speed of a locomotion tessellation as a function of the travel direction (radians),
    interpolated over :data:`SAMPLES` directions, and the lowest speed its examples show; ``hull``
    its :class:`Hull`."""

    SAMPLES = 72

    def __init__(self, tessellation):
        self.hull = Hull(tessellation)
        self.directions = np.linspace(-math.pi, math.pi, self.SAMPLES + 1)
        self.top, self.low = speed_limits(tessellation, self.directions, hull=self.hull)
        # Plain floats for one direction at a time (the steering asks once per frame): np.interp's
        # arithmetic on Python floats, without its per-call overhead.
        self._directions, self._top, self._low = self.directions.tolist(), self.top.tolist(), self.low.tolist()
        self._last = (math.nan, 0.0)  # the last direction asked and its top speed: a walk asks one all along

    def __call__(self, direction: float) -> float:
        last = self._last  # one read: a walk planned on another thread may ask at the same time
        if last[0] == direction:
            return last[1]
        top = self._at(direction, self._top)
        self._last = (direction, top)
        return top

    def lowest(self, direction: float) -> float:
        """The slowest speed (m/s) the examples show in ``direction`` (radians); 0 with an idle."""
        return self._at(direction, self._low)

    def _at(self, direction: float, values: list[float]) -> float:
        """``values`` (one per direction of :attr:`directions`) interpolated at ``direction`` (radians,
        wrapped to [-pi, pi)), as ``np.interp`` does it."""
        d = (float(direction) + math.pi) % (2.0 * math.pi) - math.pi
        xs = self._directions
        j = bisect.bisect_right(xs, d) - 1
        if j < 0:
            return values[0]
        if j >= len(xs) - 1:
            return values[-1]
        if xs[j] == d:
            return values[j]
        return (values[j + 1] - values[j]) / (xs[j + 1] - xs[j]) * (d - xs[j]) + values[j]


def coverage(tessellation) -> dict:
    """The coverage table: for each direction of :data:`DIRECTIONS_DEG` and turn rate of
    :data:`TURNS_DEG_S`, the speeds (m/s) the blend shows as asked (``shown``: lowest, top) and the top
    speed of the direction at any turn (``top``, the turn then partly spun at the root)."""
    shown: list[list[list[float]]] = []
    out = {"directions_deg": list(DIRECTIONS_DEG), "turns_deg_s": list(TURNS_DEG_S), "shown": shown, "top": []}
    d = np.radians(DIRECTIONS_DEG)
    top, _ = speed_limits(tessellation, d)
    out["top"] = top.tolist()
    for w in TURNS_DEG_S:
        hi, lo = speed_limits(tessellation, d, math.radians(w))
        shown.append([[float(a), float(b)] for a, b in zip(lo, hi)])
    return out


def describe_coverage(table: dict) -> list[str]:
    """Lines of text for a :func:`coverage` table."""
    dirs = table["directions_deg"]
    lines = ["coverage: top speed (m/s) by travel direction (deg, + left); faster requests are approximated",
             "    " + "".join(f"{d:>+11.0f}" for d in dirs),
             "    " + "".join(f"{t:>11.2f}" for t in table["top"]),
             "  speeds shown by the blend as asked (m/s) by turn rate (deg/s, + left); others turn the root:"]
    for w, row in zip(table["turns_deg_s"], table["shown"]):
        cells = "".join(f"{'-':>11}" if hi <= 0.0 else f"{lo:>5.2f}-{hi:<5.2f}" for lo, hi in row)
        lines.append(f"    {w:>+5.0f} " + cells)
    return lines
