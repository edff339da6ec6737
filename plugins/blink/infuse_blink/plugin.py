"""Registers the blink controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import Blink, blink_from_bml, idle_settings


@hookimpl
def infuse_controllers():
    return [ControllerFactory("blink", Blink, "blink at human rates through eyelid morph targets or joints",
                              from_bml=blink_from_bml, idle=idle_settings)]
