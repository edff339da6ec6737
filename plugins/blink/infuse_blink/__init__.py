"""Blinks for infuse: human blink rates per activity, through eyelid morph targets or joints."""
from .controller import CLOSURE_CURVE, RATES_PER_MIN, Blink, BlinkSchedule, closure

__all__ = ["CLOSURE_CURVE", "RATES_PER_MIN", "Blink", "BlinkSchedule", "closure"]
