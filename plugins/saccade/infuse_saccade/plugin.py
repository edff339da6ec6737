"""Registers the saccade controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import Saccades, saccade_from_bml


@hookimpl
def infuse_controllers():
    return [ControllerFactory("saccade", Saccades, "eye saccades in talk, listen or think mode (Lee et al. 2002)",
                              from_bml=saccade_from_bml)]
