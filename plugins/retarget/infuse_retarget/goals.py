"""Where the target's feet and hands should be: the goals the limb IK enforces.

- :func:`warp` is the paper's trajectory warping, ``p'(0) = p(0)``,
  ``p'(t + δt) = p'(t) + s·(p_s(t + δt) − p_s(t))``, i.e. ``p(0) + s·(p_s(t) − p_s(0))``.
- :func:`pinned` goes beyond it: while the source foot point is planted the target point is held
  exactly still, and between contacts the correction this needs glides from one contact to the
  next (smoothstep in time), so nothing pops.
- :func:`reach` scales a hand's offset from its shoulder by the arm-length ratio as the arm
  straightens, so a reaching hand reaches as far, relative to its arm, as the source's.

Positions are component-major (3, F) world metres, +Y up, over all frames at once.
"""
from __future__ import annotations

import numpy as np

from infuse.contacts import contact_runs


def smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def warp(start: np.ndarray, source: np.ndarray, scale: float) -> np.ndarray:
    """The paper's warped trajectory (3, F): ``start + scale · (source(t) − source(0))``."""
    return start[:, None] + scale * (source - source[:, :1])


def _neighbours(inside: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each frame, the nearest frame at or before / at or after it where ``inside`` is True (-1 /
    F when there is none)."""
    f = len(inside)
    idx = np.arange(f)
    prev = np.maximum.accumulate(np.where(inside, idx, -1))
    nxt = np.minimum.accumulate(np.where(inside, idx, f)[::-1])[::-1]
    return prev, nxt


def glide(values: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """``values`` (3, F) kept where ``inside`` (F,) holds and smoothstep-interpolated across the gaps
    between such frames (held flat before the first and after the last); zeros if none holds."""
    if not inside.any():
        return np.zeros_like(values)
    prev, nxt = _neighbours(inside)
    f = len(inside)
    lo = np.where(prev >= 0, prev, nxt)
    hi = np.where(nxt < f, nxt, prev)
    w = smoothstep((np.arange(f) - lo) / np.maximum(hi - lo, 1))
    return values[:, lo] * (1.0 - w) + values[:, hi] * w


def weight_near(inside: np.ndarray, frames: float) -> np.ndarray:
    """(F,) 1 where ``inside`` holds, falling smoothly to 0 ``frames`` frames away from it."""
    if not inside.any():
        return np.zeros(len(inside))
    prev, nxt = _neighbours(inside)
    f = len(inside)
    idx = np.arange(f)
    dist = np.minimum(np.where(prev >= 0, idx - prev, f), np.where(nxt < f, nxt - idx, f)).astype(np.float64)
    return smoothstep(1.0 - dist / max(frames, 1e-9))


def planted(heights: np.ndarray, flags: np.ndarray) -> float:
    """The height (m) a point rests at while planted: median over planted frames, else (a point
    that never touches down, a sprinter's heel) its 5th percentile."""
    return float(np.median(heights[flags]) if flags.any() else np.percentile(heights, 5.0))


def _pins(warped: np.ndarray, flags: np.ndarray, height: float) -> np.ndarray:
    """(3, F) one held position per contact run (mean warped XZ, ``height`` Y); other columns unused."""
    pins = np.array(warped)
    for _, a, b in contact_runs(flags[:, None]):
        pins[[0, 2], a:b] = warped[[0, 2], a:b].mean(axis=1, keepdims=True)
        pins[1, a:b] = height
    return pins


def pinned(
    warped_ankle: np.ndarray,
    ankle_flags: np.ndarray,
    ankle_height: float,
    warped_ball: np.ndarray | None = None,
    ball_flags: np.ndarray | None = None,
    ball_height: float = 0.0,
    foot_length: float = 0.0,
    blend_frames: float = 4.0,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Goals (3, F) for an ankle and (optionally) the ball of the same foot.

    ``warped_*``: the warped trajectories; ``*_flags`` (F,) planted frames of the source point;
    ``*_height``: world Y at which each point rests when planted; ``foot_length``: ankle-to-ball
    distance of the target foot. Each planted run is pinned at one position (mean warped XZ); the
    offset from the warped path glides between runs. A ball planted while the ankle is too gets a
    pin exactly ``foot_length`` from the ankle's, in the direction the foot points, so both hold at
    once; while only the ball is planted the ankle goal is kept ``foot_length`` from it, with a
    smooth ramp of ``blend_frames`` frames around the ball's contacts.
    """
    ankle_goal = warped_ankle + glide(_pins(warped_ankle, ankle_flags, ankle_height) - warped_ankle, ankle_flags)
    if warped_ball is None:
        return ankle_goal, None
    ball_pins = _pins(warped_ball, ball_flags, ball_height)
    drop = ankle_height - ball_height
    across = np.sqrt(max(foot_length * foot_length - drop * drop, 0.0))
    for _, a, b in contact_runs(ball_flags[:, None]):
        both = ankle_flags[a:b]
        if not both.any():
            continue
        k = a + int(np.argmax(both))
        direction = (warped_ball[[0, 2], a:b] - warped_ankle[[0, 2], a:b])[:, both].mean(axis=1)
        size = np.linalg.norm(direction)
        if size > 1e-9:
            ball_pins[[0, 2], a:b] = (ankle_goal[[0, 2], k] + across * direction / size)[:, None]
    ball_goal = warped_ball + glide(ball_pins - warped_ball, ball_flags)
    w = weight_near(ball_flags, blend_frames) * ~ankle_flags  # a pinned ankle stays pinned
    away = ankle_goal - ball_goal
    on_sphere = ball_goal + foot_length * away / np.maximum(np.sqrt(np.sum(away * away, axis=0)), 1e-12)
    return ankle_goal * (1.0 - w) + on_sphere * w, ball_goal


def reach(shoulder: np.ndarray, source_shoulder: np.ndarray, source_wrist: np.ndarray, transferred_wrist: np.ndarray,
          ratio: float, source_arm: float, start: float = 0.75, full: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wrist goals (3, F) for per-limb scaling by extension, and their weights (F,).

    The source wrist's offset from its shoulder, times the arm-length ``ratio``, placed at the
    target ``shoulder``; weighted in from extension ``start`` to ``full`` (wrist distance over arm
    length ``source_arm``), so relaxed arms keep the transferred pose and reaching arms reach.
    """
    offset = source_wrist - source_shoulder
    extension = np.sqrt(np.sum(offset * offset, axis=0)) / max(source_arm, 1e-9)
    w = smoothstep((extension - start) / max(full - start, 1e-9))
    return transferred_wrist * (1.0 - w) + (shoulder + ratio * offset) * w, w
