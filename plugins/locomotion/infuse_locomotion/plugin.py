"""Registers the ``locomotion`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Locomotion


def _realize(activation, stage):
    from .realize import realize_walk

    return realize_walk(activation, stage)


def _prepare(activation, stage):
    from .realize import prepare_walk

    prepare_walk(activation, stage)


def _warm_up(stage, character):
    from .realize import warm_up

    return warm_up(stage, character)


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("locomotion", Locomotion,
                              "walk, run, turn and strafe by blending a locomotion pack (base layer)", realize=_realize,
                              prepare=_prepare, warm_up=_warm_up)]
