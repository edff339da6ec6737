"""infuse-anim-retarget: motion retargeting between any two humanoid skeletons through their canonical mappings.

The paper's two steps, default-pose alignment with local-frame re-orientation, then constraint
enforcement on the legs, plus contact-pinned feet and per-limb scaling, through the core's foot
component (``infuse.contacts``, ``infuse.footing``, ``infuse.runtime.limb_ik``). Quick use::

    from infuse_retarget import retarget
    out = retarget(walk, walk_mapping, character.skeleton, character_mapping)
"""
from __future__ import annotations

from .retarget import IK_MODES, RetargetResult, retarget, retarget_clip
from .transfer import RetargetPlan

__all__ = ["IK_MODES", "RetargetPlan", "RetargetResult", "retarget", "retarget_clip"]
