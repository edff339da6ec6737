"""Behaviour packs: parameterized motion sets (locomotion, reaching) that infuse onto any character.

- :mod:`~infuse.packs.manifest`: the pack format (a TOML manifest, a skeleton, BVH or skm clips);
- :mod:`~infuse.packs.build`: ``infuse pack build``, the analysis stored in the pack;
- :mod:`~infuse.packs.importers`: SmartBody behaviour sets and folders of BVH;
- :mod:`~infuse.packs.infusion`: retargeting a pack onto a character, blend spaces, the cache;
- :mod:`~infuse.packs.spaces`: a pack infused on a runtime character once per asset (:func:`space_on`).

Installed packs register a :class:`~infuse.plugin_types.BehaviourPack` naming their manifest through
the ``infuse_behaviour_packs`` hook (entry-point group ``infuse.behaviour_packs``).
"""
from __future__ import annotations

from .build import build_pack, summary
from .importers import import_bvh_folder, import_smartbody
from .infusion import BlendClip, BlendSpace, Infusion, infuse_character
from .manifest import Manifest, read_manifest
from .pack import Pack, installed_packs, load_pack
from .spaces import InfusedSpaces, space_on
from .tessellation import Tessellation

__all__ = ["build_pack", "summary", "import_bvh_folder", "import_smartbody", "BlendClip", "BlendSpace", "Infusion",
           "infuse_character", "Manifest", "read_manifest", "Pack", "installed_packs", "load_pack", "Tessellation",
           "InfusedSpaces", "space_on"]
