"""Registers the head movement controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import HeadMovement, head_from_bml


@hookimpl
def infuse_controllers():
    return [ControllerFactory("head", HeadMovement, "nod, shake, toss or tilt the head, split over the neck joints",
                              from_bml=head_from_bml)]
