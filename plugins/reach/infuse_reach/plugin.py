"""Registers the ``reach`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Reach


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("reach", Reach, "reach, touch, grab or put down with one hand (posture layer)")]
