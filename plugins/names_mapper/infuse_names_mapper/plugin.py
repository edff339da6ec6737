"""Registers the names mapper with infuse."""
from infuse import hookimpl
from infuse.plugin_types import Mapper

from .mapper import NAME, names_map


@hookimpl
def infuse_mappers():
    return [Mapper(NAME, names_map, "dictionaries of known rig conventions (Mixamo, Unreal, VRM, Biped, CMU, ...)")]
