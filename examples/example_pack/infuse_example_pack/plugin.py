"""Registers the example-wave pack's manifest under the ``infuse.behaviour_packs`` entry-point group."""
from pathlib import Path

from infuse import hookimpl
from infuse.plugin_types import BehaviourPack

MANIFEST = Path(__file__).resolve().parent / "pack" / "manifest.toml"


def load():
    from infuse.packs import load_pack

    return load_pack(MANIFEST)


@hookimpl
def infuse_behaviour_packs():
    return [BehaviourPack("example-wave", load, "example: the right hand waves at five places around the body",
                          str(MANIFEST))]
