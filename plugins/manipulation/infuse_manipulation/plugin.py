"""Registers the ``pointing``, ``grab`` and ``ik_constraint`` controllers and how they realize BML."""
from __future__ import annotations

import infuse
from infuse.plugin_types import ControllerFactory

from . import realize
from .constraint import IKConstraint
from .grab import Grab
from .pointing import Pointing


@infuse.hookimpl
def infuse_controllers():
    return [
        ControllerFactory("pointing", Pointing, "point at a target with a hand, the body turning when it must (gaze layer)",
                          from_bml=realize.pointing_from_bml, realize=realize.realize_pointing),
        ControllerFactory("grab", Grab, "close a hand on an object, hold it, let it go (head layer)",
                          from_bml=realize.grab_from_bml, realize=realize.realize_grab),
        ControllerFactory("ik_constraint", IKConstraint, "keep a joint on a target by IK, faded in and out (head layer)",
                          from_bml=realize.constraint_from_bml, realize=realize.realize_constraint),
    ]
