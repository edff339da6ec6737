"""The paper's local-frame re-orientation, and clips expressed in the canonical frame.

Once a skeleton is aligned to the canonical T-pose, a joint with default global rotation ``R_G``
and default local rotation ``q_init`` takes a rotation ``q`` written in the canonical global frame
("a left 30° turn about Y is ``quat(Y, 30°)``, whatever the joint's initial rotation") as the
local rotation

    q' = q_init · R_G⁻¹ · q · R_G                       (:func:`reorient`)

and a clip authored on the skeleton's own frames comes back to the canonical frame with the inverse,

    q = R_G · q_init⁻¹ · q' · R_G⁻¹                      (:func:`unorient`).

:class:`~.transfer.RetargetPlan` applies the same maths to global rotations, which spares it a
matching hierarchy; :func:`to_canonical` uses it to put any clip on the canonical skeleton, where
every local frame is the world's and rotations can be shared between characters.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.motion import Motion

from .retarget import retarget


def reorient(q: np.ndarray, q_init: np.ndarray, r_g: np.ndarray) -> np.ndarray:
    """``q_init · R_G⁻¹ · q · R_G``: canonical-frame rotations ``q`` (..., 4) as a joint's local rotations."""
    return quat.multiply(quat.multiply(q_init, quat.conjugate(r_g)), quat.multiply(q, r_g))


def unorient(q_local: np.ndarray, q_init: np.ndarray, r_g: np.ndarray) -> np.ndarray:
    """``R_G · q_init⁻¹ · q' · R_G⁻¹``: a joint's local rotations ``q'`` (..., 4) in the canonical frame."""
    return quat.multiply(quat.multiply(r_g, quat.conjugate(q_init)), quat.multiply(q_local, quat.conjugate(r_g)))


def to_canonical(motion: Motion, mapping, *, extras: bool = False, source_file=None) -> Motion:
    """``motion`` on the canonical skeleton (:func:`infuse.canonical.canonical_skeleton`), without IK.

    Local rotations are then canonical-frame rotations relative to the canonical T-pose; the root
    is scaled to the canonical leg length. ``mapping``: the clip skeleton's canonical mapping;
    ``extras``: keep the optional canonical joints (``l_sternoclavicular``...) in the skeleton.
    """
    target = canonical_skeleton(extras=extras)
    identity = {n: j for j, n in enumerate(target.names)}
    return retarget(motion, mapping, target, identity, ik="none", source_file=source_file)
