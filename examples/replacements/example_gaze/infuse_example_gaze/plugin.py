"""Registers ``head-gaze`` (group ``infuse.controllers``) as the realizer of BML gaze behaviours."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import HeadGaze


def _realize(activation, stage):
    from .realize import realize_gaze

    return realize_gaze(activation, stage)


@hookimpl
def infuse_controllers():
    return [ControllerFactory("head-gaze", HeadGaze, "example: turn the head alone toward a target (replaces gaze)",
                              realize=_realize, realizes=("gaze",))]
