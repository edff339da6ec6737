"""The user's configuration file: default plugins per kind and which plugin wins a shared name.

The file is TOML, found at ``$INFUSE_CONFIG``, else ``$XDG_CONFIG_HOME/infuse/config.toml``, else
``~/.config/infuse/config.toml``; a missing file is an empty configuration::

    [defaults]              # the plugin used when a command or a call names none
    mapper = "names"
    retargeter = "paper"

    [defaults.controller]   # the controller that realizes a BML behaviour kind
    gaze = "soft-gaze"

    [prefer.controller]     # two installed distributions offer a controller "gaze": this one wins
    gaze = "infuse-fancy-gaze"

Keys of ``[defaults]`` and ``[prefer]`` are plugin kinds (:data:`infuse.registry.KINDS`); those of
``[defaults.controller]`` BML behaviour kinds (:func:`infuse.registry.realizer`).
"""
from __future__ import annotations

import os
import threading
import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from .errors import InputError


@dataclass(frozen=True)
class Config:
    """What the configuration file says. ``defaults``: kind -> plugin name; ``prefer``: kind -> {name:
    distribution}; ``realizers``: BML behaviour kind -> controller name."""

    path: Path
    defaults: dict[str, str] = field(default_factory=dict)
    prefer: dict[str, dict[str, str]] = field(default_factory=dict)
    realizers: dict[str, str] = field(default_factory=dict)


def config_path() -> Path:
    """Where the configuration file is looked for (it need not exist)."""
    return _located(os.environ.get("INFUSE_CONFIG"), os.environ.get("XDG_CONFIG_HOME"), os.environ.get("HOME"))


@lru_cache(maxsize=8)
def _located(explicit: str | None, base: str | None, home: str | None) -> Path:
    """:func:`config_path` from the variables it depends on (``home`` only through ``~``), worked out once
    for each of their values: the configuration is looked up on every plugin lookup."""
    if explicit:
        return Path(explicit).expanduser()
    base = base or os.path.join(os.path.expanduser("~"), ".config")
    return Path(base) / "infuse" / "config.toml"


def read_config(path: Path, kinds: frozenset[str]) -> Config:
    """Parse the configuration file at ``path``; :class:`InputError` names the place of any problem."""
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return Config(path)
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, None, f"cannot read the configuration file: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(path, None, f"not valid TOML: {exc}") from None
    unknown = sorted(set(doc) - {"defaults", "prefer"})
    if unknown:
        raise InputError(path, f"[{unknown[0]}]", "unknown section; the sections are [defaults] and [prefer.KIND]")
    defaults = doc.get("defaults", {})
    realizers = {}
    if isinstance(defaults, dict) and isinstance(defaults.get("controller"), dict):
        defaults = dict(defaults)
        realizers = _table(path, defaults.pop("controller"), "defaults.controller", None)
    defaults = _table(path, defaults, "defaults", kinds)
    prefer = {}
    for kind, names in _table(path, doc.get("prefer", {}), "prefer", kinds, values=dict).items():
        prefer[kind] = _table(path, names, f"prefer.{kind}", None)
    return Config(path, defaults, prefer, realizers)


def _table(path: Path, table, place: str, kinds: frozenset[str] | None, values: type = str) -> dict:
    if not isinstance(table, dict):
        raise InputError(path, f"[{place}]", "must be a table")
    for key, value in table.items():
        if kinds is not None and key not in kinds:
            raise InputError(path, f"[{place}] {key}", f"unknown plugin kind; the kinds are {', '.join(sorted(kinds))}")
        if not isinstance(value, values):
            what = "a table of names" if values is dict else "a string"
            raise InputError(path, f"[{place}] {key}", f"must be {what}, not {type(value).__name__}")
    return dict(table)


@lru_cache(maxsize=8)
def _cached(path: Path, stamp: tuple[int, int, int, int], kinds: frozenset[str]) -> Config:
    return read_config(path, kinds)


def current_config(kinds: frozenset[str]) -> Config:
    """The configuration in effect now (re-read when the file changes: its times, size or inode); within
    :func:`held_config`, the one in effect when it began."""
    held = getattr(_held, "configs", None)
    if held is None:
        return _looked_up(kinds)
    config = held.get(kinds)
    if config is None:
        config = held[kinds] = _looked_up(kinds)
    return config


@contextmanager
def held_config() -> Iterator[None]:
    """Within, :func:`current_config` on this thread gives the configuration in effect at the first look,
    without looking at the file again: the many plugin lookups of one command (a BML block scheduled and
    realized) see one configuration, for one look. Nested, the outermost holds."""
    if getattr(_held, "configs", None) is not None:
        yield
        return
    _held.configs = {}
    try:
        yield
    finally:
        _held.configs = None


_held = threading.local()  # .configs: kinds -> Config while held_config() holds on this thread, else None


def _looked_up(kinds: frozenset[str]) -> Config:
    path = config_path()
    try:
        status = os.stat(path)
    except OSError:
        return _absent(path)
    return _cached(path, (status.st_mtime_ns, status.st_ctime_ns, status.st_size, status.st_ino), kinds)


@lru_cache(maxsize=8)
def _absent(path: Path) -> Config:
    return Config(path)
