"""Finds plugins through entry points, loads them into one pluggy manager, and collects what they offer.

A plugin that fails to import, or whose hook raises, is reported once on stderr and skipped; the
rest keeps working.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from functools import lru_cache
from importlib.metadata import entry_points
from typing import Any

import pluggy

from . import hookspecs

#: Plugin kind -> entry-point group.
ENTRY_POINT_GROUPS: dict[str, str] = {
    "reader": "infuse.readers",
    "writer": "infuse.writers",
    "mapper": "infuse.mappers",
    "retargeter": "infuse.retargeters",
    "controller": "infuse.controllers",
    "behaviour-pack": "infuse.behaviour_packs",
    "tts": "infuse.tts",
    "bml-behaviour": "infuse.bml_behaviours",
    "command": "infuse.commands",
}


@dataclass
class PluginRecord:
    """One entry point: where it came from and whether it loaded."""

    name: str
    kind: str
    distribution: str
    version: str
    module: str
    error: str | None = None


class PluginSet:
    """The loaded plugins and their pluggy manager."""

    def __init__(self) -> None:
        self.manager = pluggy.PluginManager("infuse")
        self.manager.add_hookspecs(hookspecs)
        self.records: list[PluginRecord] = []
        self._reported: set[str] = set()

    def load_entry_points(self) -> None:
        for kind, group in ENTRY_POINT_GROUPS.items():
            for ep in entry_points(group=group):
                dist = ep.dist.name if ep.dist else "?"
                version = ep.dist.version if ep.dist else "?"
                record = PluginRecord(ep.name, kind, dist, version, ep.value)
                self.records.append(record)
                try:
                    module = ep.load()
                    if self.manager.is_registered(module):
                        continue
                    self.manager.register(module, name=f"{dist}:{ep.value}")
                except Exception as exc:  # a broken third-party plugin must not stop infuse
                    record.error = f"{type(exc).__name__}: {exc}"
                    self.report(f"plugin {ep.name!r} ({dist}, group {group}) failed to load and is skipped: {record.error}")

    def register(self, module: Any, name: str | None = None) -> None:
        """Register a plugin module directly (for tests and embedding applications)."""
        self.manager.register(module, name=name)
        self.collect.cache_clear()

    def report(self, message: str) -> None:
        if message not in self._reported:
            self._reported.add(message)
            print(f"infuse: warning: {message}", file=sys.stderr)

    @lru_cache(maxsize=None)
    def collect(self, hook_name: str) -> tuple:
        """Call hook ``hook_name`` on each plugin separately and concatenate the lists they return."""
        caller = getattr(self.manager.hook, hook_name)
        items: list = []
        for impl in caller.get_hookimpls():
            try:
                result = impl.function()
            except Exception as exc:
                self.report(f"plugin {impl.plugin_name!r} failed in {hook_name} and is skipped: {type(exc).__name__}: {exc}")
                continue
            items.extend(result or [])
        return tuple(items)

    def by_name(self, hook_name: str) -> dict[str, Any]:
        """``collect(hook_name)`` as a dict by descriptor name (first registration wins)."""
        out: dict[str, Any] = {}
        for item in self.collect(hook_name):
            out.setdefault(item.name, item)
        return out


@lru_cache(maxsize=1)
def plugins() -> PluginSet:
    """The process-wide plugin set, loaded from entry points on first use."""
    ps = PluginSet()
    ps.load_entry_points()
    return ps


def readers() -> dict[str, Any]:
    return plugins().by_name("infuse_readers")


def writers() -> dict[str, Any]:
    return plugins().by_name("infuse_writers")


def mappers() -> dict[str, Any]:
    return plugins().by_name("infuse_mappers")


def retargeters() -> dict[str, Any]:
    return plugins().by_name("infuse_retargeters")


def commands() -> dict[str, Any]:
    return plugins().by_name("infuse_commands")
