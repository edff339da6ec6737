"""What each installed plugin offers, learnt once and kept, so that listing never imports a plugin.

For every entry point of a kind, the index holds the name, the one-line description (a command's
help) and the file extensions (readers, writers) of each descriptor its module offers. A module is
imported once to learn them; they are kept in ``plugins-<environment>.json`` in the cache folder
(``$XDG_CACHE_HOME/infuse``, else ``~/.cache/infuse``; one file per Python environment), keyed by the
entry point and stamped with the version of its distribution and the size and modification time of
every Python file beside its module, and learnt again when the stamp changes. The command line lists
commands from it, and a file is read by importing only the readers that claim its extension.
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

FORMAT = 1


@dataclass(frozen=True)
class Offer:
    """One descriptor as an entry point offers it, without its plugin imported."""

    name: str
    description: str
    extensions: tuple[str, ...]
    entry_point: EntryPoint

    @property
    def distribution(self) -> str:
        return distribution(self.entry_point)


def distribution(ep: EntryPoint) -> str:
    """The name of the distribution of ``ep`` ("?" when its metadata says none, e.g. while it is reinstalled)."""
    return (ep.dist.name if ep.dist else None) or "?"


def cache_file() -> Path:
    """The index of this Python environment (one per environment: each has its own copies of the plugins)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    environment = hashlib.blake2b(sys.prefix.encode(), digest_size=6).hexdigest()
    return Path(base) / "infuse" / f"plugins-{environment}.json"


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
    """What changes when what ``ep`` offers may have: its distribution's version and the size and
    modification time of every Python file in its module's folder. ``None`` when the module is not found."""
    path = module_file(ep.module)
    if path is None:
        return None
    digest = hashlib.blake2b(digest_size=12)
    digest.update(f"{(ep.dist.version if ep.dist else None) or '?'}\0{ep.value}".encode())
    try:
        for entry in sorted(os.scandir(path.parent), key=lambda e: e.name):
            if entry.name.endswith(".py") and entry.is_file():
                info = entry.stat()
                digest.update(f"\0{entry.name}\0{info.st_mtime_ns}\0{info.st_size}".encode())
    except OSError:
        return None
    return digest.hexdigest()


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


def _learn(ep: EntryPoint, kind: str) -> list[list] | None:
    """Import the plugin of ``ep`` and ask it what it offers; ``None`` when it is broken (already reported)."""
    from . import registry

    plugins = registry.plugins()
    module = plugins.load_entry_point(ep, kind)
    if module is None:
        return None
    return [[d.name, getattr(d, "help", None) or getattr(d, "description", ""), list(getattr(d, "extensions", ()))]
            for d in plugins.offered_by(module, kind)]


def entry_points_of(group: str) -> list[EntryPoint]:
    """The entry points of ``group`` in precedence order: by distribution name, then entry-point name."""
    return sorted(entry_points(group=group), key=lambda e: (distribution(e), e.name))


#: kind -> what its entry points offer, learnt once per process (the installed plugins do not change under it).
_LEARNT: dict[str, list[Offer]] = {}


def offers(kind: str, refresh: bool = False) -> list[Offer]:
    """What every entry point of ``kind`` offers, in precedence order; ``refresh`` ignores the caches."""
    if not refresh and kind in _LEARNT:
        return list(_LEARNT[kind])
    from .registry import kind_of

    path = cache_file()
    cached = _read_cache(path)
    entries = {key: entry for key, entry in cached.items() if not key.startswith(f"{kind}|")}
    out = []
    for ep in entry_points_of(kind_of(kind).group):
        key = f"{kind}|{distribution(ep)}|{ep.name}|{ep.value}"
        stamp = source_stamp(ep)
        hit = None if refresh else cached.get(key)
        if stamp is not None and isinstance(hit, dict) and hit.get("stamp") == stamp:
            entries[key] = hit
            learnt = hit.get("offers", [])
        else:
            learnt = _learn(ep, kind)
            if learnt is None:
                continue
            if stamp is not None:
                entries[key] = {"stamp": stamp, "offers": learnt}
        out += [Offer(str(name), str(text), tuple(extensions), ep) for name, text, extensions in learnt]
    if entries != cached:
        _write_cache(path, entries)
    _LEARNT[kind] = out
    return list(out)
