"""Registers the retargeters (``default``: contact-pinned feet; ``paper``: the paper's warped feet)
and the ``infuse retarget`` command."""
from __future__ import annotations

from functools import partial

import infuse
from infuse.plugin_types import Command, Retargeter

from . import command
from .retarget import retarget, retarget_clip
from .transfer import RetargetPlan


def prepare(source_skeleton, source_mapping, target_skeleton, target_mapping, *, ik: str = "contacts",
            limb_scaling: bool = False, **plan_options):
    """One :class:`RetargetPlan` for many clips on ``source_skeleton``: returns ``(motion) -> Motion``.
    ``plan_options``: ``source_motion``, ``target_motion``, ``source_file``, ``target_file``,
    ``target_meshes``."""
    plan = RetargetPlan(source_skeleton, source_mapping, target_skeleton, target_mapping, **plan_options)
    return partial(_retargeted, plan, ik=ik, limb_scaling=limb_scaling)


def _retargeted(plan: RetargetPlan, motion, **options):
    return retarget_clip(plan, motion, **options).motion


@infuse.hookimpl
def infuse_retargeters():
    return [
        Retargeter("default", retarget, "rotations through the canonical frame, root by leg length, planted feet pinned by IK",
                   prepare=prepare),
        Retargeter("paper", partial(retarget, ik="paper"), "the paper's algorithm: warped foot trajectories enforced by IK",
                   prepare=partial(prepare, ik="paper")),
    ]


@infuse.hookimpl
def infuse_commands():
    return [Command("retarget", "put a motion clip onto another character (BVH or glTF with the character's mesh)",
                    command.add_arguments, command.run)]
