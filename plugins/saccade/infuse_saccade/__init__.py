"""Saccades for infuse: the statistical eye movement model of Lee, Badler and Badler (2002)."""
from .model import DIRECTION_BINS_DEG, DIRECTION_PERCENT, MODES, SaccadeMode, SaccadeSchedule, magnitude_cdf
from .controller import Saccades

__all__ = ["DIRECTION_BINS_DEG", "DIRECTION_PERCENT", "MODES", "SaccadeMode", "SaccadeSchedule", "magnitude_cdf", "Saccades"]
