"""The names and help lines of the installed commands, learnt without importing their plugins.

Commands come from the ``infuse.commands`` entry points. A command plugin's module is imported once to
learn the names and help lines of the commands it offers; they are kept in ``commands.json`` in the
cache folder (``$XDG_CACHE_HOME/infuse``, else ``~/.cache/infuse``), keyed by the entry point, the
version of its distribution and the modification times of the files beside its module. Later runs
read them from there, and import a command's plugin only when that command runs.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
from dataclasses import dataclass
from importlib.machinery import PathFinder
from importlib.metadata import EntryPoint, entry_points
from importlib.util import find_spec
from pathlib import Path

from ..errors import MissingFeatureError

GROUP = "infuse.commands"
FORMAT = 1


@dataclass(frozen=True)
class IndexedCommand:
    """One command as an entry point offers it."""

    name: str
    help: str
    entry_point: EntryPoint

    @property
    def distribution(self) -> str:
        return self.entry_point.dist.name if self.entry_point.dist else "?"


def cache_file() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "infuse" / "commands.json"


def module_file(module: str) -> Path | None:
    """Where ``module`` (dotted name) is, found without importing it or its packages."""
    parts = module.split(".")
    try:
        spec = find_spec(parts[0])
        for depth in range(1, len(parts)):
            if spec is None or spec.submodule_search_locations is None:
                return None
            spec = PathFinder.find_spec(".".join(parts[:depth + 1]), list(spec.submodule_search_locations))
    except (ImportError, ValueError):
        return None
    return Path(spec.origin) if spec is not None and spec.has_location and spec.origin else None


def source_stamp(ep: EntryPoint) -> str | None:
    """What changes when the commands of ``ep`` may have: its distribution's version and the size and
    modification time of every Python file in its module's folder. ``None`` when the module is not found."""
    path = module_file(ep.module)
    if path is None:
        return None
    digest = hashlib.blake2b(digest_size=12)
    digest.update(f"{ep.dist.version if ep.dist else '?'}\0{ep.value}".encode())
    try:
        for entry in sorted(os.scandir(path.parent), key=lambda e: e.name):
            if entry.name.endswith(".py") and entry.is_file():
                info = entry.stat()
                digest.update(f"\0{entry.name}\0{info.st_mtime_ns}\0{info.st_size}".encode())
    except OSError:
        return None
    return digest.hexdigest()


def _entry_key(ep: EntryPoint) -> str:
    return f"{ep.dist.name if ep.dist else '?'}|{ep.name}|{ep.value}"


def _read_cache(path: Path) -> dict:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or not isinstance(doc.get("entries"), dict):
        return {}
    return doc["entries"]


def _write_cache(path: Path, entries: dict) -> None:
    """Replace the cache file whole (concurrent runs each write a complete file); silent when it cannot."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_name(f".{path.name}.{os.getpid()}")
        temporary.write_text(json.dumps({"format": FORMAT, "entries": entries}, indent=0), encoding="utf-8")
        os.replace(temporary, path)
    except OSError:
        pass


def _learn(ep: EntryPoint) -> list[tuple[str, str]] | None:
    """Import the plugin of ``ep`` and ask it for its commands; ``None`` when it is broken (already reported)."""
    from .. import registry

    plugins = registry.plugins()
    module = plugins.load_entry_point(ep, "command")
    if module is None:
        return None
    return [(c.name, c.help) for c in plugins.offered_by(module, "command")]


def command_index(refresh: bool = False) -> dict[str, list[IndexedCommand]]:
    """Command name -> the entry points offering it, in precedence order (distribution, entry-point name).

    ``refresh`` ignores the cache and imports every command plugin.
    """
    eps = sorted(entry_points(group=GROUP), key=lambda e: (e.dist.name if e.dist else "", e.name))
    path = cache_file()
    cached = {} if refresh else _read_cache(path)
    entries: dict[str, dict] = {}
    changed = refresh
    index: dict[str, list[IndexedCommand]] = {}
    for ep in eps:
        key, stamp = _entry_key(ep), source_stamp(ep)
        hit = cached.get(key)
        if stamp is not None and isinstance(hit, dict) and hit.get("stamp") == stamp:
            commands = [tuple(c) for c in hit.get("commands", ())]
        else:
            commands = _learn(ep)
            changed = True
            if commands is None:
                continue
        if stamp is not None:
            entries[key] = {"stamp": stamp, "commands": commands}
        for name, help_line in commands:
            index.setdefault(name, []).append(IndexedCommand(name, help_line, ep))
    if changed or set(entries) != set(cached):
        _write_cache(path, entries)
    return index


def load_command(name: str, offers: list[IndexedCommand]):
    """The :class:`~infuse.plugin_types.Command` ``name``, importing only the plugin that wins it.

    ``None`` when that plugin no longer offers it (the index is then rebuilt).
    """
    from .. import registry
    from ..config import current_config

    chosen = offers[0]
    if len(offers) > 1:
        preferred = current_config(frozenset(registry.KINDS)).prefer.get("command", {}).get(name)
        owners = [(o.distribution, o.entry_point.value) for o in offers]
        chosen = offers[registry.choose("command", name, owners, preferred, registry.plugins().report)]
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
