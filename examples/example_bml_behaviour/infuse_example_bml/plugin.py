"""Registers the ``<shrug>`` handler under the ``infuse.bml_behaviours`` entry-point group."""
from infuse import hookimpl
from infuse.plugin_types import BMLBehaviour

from .shrug import ATTRIBUTES, ELEMENT, plan_shrug


@hookimpl
def infuse_bml_behaviours():
    return [BMLBehaviour("shrug", plan_shrug, "example: shrug both shoulders", (ELEMENT,), ATTRIBUTES)]
