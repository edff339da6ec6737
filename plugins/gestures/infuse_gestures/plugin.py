"""Registers the ``gesture`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Gesture, gesture_from_bml


def _realize(activation, stage):
    """The gesture the generic way (:func:`gesture_from_bml`), or the character's own clip when it names no
    pack, and over its span SmartBody's noise on the joints its ``sbm:joint-range`` names
    (``sbm:frequency``, ``sbm:scale``) when a ``noise`` controller is installed."""
    from infuse.bml.model import BEHAVIOR_DEGRADED
    from infuse.errors import InfuseError
    from infuse.runtime import controller

    activity = stage.play(activation) if activation.parameters.get("pack") else stage.play_clip(activation)
    noise = activation.parameters.get("noise") or {}
    if activity is None or not noise.get("joints"):
        return activity
    settings = {"joints": noise["joints"]}
    if noise.get("scale"):
        settings["scale"] = float(noise["scale"])
    if noise.get("frequency"):
        settings["frequency_hz"] = float(noise["frequency"])
    try:
        stage.activate(activation, controller("noise", **settings), activity.end_s)
    except InfuseError as exc:
        stage.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: its noise is not shown: {exc}")
    return activity


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("gesture", Gesture, "a gesture of a gestures pack on the arms, its stroke on its sync "
                                                  "point (posture layer)", from_bml=gesture_from_bml, realize=_realize)]
