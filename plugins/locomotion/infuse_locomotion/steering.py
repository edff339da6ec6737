"""Steering: the speed, turn rate and travel direction asked of the blend, frame by frame.

Either constant or time-varying requests (``speed``, ``turn_rate``, ``direction`` as numbers or
functions of seconds), or a path to follow (ground points, metres, in the character's own frame;
one point is a target to go to). Speed changes are limited to ``max_accel`` / ``max_decel`` m/s²,
turn-rate changes to ``max_turn_accel`` rad/s²; a path ends with a stop on its last point.
The state (position, heading, speed, turn rate) carries from one block of frames to the next.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def _value(v, t: float) -> float:
    return float(v(t)) if callable(v) else float(v)


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

    def run(self, state: dict, times: np.ndarray, dt: float) -> np.ndarray:
        """(F, 3) requests (speed, turn rate, direction) for ``times``; updates ``state`` (``x``, ``z``,
        ``heading``, ``speed``, ``turn``, ``waypoint``), integrating the requests themselves."""
        out = np.empty((len(times), 3))
        x, z, h = state["x"], state["z"], state["heading"]
        v, w = state["speed"], state["turn"]
        k = state.get("waypoint", 0)
        for i, t in enumerate(times):
            direction = _value(self.direction, t)
            if self.path is None:
                v_goal, w_goal = _value(self.speed, t), _value(self.turn_rate, t)
            else:
                # Advance along the path while the next point is within the look-ahead distance.
                while k < len(self.path) - 1 and math.hypot(self.path[k, 0] - x, self.path[k, 1] - z) < max(self.lookahead, 0.5 * v):
                    k += 1
                px, pz = self.path[k]
                dist = math.hypot(px - x, pz - z)
                want = math.atan2(px - x, pz - z) - direction
                err = (want - h + math.pi) % (2.0 * math.pi) - math.pi
                w_goal = max(-self.max_turn_rate, min(self.max_turn_rate, 2.5 * err))
                v_goal = _value(self.speed, t) * max(0.25, math.cos(min(abs(err), math.pi / 2)))
                if k == len(self.path) - 1:
                    v_goal = min(v_goal, math.sqrt(2.0 * self.max_decel * max(dist - self.arrive, 0.0)))
                    if dist < self.arrive:
                        w_goal = 0.0
            v += max(-self.max_decel * dt, min(self.max_accel * dt, v_goal - v))
            w += max(-self.max_turn_accel * dt, min(self.max_turn_accel * dt, w_goal - w))
            out[i] = (v, w, direction)
            h += w * dt
            x += v * math.sin(h + direction) * dt
            z += v * math.cos(h + direction) * dt
        state.update(x=x, z=z, heading=h, speed=v, turn=w, waypoint=k)
        return out
