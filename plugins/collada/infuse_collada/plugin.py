"""Registers the COLLADA reader with infuse."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader

from .reader import read


@hookimpl
def infuse_readers():
    return [Reader("collada", (".dae",), read, "COLLADA 1.4/1.5: joints, rest pose, skinned meshes, morph targets, animations")]
