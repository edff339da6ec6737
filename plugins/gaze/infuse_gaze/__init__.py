"""Gaze for infuse: the Thiebaux, Lance and Marsella (2009) model as SmartBody uses it.

Joint groups from the pelvis up to the eyes share the turn toward a target, each within elliptical
limits, smoothed and speed-limited per frame. See :class:`~infuse_gaze.controller.Gaze`.
"""
from .controller import Gaze
from .model import GROUPS, INFLUENCES, GroupSettings

__all__ = ["Gaze", "GROUPS", "INFLUENCES", "GroupSettings"]
