"""Registers the ``locomotion`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Locomotion


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("locomotion", Locomotion,
                              "walk, run, turn and strafe by blending a locomotion pack (base layer)")]
