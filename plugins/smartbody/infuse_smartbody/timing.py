"""Frame rate from ``.skm`` key times, and resampling of irregular key times to a fixed rate."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from infuse import quaternions as quat
from infuse.errors import InputError

#: Frame rate assumed for a single-frame pose.
DEFAULT_FPS = 30.0
_SNAP = 0.005  # relative distance to a whole frame rate that counts as that rate (times are rounded in files)
_IRREGULAR = 0.05  # relative deviation of one step from the median step that makes key times irregular


def frame_rate(times: np.ndarray, file: Path) -> tuple[float, bool]:
    """Frames per second of key times ``times`` (F,) in seconds, and whether they are evenly spaced."""
    if times.size < 2:
        return DEFAULT_FPS, True
    steps = np.diff(times)
    bad = np.nonzero(steps <= 0.0)[0]
    if bad.size:
        raise InputError(file, f"frame {bad[0] + 2}", f"key time {times[bad[0] + 1]} does not increase")
    step = float(np.median(steps))
    fps = 1.0 / step
    if abs(fps - round(fps)) <= _SNAP * fps:
        fps = float(round(fps))
    regular = bool(np.all(np.abs(steps - step) <= _IRREGULAR * step))
    return fps, regular


def resample(times: np.ndarray, fps: float, rotations: np.ndarray, translations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotations (F,J,4) and translations (F,J,3) at key ``times`` resampled every ``1/fps`` s.

    Rotations are interpolated by slerp, translations linearly, between the surrounding keys.
    """
    count = int(np.floor((times[-1] - times[0]) * fps + 1e-6)) + 1
    t = times[0] + np.arange(count) / fps
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.size - 2)
    u = np.clip((t - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0)
    rot = quat.slerp(rotations[i], rotations[i + 1], np.broadcast_to(u[:, None], (count, rotations.shape[1])))
    trans = translations[i] + (translations[i + 1] - translations[i]) * u[:, None, None]
    return rot, trans
