"""The core's own controllers (``clip``, ``tracks``), registered as a plugin like any other."""
from __future__ import annotations

from ..hookspecs import hookimpl
from ..plugin_types import ControllerFactory
from .clip import Clip
from .tracks import Tracks


@hookimpl
def infuse_controllers():
    return [
        ControllerFactory("clip", Clip, "play a Motion on a character, looping or once (base layer)"),
        ControllerFactory("tracks", Tracks, "play keyed joint-rotation and morph-weight curves (face layer by default)"),
    ]
