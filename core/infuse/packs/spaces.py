"""A pack infused on a runtime character once per asset and mapping, shared by every controller that plays it."""
from __future__ import annotations

from .infusion import BlendSpace, infuse_character


class InfusedSpaces(dict):
    """The packs infused on a character's asset: pack name -> (the mapping it was infused through, its
    :class:`BlendSpace`). Kept for the asset (:meth:`~infuse.runtime.rig.Rig.asset_state_of`): every runtime
    and scene playing a character made of it shares it, and it goes with the asset."""


def space_on(rig, pack) -> BlendSpace:
    """The :class:`BlendSpace` of ``pack`` (a BlendSpace, returned as is, or an installed pack's name or
    folder) on the runtime character ``rig``: infused the first time, again only when the rig's mapping
    is another."""
    if isinstance(pack, BlendSpace):
        return pack
    spaces = rig.asset_state_of(InfusedSpaces)
    mapping, space = spaces.get(str(pack), (None, None))
    if space is None or mapping is not rig.mapping:
        infusion = infuse_character(rig.character, [pack], mapping=rig.mapping)
        space = next(iter(infusion.spaces.values()))
        spaces[str(pack)] = (rig.mapping, space)
    return space
