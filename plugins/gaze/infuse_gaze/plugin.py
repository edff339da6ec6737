"""Registers the gaze controller (group ``infuse.controllers``) and ``infuse gaze`` (group ``infuse.commands``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .bml import gaze_from_bml
from .controller import Gaze


@hookimpl
def infuse_controllers():
    return [ControllerFactory("gaze", Gaze, "look at a point, a moving object or a character's joint with eyes, head and spine "
                      "(Thiebaux et al. 2009)", from_bml=gaze_from_bml)]


@hookimpl
def infuse_commands():
    from .command import gaze_command

    return [gaze_command()]
