"""Registers the ``reach`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Reach


def _realize(activation, stage):
    from .realize import realize_reach

    return realize_reach(activation, stage)


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("reach", Reach, "reach, touch, grab or put down with one hand (posture layer)",
                              realize=_realize)]
