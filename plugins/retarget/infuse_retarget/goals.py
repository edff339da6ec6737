"""Where the target's feet and hands should be: the goals the limb IK enforces.

- :func:`warp` is the paper's trajectory warping, ``p'(0) = p(0)``,
  ``p'(t + δt) = p'(t) + s·(p_s(t + δt) − p_s(t))``, i.e. ``p(0) + s·(p_s(t) − p_s(0))``.
- Beyond it, planted feet are pinned by :func:`infuse.footing.pinned`: while the source foot point
  is planted the target point is held exactly still, and between contacts the correction this needs
  glides from one contact to the next (smoothstep in time), so nothing pops.
- :func:`reach` scales a hand's offset from its shoulder by the arm-length ratio as the arm
  straightens, so a reaching hand reaches as far, relative to its arm, as the source's.

Positions are component-major (3, F) world metres, +Y up, over all frames at once.
"""
from __future__ import annotations

import numpy as np

from infuse.footing import smoothstep


def warp(start: np.ndarray, source: np.ndarray, scale: float) -> np.ndarray:
    """The paper's warped trajectory (3, F): ``start + scale · (source(t) − source(0))``."""
    return start[:, None] + scale * (source - source[:, :1])


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
