"""Registers the FBX reader with infuse."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader

from .reader import read


@hookimpl
def infuse_readers():
    return [Reader("fbx", (".fbx",), read, "FBX 7.x, binary or ASCII: skeleton, rest pose, animation stacks, skinned meshes, blend shapes")]
