"""Registers the gestures pack's manifest under the infuse.behaviour_packs group."""
from __future__ import annotations

from pathlib import Path

import infuse
from infuse.plugin_types import BehaviourPack

MANIFEST = Path(__file__).resolve().parent / "pack" / "manifest.toml"


def _load():
    from infuse.packs import load_pack

    return load_pack(MANIFEST)


@infuse.hookimpl
def infuse_behaviour_packs():
    return [BehaviourPack("gestures", _load, "conversational gestures for each hand and both, their phases as sync times "
                                             "(procedural)", str(MANIFEST))]
