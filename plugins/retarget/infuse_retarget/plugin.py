"""Registers the retargeters (``default``: contact-pinned feet; ``paper``: the paper's warped feet)
and the ``infuse retarget`` command."""
from __future__ import annotations

from functools import partial

import infuse
from infuse.plugin_types import Command, Retargeter

from . import command
from .retarget import retarget


@infuse.hookimpl
def infuse_retargeters():
    return [
        Retargeter("default", retarget, "rotations through the canonical frame, root by leg length, planted feet pinned by IK"),
        Retargeter("paper", partial(retarget, ik="paper"), "the paper's algorithm: warped foot trajectories enforced by IK"),
    ]


@infuse.hookimpl
def infuse_commands():
    return [Command("retarget", "put a motion clip onto another character (BVH or glTF with the character's mesh)",
                    command.add_arguments, command.run)]
