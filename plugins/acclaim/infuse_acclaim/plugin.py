"""Registers the Acclaim readers with infuse (entry point group ``infuse.readers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader

from . import reader


@hookimpl
def infuse_readers():
    return [
        Reader("acclaim-asf", (".asf",), reader.read_asf, "Acclaim skeleton (CMU mocap): bones, axes, dofs, limits"),
        Reader("acclaim-amc", (".amc",), reader.read_amc, "Acclaim motion (CMU mocap); finds its .asf beside it"),
    ]
