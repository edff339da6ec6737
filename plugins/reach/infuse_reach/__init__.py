"""infuse-anim-reach: reaching for points and scene objects with a reaching pack, exact by arm IK."""
from __future__ import annotations

from .controller import HeldTarget, Reach

__all__ = ["HeldTarget", "Reach"]
