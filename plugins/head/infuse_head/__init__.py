"""Head movements for infuse: nod, shake, toss and tilt (SmartBody's oscillation model)."""
from .controller import AMPLITUDE_DEG, AXES, HeadMovement, head_angle

__all__ = ["AMPLITUDE_DEG", "AXES", "HeadMovement", "head_angle"]
