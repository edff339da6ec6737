"""Registers the ``reach`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Reach


def _realize(activation, stage):
    from .realize import realize_reach

    return realize_reach(activation, stage)


def _warm_up(stage, character):
    from .realize import warm_up

    return warm_up(stage, character)


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("reach", Reach, "reach, touch, grab or put down with one hand (posture layer)",
                              realize=_realize, warm_up=_warm_up)]
