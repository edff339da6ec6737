"""Registers the SmartBody readers with infuse (entry point group ``infuse.readers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Reader

from . import reader


@hookimpl
def infuse_readers():
    return [
        Reader("smartbody-sk", (".sk",), reader.read_sk, "SmartBody skeleton (offsets, prerot, channels and limits)"),
        Reader("smartbody-skm", (".skm",), reader.read_skm,
               "SmartBody motion (rotation-vector Quat channels, sync points); finds its .sk beside it"),
    ]
