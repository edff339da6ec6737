"""The installed commands by name, from the plugin index (:mod:`infuse.plugin_index`): listing them
imports no plugin, running one imports only the plugin that offers it."""
from __future__ import annotations

import sys

from ..errors import MissingFeatureError
from ..plugin_index import Offer, offers


def command_index(refresh: bool = False) -> dict[str, list[Offer]]:
    """Command name -> the entry points offering it, in precedence order (distribution, entry-point name).

    ``refresh`` ignores the cache and imports every command plugin.
    """
    index: dict[str, list[Offer]] = {}
    for offer in offers("command", refresh):
        index.setdefault(offer.name, []).append(offer)
    return index


def load_command(name: str, offered: list[Offer]):
    """The :class:`~infuse.plugin_types.Command` ``name``, importing only the plugin that wins it.

    ``None`` when that plugin no longer offers it (the index is then rebuilt).
    """
    from .. import registry
    from ..config import current_config

    chosen = offered[0]
    if len(offered) > 1:
        preferred = current_config(frozenset(registry.KINDS)).prefer.get("command", {}).get(name)
        owners = [(o.distribution, o.entry_point.value) for o in offered]
        chosen = offered[registry.choose("command", name, owners, preferred, registry.plugins().report)]
    plugins = registry.plugins()
    module = plugins.load_entry_point(chosen.entry_point, "command")
    if module is None:
        raise MissingFeatureError(None, f"the plugin of the command {name!r} ({chosen.entry_point.value}, "
                                        f"{chosen.distribution}) failed to load; see the warning above")
    found = [c for c in plugins.offered_by(module, "command") if c.name == name]
    if not found:
        print(f"infuse: warning: the command list is out of date: {chosen.entry_point.value} no longer offers "
              f"{name!r}; it is rebuilt", file=sys.stderr)
        command_index(refresh=True)
        return None
    return found[0]
