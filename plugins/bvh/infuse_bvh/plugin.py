"""Registers the BVH reader and writer with infuse (entry points ``infuse.readers`` and ``infuse.writers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader, Writer

from . import reader, writer


@hookimpl
def infuse_readers():
    return [Reader("bvh", (".bvh",), reader.read, "Biovision Hierarchy motion capture (any channel order)")]


@hookimpl
def infuse_writers():
    return [Writer("bvh", (".bvh",), writer.write, "Biovision Hierarchy, centimetres, Y up (or the layout it was read with)")]
