"""Animation samplers evaluated on a uniform frame grid, vectorized over frames and channels.

Interpolation follows the glTF 2.0 spec: ``STEP`` holds the previous key, ``LINEAR`` is a lerp (a
shortest-path slerp for rotations), ``CUBICSPLINE`` is a Hermite spline whose keys store
(in-tangent, value, out-tangent) with tangents scaled by the key interval; cubic rotations are
renormalized. Times are seconds; before the first key the first value holds, after the last key
the last value.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat

DEFAULT_FPS = 30.0
#: Keyframe rates outside this range are not taken as the clip's frame rate (sparse keys, or noise).
FPS_RANGE = (12.0, 240.0)
INTERPOLATIONS = ("LINEAR", "STEP", "CUBICSPLINE")


def detect_fps(times: list[np.ndarray]) -> tuple[float, str]:
    """The frame rate the keyframe times were sampled at, or :data:`DEFAULT_FPS`.

    A rate is found when every key of every channel sits (within 1 % of a frame) on one grid whose
    step is the smallest key interval, and it lies in :data:`FPS_RANGE`. The rate is fitted to the
    keys, then rounded to a whole number of frames per second only if the keys fit the round rate
    to float32 precision (so a 30.00003 fps source keeps its rate). Returns the rate and how it was
    found (``"keyframes"`` or ``"default"``).
    """
    keys = np.unique(np.concatenate([np.asarray(t, dtype=np.float64).ravel() for t in times])) if times else np.zeros(0)
    if keys.size < 3:
        return DEFAULT_FPS, "default"
    step = float(np.min(np.diff(keys)))
    span = keys - keys[0]
    if step <= 0 or span[-1] <= 0:
        return DEFAULT_FPS, "default"
    frames = np.round(span / step)  # the smallest interval carries float32 noise: refit on the whole span
    rate = float(frames[-1] / span[-1])
    if np.max(np.abs(span * rate - frames)) > 0.01:
        return DEFAULT_FPS, "default"
    if not FPS_RANGE[0] <= rate <= FPS_RANGE[1]:
        return DEFAULT_FPS, "default"
    whole = float(np.round(rate))
    tolerance = np.maximum(4.0 * np.spacing(np.abs(keys).astype(np.float32)).astype(np.float64) * whole, 1e-6)
    if np.all(np.abs(span * whole - frames) <= tolerance):
        rate = whole
    return rate, "keyframes"


def frame_times(start: float, end: float, fps: float) -> np.ndarray:
    """Uniform frame times from ``start`` covering ``end`` (the last frame may hold the last key).

    Key times are float32 in glTF: an end that is a whole number of frames, rounded up in float32,
    does not add a frame (79 frames at 24 fps end at 3.2916667461 s, 79.000002 frames).
    """
    slack = max(1e-6, 4.0 * float(np.spacing(np.float32(max(abs(start), abs(end))))) * fps)
    count = int(np.ceil((end - start) * fps - slack)) + 1
    return start + np.arange(max(count, 1)) / fps


def sample(times: np.ndarray, values: np.ndarray, interpolation: str, query: np.ndarray, rotation: bool) -> np.ndarray:
    """Evaluate keys at ``query`` (F,) seconds.

    ``times`` (K,) non-decreasing; ``values`` (K, ..., C) for LINEAR/STEP or (K, 3, ..., C) for
    CUBICSPLINE (in-tangent, value, out-tangent); returns (F, ..., C). ``rotation`` selects slerp
    and renormalization for (x, y, z, w) quaternions.
    """
    times = np.asarray(times, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    cubic = interpolation == "CUBICSPLINE"
    points = values[:, 1] if cubic else values
    k = len(times)
    if k == 1:
        return np.broadcast_to(points[0], (len(query),) + points.shape[1:]).copy()
    if interpolation == "STEP":
        return points[np.clip(np.searchsorted(times, query, side="right") - 1, 0, k - 1)]
    i = np.clip(np.searchsorted(times, query, side="right") - 1, 0, k - 2)
    dt = times[i + 1] - times[i]
    u = np.clip(np.where(dt > 0, (query - times[i]) / np.where(dt > 0, dt, 1.0), 1.0), 0.0, 1.0)
    ub = u.reshape(u.shape + (1,) * (points.ndim - 1))
    if not cubic:
        if rotation:
            return quat.slerp(points[i], points[i + 1], ub[..., 0])
        return points[i] + ub * (points[i + 1] - points[i])
    dtb = dt.reshape(ub.shape)
    u2, u3 = ub * ub, ub * ub * ub
    out = ((2 * u3 - 3 * u2 + 1) * values[i, 1] + dtb * (u3 - 2 * u2 + ub) * values[i, 2]
           + (-2 * u3 + 3 * u2) * values[i + 1, 1] + dtb * (u3 - u2) * values[i + 1, 0])
    return quat.normalize(out) if rotation else out
