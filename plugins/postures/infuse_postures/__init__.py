"""infuse-anim-postures: a postures pack's standing idles on the whole body, the feet kept where they stand."""
from __future__ import annotations

from .controller import Posture

__all__ = ["Posture"]
