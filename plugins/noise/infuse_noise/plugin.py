"""Registers the noise controller (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import ControllerFactory

from .controller import Noise, noise_from_bml, realize_noise


@hookimpl
def infuse_controllers():
    return [ControllerFactory("noise", Noise, "smooth random turns of named joints (SmartBody's Perlin noise)",
                              from_bml=noise_from_bml, realize=realize_noise)]
