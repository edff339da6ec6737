"""Registers the Ogre skeleton XML reader with infuse."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader

from .reader import read


@hookimpl
def infuse_readers():
    return [Reader("ogre", (".skeleton.xml",), read, "Ogre3D skeleton XML: bones, binding pose, animations")]
