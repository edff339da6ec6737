"""infuse-anim-manipulation: pointing at targets, grabbing and holding objects, effectors kept on targets.

Three controllers, each realizing its BML behaviour kind: :class:`Pointing` (``<pointing>``, SmartBody's
``sbm:reach action="point-at"``), :class:`Grab` (``sbm:grab``) and :class:`IKConstraint`
(``sbm:constraint``). Hands and fingers are found on any rig through its canonical mapping (:mod:`.hands`).
"""
from .constraint import IKConstraint
from .grab import Grab, HeldObject
from .pointing import Pointing

__all__ = ["Grab", "HeldObject", "IKConstraint", "Pointing"]
