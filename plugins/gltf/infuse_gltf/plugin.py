"""Registers the glTF reader and writer with infuse (entry points ``infuse.readers`` / ``infuse.writers``)."""
from __future__ import annotations

import infuse
from infuse.plugin_types import Reader, Writer

EXTENSIONS = (".glb", ".gltf", ".vrm", ".vrma")


def _read(path, **options):
    from .reader import read

    return read(path, **options)


def _write(asset, path, **options):
    from .writer import write

    return write(asset, path, **options)


@infuse.hookimpl
def infuse_readers():
    return [Reader("gltf", EXTENSIONS, _read, "glTF 2.0 (.gltf/.glb), VRM 0.x/1.0 and VRM Animation")]


@infuse.hookimpl
def infuse_writers():
    return [Writer("gltf", EXTENSIONS, _write, "glTF 2.0 (.gltf/.glb) and VRM: the character with new clips")]
