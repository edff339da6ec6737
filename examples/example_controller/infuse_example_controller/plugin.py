"""Registers the ``shrug`` controller under the ``infuse.controllers`` entry-point group."""
from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import Shrug, shrug_from_bml


@hookimpl
def infuse_controllers():
    return [ControllerFactory("shrug", Shrug, "example: raise both shoulders and let them fall",
                              from_bml=shrug_from_bml)]
