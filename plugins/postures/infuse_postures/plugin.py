"""Registers the ``posture`` controller."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from .controller import Posture, posture_from_bml


@infuse.hookimpl
def infuse_controllers():
    return [ControllerFactory("posture", Posture, "a standing posture of a postures pack on the whole body, its idle "
                                                  "looping, the feet planted where they stand (base layer)",
                              from_bml=posture_from_bml)]
