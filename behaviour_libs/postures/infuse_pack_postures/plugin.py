"""Registers the postures pack's manifest under the infuse.behaviour_packs group."""
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
    return [BehaviourPack("postures", _load, "standing postures with their idles (weight shifts, sway): neutral, weight "
                                             "on one leg, arms crossed, hands on hips, behind the back or clasped, "
                                             "leaning (procedural)", str(MANIFEST))]
