"""Registers the breathing controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import Breathing, breathing_from_bml, idle_settings


@hookimpl
def infuse_controllers():
    return [ControllerFactory("breathing", Breathing, "subtle chest and clavicle motion at a breathing rate and depth",
                              from_bml=breathing_from_bml, idle=idle_settings)]
