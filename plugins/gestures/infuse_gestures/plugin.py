"""Registers the ``gesture`` controller and how it realizes BML ``<gesture>``."""
from __future__ import annotations

from dataclasses import replace

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Gesture, gesture_from_bml


def _realize(activation, stage):
    """The gesture the generic way (:func:`gesture_from_bml`), or the character's own clip when it names no
    pack, and over its span SmartBody's noise on the joints its ``sbm:joint-range`` names
    (``sbm:frequency``, ``sbm:scale``) when a ``noise`` controller is installed. A deictic gesture with a
    target points at it (the installed ``pointing`` controller); another gesture with a target is aimed
    at it, played by the hand on the target's side unless the BML chose one."""
    from infuse.bml.model import BEHAVIOR_DEGRADED
    from infuse.errors import InfuseError
    from infuse.runtime import controller

    if activation.parameters.get("target"):
        activation = _targeted(activation, stage)
        if activation is None:
            return None
        if activation.parameters.get("deictic"):
            return _point(activation, stage)
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


def _targeted(activation, stage):
    """The activation with its target as the scene spells it and, when its hand is free to choose
    (``hand_clips``), the clip of the hand on the target's side; None (warned) for an unknown target."""
    from infuse.bml.model import NO_SUCH_TARGET

    p = dict(activation.parameters)
    name = stage.resolve(p["target"])
    if stage.what(name.partition(":")[0]) is None:
        stage.warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: no character, object or target named "
                                               f"{p['target']!r}")
        return None
    p["target"] = name
    where = stage.locate(name)
    if p.get("hand_clips") and where is not None:
        side = stage.runtime.rig(activation.character).side_of(where)
        p["clip"] = p["hand_clips"].get(side, p.get("clip"))
    return replace(activation, parameters=p)


def _point(activation, stage):
    """A deictic gesture: the ``pointing`` controller at its target over the gesture's phases."""
    from infuse.bml.model import CANNOT_CREATE_BEHAVIOR
    from infuse.errors import InfuseError
    from infuse.runtime import controller
    from infuse.stage import end_s

    start = activation.start
    at = {p: activation.time(p) for p in ("ready", "stroke", "relax")}
    try:
        pointing = controller("pointing", target=activation.parameters["target"],
                              hand=activation.parameters.get("hand") or "auto", ready_s=at["ready"] - start,
                              stroke_s=at["stroke"] - start, relax_s=at["relax"] - start,
                              duration_s=activation.end - start)
    except InfuseError as exc:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot point: {exc}")
        return None
    return stage.activate(activation, pointing, end_s(activation))


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("gesture", Gesture, "a gesture of a gestures pack on the arms, its stroke on its sync "
                                                  "point (posture layer)", from_bml=gesture_from_bml, realize=_realize)]
