"""Evaluation layers, composition modes and blend weights.

Each frame a character's pose is built bottom-up: every layer starts from the pose the layers
below left, and within a layer controllers apply in order of priority (lowest first, so the highest
has the last word), then of activation.
"""
from __future__ import annotations

import enum

import numpy as np


class Layer(enum.IntEnum):
    """Where a controller acts, in evaluation order."""

    BASE = 1      # base motion and blends (clips, walking)
    POSTURE = 2   # posture and gestures (the chest, the arms, gestures)
    GAZE = 3      # where the eyes, head and spine look
    HEAD = 4      # head movements (nod, shake, toss, tilt)
    FACE = 5      # face: blinks, lip sync, expressions (morph weights and face joints)


class Mode(str, enum.Enum):
    """How a controller's output meets the pose below it.

    - ``OVERRIDE``: the output replaces the pose, blended by the activity's weight (slerp);
    - ``ADDITIVE``: the output is an offset applied on top of the pose (a local rotation post-multiplied,
      a translation or morph weight added), scaled by the weight.
    """

    OVERRIDE = "override"
    ADDITIVE = "additive"


def clamp(x, low, high) -> np.ndarray:
    """``x`` clipped to [``low``, ``high``], as ``np.clip`` clips it (NaN stays NaN), at half its fixed cost
    per call: what evaluating blocks of one frame, a few values at a time, pays for."""
    return np.minimum(np.maximum(x, low), high)


def smoothstep(x) -> np.ndarray:
    """3x² - 2x³ of ``x`` clipped to [0, 1]: a ramp with zero slope at both ends."""
    x = clamp(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def blend_weights(times, start_s: float, end_s: float | None, blend_in_s: float, blend_out_s: float) -> np.ndarray:
    """(F,) weights in [0, 1] of an activity at ``times`` (seconds).

    The weight is 0 before ``start_s``, ramps up over ``blend_in_s``, and ramps down to 0 at
    ``end_s`` (never, when ``end_s`` is None). Ramps are :func:`smoothstep`; a zero blend time is a step.
    """
    t = np.asarray(times, dtype=np.float64)
    if t.size and _fully_on(float(t.min()), float(t.max()), start_s, end_s, blend_in_s, blend_out_s):
        return np.ones(t.shape)
    if blend_in_s > 0:
        w = smoothstep((t - start_s) / blend_in_s)
    else:
        w = (t >= start_s - 1e-9).astype(np.float64)
    if end_s is not None:
        if blend_out_s > 0:
            w = w * smoothstep((end_s - t) / blend_out_s)
        else:
            w = w * (t < end_s - 1e-9)
    return w


def _fully_on(first: float, last: float, start_s: float, end_s: float | None, blend_in_s: float, blend_out_s: float) -> bool:
    """Whether every time from ``first`` to ``last`` lies past the blend-in and before the blend-out
    (the weights are then exactly 1, as :func:`blend_weights` computes them)."""
    started = (first - start_s) / blend_in_s >= 1.0 if blend_in_s > 0 else first >= start_s - 1e-9
    if end_s is None or not started:
        return started
    return (end_s - last) / blend_out_s >= 1.0 if blend_out_s > 0 else last < end_s - 1e-9


def blend_weights_of(times, start_s: np.ndarray, end_s: np.ndarray, blend_in_s: np.ndarray, blend_out_s: np.ndarray) -> np.ndarray:
    """(N, F) weights of N activities at ``times`` (F,) seconds, each as :func:`blend_weights` gives it
    (to the bit): ``start_s``, ``end_s`` (inf: no end), ``blend_in_s``, ``blend_out_s`` are (N,) seconds."""
    t = np.asarray(times, dtype=np.float64)[None]
    start, end = start_s[:, None], end_s[:, None]
    ramp_in, ramp_out = blend_in_s[:, None], blend_out_s[:, None]
    rising = np.where(ramp_in > 0, smoothstep((t - start) / np.where(ramp_in > 0, ramp_in, 1.0)), t >= start - 1e-9)
    falling = np.where(ramp_out > 0, smoothstep((end - t) / np.where(ramp_out > 0, ramp_out, 1.0)), t < end - 1e-9)
    return rising * falling  # no end: (inf - t) / ramp is inf, a ramp that never comes down
