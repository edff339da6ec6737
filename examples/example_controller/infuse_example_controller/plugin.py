"""Registers the ``shrug`` controller under the ``infuse.controllers`` entry-point group."""
from infuse import hookimpl
from infuse.plugin_types import Component

from .controller import Shrug, shrug_from_bml


@hookimpl
def infuse_controllers():
    return [Component("shrug", Shrug, "example: raise both shoulders and let them fall",
                      {"layer": int(Shrug.layer), "from_bml": shrug_from_bml})]
