"""The ``studio-prefix`` mapper: joints named ``c_<canonical name>`` map to that canonical name.

Every canonical name the scheme does not cover is left to infuse's default mapper, run by
``infuse.mapping.map_skeleton`` with the names found here as a saved map: they win, and a joint
they name is never given to another canonical name.
"""
from infuse import hookimpl
from infuse.canonical import ALL_NAMES
from infuse.errors import NotHumanoidError
from infuse.mapping import DEFAULT_MAPPER, Mapping, map_skeleton
from infuse.plugin_types import Mapper

PREFIX = "c_"


def studio_map(skeleton, fixed=None, **options) -> Mapping:
    found = {name[len(PREFIX):]: name for name in skeleton.names
             if name.startswith(PREFIX) and name[len(PREFIX):] in ALL_NAMES}
    found.update(fixed or {})
    try:
        rest = map_skeleton(skeleton, DEFAULT_MAPPER, saved_map=found or None, **options)
    except NotHumanoidError:
        if not found:
            raise
        rest = Mapping.build(skeleton, found, {k: 1.0 for k in found})
    reasons = {**rest.reasons, **{k: f"studio name {v!r}" for k, v in found.items() if v is not None}}
    return Mapping.build(skeleton, rest.joints, rest.confidence, reasons, mapper="studio-prefix")


@hookimpl
def infuse_mappers():
    return [Mapper("studio-prefix", studio_map, "example: c_<canonical> joint names, then the default mapper")]
