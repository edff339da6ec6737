"""Registers the breathing controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Component

from .controller import Breathing, breathing_from_bml


@hookimpl
def infuse_controllers():
    return [Component("breathing", Breathing, "subtle chest and clavicle motion at a breathing rate and depth",
                      {"layer": int(Breathing.layer), "from_bml": breathing_from_bml})]
