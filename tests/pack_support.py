"""SmartBody's locomotion sets as a new user gets them: imported from the corpus, built, infused."""
from __future__ import annotations

from pathlib import Path

import infuse
from infuse.packs import build_pack, import_smartbody, infuse_character

from corpus_data import corpus_file


def smartbody_space(asset: infuse.Asset, behaviour_set: str, folder: Path):
    """The blend space of SmartBody's ``behaviour_set`` (``MaleLocomotion``, ``FemaleLocomotion``)
    imported into ``folder``, built and infused onto ``asset``."""
    name = {"MaleLocomotion": "sb-male", "FemaleLocomotion": "sb-female"}.get(behaviour_set, behaviour_set.lower())
    pack = import_smartbody(corpus_file(f"smartbody/behaviorsets/{behaviour_set}"), folder / name, name=name)
    build_pack(pack)
    return next(iter(infuse_character(infuse.Character("c", asset), [str(pack)]).spaces.values()))
