"""Registers the heuristic mapper with infuse."""
from infuse import hookimpl
from infuse.plugin_types import Mapper

from .mapper import NAME, heuristic_map


@hookimpl
def infuse_mappers():
    return [Mapper(NAME, heuristic_map, "hierarchy, symmetry, rest geometry and name tokens, scored per joint")]
