"""Registers the saccade controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Component

from .controller import Saccades, saccade_from_bml


@hookimpl
def infuse_controllers():
    return [Component("saccade", Saccades, "eye saccades in talk, listen or think mode (Lee et al. 2002)",
                      {"layer": int(Saccades.layer), "from_bml": saccade_from_bml})]
