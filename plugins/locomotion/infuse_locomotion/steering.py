"""Steering: the speed, turn rate and travel direction asked of the blend, frame by frame.

Either constant or time-varying requests (``speed``, ``turn_rate``, ``direction`` as numbers or
functions of seconds), or a path to follow (ground points, metres, in the character's own frame;
one point is a target to go to). Speed changes are limited to ``max_accel`` / ``max_decel`` m/s²,
turn-rate changes to ``max_turn_accel`` rad/s² and turn rates to ``max_turn_rate``. The steering
is the controller's own and works in radians; :class:`~.controller.Locomotion` takes degrees and
converts them.

Following a path the character **turns, then goes**: the farther a point lies off its facing, the
slower it walks (not at all from :data:`TURN_IN_PLACE` off, where it turns on the spot), and never
faster than the turn rate lets it bend onto the point (the circle through it, tangent to the
facing, has radius d / (2 sin e) for a point d metres away, e off the facing), so it neither
circles a point nor overshoots it. A path ends with a stop on its last point: the speed falls off
as the braking distance runs out, and the character stands once within ``arrive`` metres.
The state (position, heading, speed, turn rate) carries from one block of frames to the next.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Off the facing by this much or more (radians), the character turns on the spot before it walks.
TURN_IN_PLACE = math.radians(75.0)
_COS_TURN_IN_PLACE = math.cos(TURN_IN_PLACE)
#: Turn rate asked per radian off the facing (1/s), before the turn-rate limit.
TURN_GAIN = 3.0
#: A character standing within this many metres of a path's last point stays there.
STAY = 0.15


def of_time(v):
    """A request as a function of time (seconds): ``v`` itself, or a constant."""
    if callable(v):
        return lambda t: float(v(t))
    value = float(v)
    return lambda t: value


@dataclass
class SteeringState:
    """Where the steering has the character: ``x``, ``z`` (m, its own frame), ``heading`` (radians about
    +Y from +Z, + left), ``speed`` (m/s), ``turn`` (rad/s), ``waypoint`` (the path's point it heads for),
    and ``capped`` (asked m/s, realized m/s, direction radians) once a speed was kept to what the pack
    realizes (None before)."""

    x: float = 0.0
    z: float = 0.0
    heading: float = 0.0
    speed: float = 0.0
    turn: float = 0.0
    waypoint: int = 0
    capped: tuple[float, float, float] | None = None

    def go_on_from(self, where: SteeringState) -> None:
        """Stand where ``where`` is, heading, moving and turning as it does (its waypoint left aside)."""
        self.x, self.z, self.heading, self.speed, self.turn = where.x, where.z, where.heading, where.speed, where.turn


@dataclass
class Steering:
    """Steering settings (see the module doc). Angles in radians, speeds m/s, times s."""

    speed: object = 1.3
    turn_rate: object = 0.0
    direction: object = 0.0
    path: np.ndarray | None = None
    max_accel: float = 1.5
    max_decel: float = 2.5
    max_turn_rate: float = math.radians(90.0)
    max_turn_accel: float = math.radians(240.0)
    arrive: float = 0.05
    lookahead: float = 0.6

    def __post_init__(self):
        if self.path is not None:
            p = np.asarray(self.path, dtype=np.float64)
            if p.ndim == 1:
                p = p[None]
            if p.shape[1] == 3:
                p = p[:, [0, 2]]
            if p.shape[1] != 2 or not np.all(np.isfinite(p)):
                raise ValueError("a path is (K, 2) ground points (x, z) or (K, 3) points, metres")
            self.path = p

    def requests(self):
        """The speed, turn rate and direction asked as functions of time (see :func:`of_time`) and the
        path's points as a list of (x, z) (None without a path): made once, again only after a field
        changes (the steering runs once per block, the planner once per frame)."""
        c = self.__dict__.get("_requests")
        if c is None or c[0] is not self.speed or c[1] is not self.turn_rate or c[2] is not self.direction \
                or c[3] is not self.path:
            made = (of_time(self.speed), of_time(self.turn_rate), of_time(self.direction),
                    None if self.path is None else self.path.tolist())
            c = self.__dict__["_requests"] = (self.speed, self.turn_rate, self.direction, self.path, made)
        return c[4]

    def run(self, state: SteeringState, times: np.ndarray, dt: float, top=None) -> np.ndarray:
        """(F, 5) requests (speed, turn rate, direction, stopping, final) for ``times``; updates
        ``state`` (``x``, ``z``, ``heading``, ``speed``, ``turn``, ``waypoint``), integrating the
        requests themselves. ``stopping`` is 1 on the way into a path's last point: braking for it,
        or there; ``final`` is 1 on the way to it, not braking yet. ``top(direction)``: the fastest
        speed (m/s) realizable in a travel direction (radians); a faster speed asked is kept to it and
        ``state.capped`` is set the first time."""
        rows = [self.step(state, t, dt, top) for t in times.tolist()]
        return np.array(rows, dtype=np.float64).reshape(len(rows), 5)

    def step(self, state: SteeringState, t: float, dt: float, top=None) -> tuple[float, float, float, float, float]:
        """One frame of :meth:`run` at time ``t`` (seconds): its request (speed, turn rate, direction,
        stopping, final), ``state`` updated. Plain floats: it runs once per frame, and numpy scalars
        cost more than the maths."""
        x, z, h = float(state.x), float(state.z), float(state.heading)
        v, w = float(state.speed), float(state.turn)
        k = state.waypoint
        speed_at, turn_rate_at, direction_at, path = self.requests()
        accel, decel = self.max_accel * dt, self.max_decel * dt
        turn_accel = self.max_turn_accel * dt
        direction = direction_at(t)
        stopping, last, arrived = 0.0, False, False
        asked = speed_at(t)
        if top is not None:
            limit = top(direction)
            if asked > limit + 1e-3 and state.capped is None:
                state.capped = (asked, limit, direction)
            asked = min(asked, limit)
        if path is None:
            v_goal, w_goal = asked, turn_rate_at(t)
        else:
            # Advance along the path while the next point is within the look-ahead distance.
            last_k = len(path) - 1
            while k < last_k and math.hypot(path[k][0] - x, path[k][1] - z) < max(self.lookahead, 0.5 * v):
                k += 1
            px, pz = path[k]
            dist = math.hypot(px - x, pz - z)
            last = k == last_k
            # There, or standing close by (it stopped there: the blend realizes the steering's
            # motion to a few millimetres, not exactly).
            arrived = last and (dist < self.arrive or (v < 1e-3 and dist < STAY))
            if arrived:
                v_goal, w_goal = 0.0, 0.0
            else:
                want = math.atan2(px - x, pz - z) - direction
                err = (want - h + math.pi) % (2.0 * math.pi) - math.pi
                w_goal = max(-self.max_turn_rate, min(self.max_turn_rate, TURN_GAIN * err))
                ahead = (math.cos(err) - _COS_TURN_IN_PLACE) / (1.0 - _COS_TURN_IN_PLACE)
                v_goal = asked * min(max(ahead, 0.0), 1.0)
                if abs(math.sin(err)) > 1e-6:  # stay on a circle that meets the point
                    v_goal = min(v_goal, self.max_turn_rate * dist / (2.0 * abs(math.sin(err))))
                if last:
                    v_goal = min(v_goal, math.sqrt(2.0 * self.max_decel * max(dist - self.arrive, 0.0)))
            stopping = float(last and (arrived or v_goal < v))
        v += max(-decel, min(accel, v_goal - v))
        w += max(-turn_accel, min(turn_accel, w_goal - w))
        final = float(path is not None and last and not arrived and not stopping)
        h += w * dt
        x += v * math.sin(h + direction) * dt
        z += v * math.cos(h + direction) * dt
        state.x, state.z, state.heading, state.speed, state.turn, state.waypoint = x, z, h, v, w, k
        return v, w, direction, stopping, final
