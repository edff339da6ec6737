"""infuse-anim-gestures: a gestures pack's clips played on the arms, their phases on BML sync points."""
from __future__ import annotations

from .controller import Gesture
from .timewarp import phase_warp

__all__ = ["Gesture", "phase_warp"]
