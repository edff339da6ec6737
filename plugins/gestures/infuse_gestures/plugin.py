"""Registers the ``gesture`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Gesture, gesture_from_bml


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("gesture", Gesture, "a gesture of a gestures pack on the arms, its stroke on its sync "
                                                  "point (posture layer)", from_bml=gesture_from_bml)]
