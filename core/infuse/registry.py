"""Finds plugins through entry points and asks them, through one pluggy manager, what they offer.

Each kind of plugin has an entry-point group, a hook of :mod:`infuse.hookspecs` and a descriptor type
of :mod:`infuse.plugin_types` (:data:`KINDS`). A kind's plugins are imported the first time that kind
is asked for, and a file is read importing only the readers that claim its extension
(:func:`table_for_file`, from :mod:`infuse.plugin_index`).

- :func:`table` (kind) is every descriptor of a kind by name; :func:`get` (kind, name=None) is one,
  the kind's default when no name is given (:func:`default_name`).
- Two plugins offering the same name is a clash: a warning names both, and the winner is the plugin
  registered by the program (:meth:`PluginSet.register`), else the distribution the configuration
  file prefers (``[prefer.KIND]``, :mod:`infuse.config`), else the first by distribution name and
  entry-point name, the same in every environment.
- A BML behaviour kind maps to the controller that realizes it through :func:`realizer` (its own
  precedence, described there).
- A plugin that fails to import, implements a hook infuse does not declare (a misspelled name, found by
  pluggy's ``check_pending``), raises in its hook or returns something other than its kind's
  descriptors is reported once on stderr and skipped, as is a hook function left unmarked; the rest
  keeps working.
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from functools import lru_cache
from importlib.metadata import EntryPoint
from pathlib import Path
from typing import Any

import pluggy

from . import hookspecs
from .config import current_config
from .errors import UsageError
from .plugin_index import distribution, entry_points_of, offers
from .plugin_types import (
    BehaviourPack, BMLBehaviour, BMLGenerator, Command, ControllerFactory, Mapper, Reader, Retargeter, TTSEngine, Writer,
    normalized_extension,
)


@dataclass(frozen=True)
class Kind:
    """One kind of plugin: its entry-point group, its hook, its descriptor type and its built-in default name."""

    name: str
    group: str
    hook: str
    descriptor: type
    default: str | None = None

    @property
    def environment_variable(self) -> str:
        """The variable that sets this kind's default, e.g. ``INFUSE_DEFAULT_MAPPER``."""
        return "INFUSE_DEFAULT_" + self.name.upper().replace("-", "_")


#: Plugin kind -> its description.
KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("reader", "infuse.readers", "infuse_readers", Reader),
    Kind("writer", "infuse.writers", "infuse_writers", Writer),
    Kind("mapper", "infuse.mappers", "infuse_mappers", Mapper, "heuristic"),
    Kind("retargeter", "infuse.retargeters", "infuse_retargeters", Retargeter, "default"),
    Kind("controller", "infuse.controllers", "infuse_controllers", ControllerFactory),
    Kind("behaviour-pack", "infuse.behaviour_packs", "infuse_behaviour_packs", BehaviourPack),
    Kind("tts", "infuse.tts", "infuse_tts_engines", TTSEngine, "espeak"),
    Kind("bml-behaviour", "infuse.bml_behaviours", "infuse_bml_behaviours", BMLBehaviour),
    Kind("bml-generator", "infuse.bml_generators", "infuse_bml_generators", BMLGenerator),
    Kind("command", "infuse.commands", "infuse_commands", Command),
)}
#: The names of :data:`KINDS`: what the configuration file's sections may name.
KIND_NAMES = frozenset(KINDS)

#: The distribution name given to plugins registered by the program rather than installed.
PROGRAM = "(program)"


@dataclass
class PluginRecord:
    """One entry point: where it came from and whether it loaded."""

    name: str
    kind: str
    distribution: str
    version: str
    module: str
    error: str | None = None


def entry_point_record(ep: EntryPoint, kind: str) -> PluginRecord:
    dist = distribution(ep)
    version = (ep.dist.version if ep.dist else None) or "?"
    return PluginRecord(ep.name, kind, dist, version, ep.value)


def kind_of(kind: str) -> Kind:
    try:
        return KINDS[kind]
    except KeyError:
        raise UsageError(f"no plugin kind {kind!r}; the kinds are {', '.join(KINDS)}") from None


class PluginSet:
    """The loaded plugins, their pluggy manager, and the descriptors they offer."""

    def __init__(self) -> None:
        self.manager = pluggy.PluginManager("infuse")
        self.manager.add_hookspecs(hookspecs)
        self._records: list[PluginRecord] = []
        self._records_by_key: dict[tuple, PluginRecord] = {}
        self._loaded: set[str] = set()
        self._order: dict[str, tuple] = {}  # pluggy plugin name -> its rank among providers of a name
        self._reported: set[str] = set()
        # kind -> (the configuration and the hook implementations it was made from, its key, the table)
        self._tables: dict[str, tuple[Any, list, tuple, dict[str, Any]]] = {}

    @property
    def records(self) -> list[PluginRecord]:
        """Every entry point of every kind (all are loaded), in kind order."""
        for kind in KINDS:
            self.load_kind(kind)
        return sorted(self._records, key=lambda r: list(KINDS).index(r.kind))

    def loaded(self, kind: str) -> bool:
        """Whether every plugin of ``kind`` has been imported."""
        return kind in self._loaded

    def load_kind(self, kind: str) -> None:
        """Import and register the plugins of the entry-point group of ``kind`` (once)."""
        if kind in self._loaded:
            return
        self._loaded.add(kind)
        for ep in entry_points_of(kind_of(kind).group):
            self.load_entry_point(ep, kind)

    def load_entry_point(self, ep: EntryPoint, kind: str) -> Any | None:
        """Import one entry point's module and register it; ``None`` (and a warning) when it is broken."""
        record = entry_point_record(ep, kind)
        known = self._records_by_key.setdefault((kind, record.distribution, ep.name, ep.value), record)
        if known is record:
            self._records.append(record)
        elif known.error is not None:
            return None
        record = known
        try:
            module = ep.load()
        except Exception as exc:  # a broken third-party plugin must not stop infuse
            record.error = f"{type(exc).__name__}: {exc}"
            self.report(f"plugin {ep.name!r} ({record.distribution}, group {ep.group}) failed to load and is skipped: "
                        f"{record.error}")
            return None
        if self.manager.is_registered(module):
            return module
        name = f"{record.distribution}:{ep.value}"
        try:
            self._register(module, name)
        except pluggy.PluginValidationError as exc:
            record.error = f"invalid plugin: {exc}"
            self.report(f"plugin {ep.name!r} ({record.distribution}, group {ep.group}) is invalid and is skipped: {exc}")
            return None
        self._order[name] = (1, record.distribution, ep.name)
        return module

    def register(self, module: Any, name: str | None = None) -> None:
        """Register a plugin module directly (for tests and embedding applications).

        It wins every name it shares with an installed plugin. Raises ``pluggy.PluginValidationError``
        when it implements a hook infuse does not declare.
        """
        name = name or getattr(module, "__name__", None) or repr(module)
        self._register(module, name)
        self._order[name] = (0, PROGRAM, name)

    def unregister(self, module: Any) -> None:
        """Remove a plugin registered with :meth:`register`."""
        name = self.manager.get_name(module)
        self.manager.unregister(module)
        self._order.pop(name, None)

    def _register(self, module: Any, name: str) -> None:
        try:
            self.manager.register(module, name=name)
            self.manager.check_pending()
        except pluggy.PluginValidationError:
            if self.manager.is_registered(module):
                self.manager.unregister(module)
            raise
        marked = {caller.name for caller in self.manager.get_hookcallers(module) or ()}
        for attr in vars(hookspecs):
            if attr.startswith("infuse_") and attr not in marked and callable(getattr(module, attr, None)):
                self.report(f"plugin {name!r} defines {attr}() without @infuse.hookimpl: infuse does not call it")

    def report(self, message: str) -> None:
        """Print a warning on stderr, once per process."""
        if message not in self._reported:
            self._reported.add(message)
            print(f"infuse: warning: {message}", file=sys.stderr)

    def offers(self, kind: str) -> list[tuple[str, list]]:
        """(pluggy plugin name, descriptors) of each registered plugin implementing the hook of ``kind``, in
        precedence order."""
        caller = getattr(self.manager.hook, kind_of(kind).hook)
        out = [(impl.plugin_name, self.offered_by(impl.plugin, kind)) for impl in caller.get_hookimpls()]
        out.sort(key=lambda entry: self._rank(entry[0]))
        return out

    def offered_by(self, plugin: Any, kind: str) -> list:
        """The descriptors of ``kind`` one registered plugin offers; [] (and a warning) when its hook raises.

        The hook is called through the manager on this plugin alone, so one that raises is skipped alone.
        """
        spec = kind_of(kind)
        plugin_name = self.manager.get_name(plugin)
        others = [p for p in self.manager.get_plugins() if p is not plugin]
        try:
            results = self.manager.subset_hook_caller(spec.hook, others)()
        except Exception as exc:
            self.report(f"plugin {plugin_name!r} failed in {spec.hook} and is skipped: {type(exc).__name__}: {exc}")
            return []
        items = []
        for result in results:
            for item in result or ():
                if isinstance(item, spec.descriptor) and isinstance(getattr(item, "name", None), str) and item.name:
                    items.append(item)
                else:
                    self.report(f"plugin {plugin_name!r} returned {type(item).__name__} from {spec.hook}, "
                                f"not a named {spec.descriptor.__name__}; it is skipped")
        return items

    def table(self, kind: str, complete: bool = True) -> dict[str, Any]:
        """Every descriptor of ``kind`` by name; a name offered twice is a clash (see the module docstring).

        ``complete=False`` leaves out the plugins of the kind not imported yet.
        """
        if complete:
            self.load_kind(kind)
        caller = getattr(self.manager.hook, kind_of(kind).hook)
        config = current_config(KIND_NAMES)
        impls = caller.get_hookimpls()
        cached = self._tables.get(kind)
        if cached is not None and cached[0] is config and cached[1] == impls:  # the very same inputs
            return cached[3]
        prefer = config.prefer.get(kind, {})
        key = (config.path, tuple(sorted(prefer.items())), *(id(impl.plugin) for impl in impls))
        if cached is not None and cached[2] == key:
            self._tables[kind] = (config, impls, key, cached[3])
            return cached[3]
        offered: dict[str, list[tuple[str, Any]]] = {}
        for plugin_name, items in self.offers(kind):
            for item in items:
                offered.setdefault(item.name, []).append((plugin_name, item))
        table = {}
        for name, candidates in offered.items():
            table[name] = self._winner(kind, name, candidates, prefer.get(name))
        self._tables[kind] = (config, impls, key, table)
        return table

    def distribution_of(self, kind: str, descriptor: Any) -> str:
        """The distribution offering ``descriptor`` (one of ``kind``), ``"?"`` when none registered offers it."""
        for plugin_name, items in self.offers(kind):
            if descriptor in items:
                return self._rank(plugin_name)[1]
        return "?"

    def _rank(self, plugin_name: str) -> tuple:
        return self._order.get(plugin_name, (2, plugin_name, ""))

    def _winner(self, kind: str, name: str, candidates: list[tuple[str, Any]], preferred: str | None) -> Any:
        if len(candidates) == 1 or self._rank(candidates[0][0])[0] == 0:  # the program's own plugin is deliberate
            return candidates[0][1]
        owners = [(self._rank(plugin_name)[1], plugin_name.split(":", 1)[-1]) for plugin_name, _ in candidates]
        return candidates[choose(kind, name, owners, preferred, self.report)][1]


def choose(kind: str, name: str, owners: list[tuple[str, str]], preferred: str | None, report) -> int:
    """Which of several plugins offering ``name`` wins: the index into ``owners`` ((distribution, module) in
    precedence order): the configuration's preference, else the first, with a warning through ``report``."""
    distributions = [dist for dist, _ in owners]
    if preferred in distributions:
        return distributions.index(preferred)
    listed = " and ".join(f"{dist} ({module})" for dist, module in owners)
    report(f"{len(owners)} {kind} plugins are named {name!r}: {listed}; using {distributions[0]}'s "
           f"(choose with [prefer.{kind}] {name} = \"DISTRIBUTION\" in {current_config(KIND_NAMES).path})")
    return 0


@lru_cache(maxsize=1)
def plugins() -> PluginSet:
    """The process-wide plugin set; each kind is loaded from its entry points on first use."""
    return PluginSet()


def default_name(kind: str) -> tuple[str | None, str]:
    """The default plugin name of ``kind`` and what set it.

    Precedence: the environment variable ``INFUSE_DEFAULT_<KIND>`` (``INFUSE_DEFAULT_MAPPER``), then
    ``[defaults]`` in the configuration file, then the kind's built-in default (:data:`KINDS`).
    """
    spec = kind_of(kind)
    from_env = os.environ.get(spec.environment_variable)
    if from_env:
        return from_env, spec.environment_variable
    config = current_config(KIND_NAMES)
    if kind in config.defaults:
        return config.defaults[kind], f"[defaults] {kind} in {config.path}"
    return spec.default, "built-in default"


def table(kind: str) -> dict[str, Any]:
    """Every installed descriptor of ``kind`` (``"reader"``, ``"mapper"``...) by name."""
    return plugins().table(kind)


def get(kind: str, name: str | None = None) -> Any:
    """The descriptor of ``kind`` called ``name``, or the kind's default (:func:`default_name`).

    Raises :class:`~infuse.errors.UsageError` naming the installed ones when there is no such plugin.
    """
    chosen, source = (name, None) if name else default_name(kind)
    found = table(kind)
    if chosen is None:
        raise UsageError(f"name a {kind}: there is no default {kind}; installed: {', '.join(sorted(found)) or 'none'}")
    if chosen not in found:
        why = f" (the default, from {source})" if source else ""
        raise UsageError(f"no {kind} named {chosen!r}{why}; installed: {', '.join(sorted(found)) or 'none'}")
    return found[chosen]


@lru_cache(maxsize=256)
def realizer_variable(kind: str) -> str:
    """The variable that names the controller realizing BML behaviour ``kind``: ``INFUSE_DEFAULT_CONTROLLER_GAZE``."""
    return "INFUSE_DEFAULT_CONTROLLER_" + "".join(c if c.isalnum() else "_" for c in kind.upper())


def realizer(kind: str) -> ControllerFactory | None:
    """The installed controller that realizes BML behaviours of ``kind`` (an activation's ``controller``),
    or None when none does.

    Candidates are the controllers whose :attr:`~infuse.plugin_types.ControllerFactory.behaviour_kinds`
    hold ``kind``. The first of these wins:

    1. the controller named by ``INFUSE_DEFAULT_CONTROLLER_<KIND>``, else by ``[defaults.controller]``
       in the configuration file (:class:`UsageError` when it names no candidate);
    2. a controller that replaces the one named after the kind (it lists ``kind`` in ``realizes``
       under another name), over the one named after it;
    3. among several replacements, the first by name, with a warning naming them all and how to choose.
    """
    controllers = table("controller")
    variable = realizer_variable(kind)
    config = current_config(KIND_NAMES)
    chosen, source = os.environ.get(variable), variable
    inputs = (controllers, chosen, config)
    known = _REALIZERS.get(kind)
    if known is not None and known[0][0] is controllers and known[0][1] == chosen and known[0][2] is config:
        return known[1]
    candidates = [d for d in controllers.values() if kind in d.behaviour_kinds]
    if not chosen and kind in config.realizers:
        chosen, source = config.realizers[kind], f"[defaults.controller] {kind} in {config.path}"
    if chosen:
        for descriptor in candidates:
            if descriptor.name == chosen:
                _REALIZERS[kind] = (inputs, descriptor)
                return descriptor
        names = ", ".join(sorted(d.name for d in candidates)) or "none"
        raise UsageError(f"{source} names controller {chosen!r}, which does not realize BML {kind!r} behaviours; "
                         f"those that do: {names}")
    replacements = sorted((d for d in candidates if d.name != kind), key=lambda d: d.name)
    if not replacements:
        _REALIZERS[kind] = (inputs, candidates[0] if candidates else None)
        return candidates[0] if candidates else None
    _REALIZERS[kind] = (inputs, replacements[0])
    if len(replacements) > 1:
        listed = " and ".join(f"{d.name} ({plugins().distribution_of('controller', d)})" for d in replacements)
        plugins().report(f"{len(replacements)} controllers replace BML {kind!r} behaviours: {listed}; using "
                         f"{replacements[0].name} (choose with {variable}=NAME, or [defaults.controller] {kind} = "
                         f"\"NAME\" in {config.path})")
    return replacements[0]


#: BML behaviour kind -> ((the controller table, the variable's value, the configuration) it was chosen
#: from, the controller :func:`realizer` chose): made again when the variable's value differs or the table
#: or the configuration is another object (each is a new object whenever it changes; the plugin set that
#: made the table warns about several replacements once anyway).
_REALIZERS: dict[str, tuple[tuple, ControllerFactory | None]] = {}


def table_for_file(kind: str, path: str | Path, format: str | None = None) -> dict[str, Any]:
    """Readers (or writers) by name, holding the one for ``path``: the one named ``format``, else those
    claiming its extension.

    Imports only the plugins the index (:mod:`infuse.plugin_index`) says offer such a name or extension,
    and every plugin offering the same names, so clashes resolve as in :func:`table`; the whole kind
    when none does.
    """
    ps = plugins()
    if ps.loaded(kind):
        return ps.table(kind)
    extension = normalized_extension(path)

    def fits(name: str, extensions) -> bool:
        return name == format if format else extension in extensions

    everything = offers(kind)
    names = {o.name for o in everything if fits(o.name, o.extensions)}
    for offer in everything:
        if offer.name in names:
            ps.load_entry_point(offer.entry_point, kind)
    partial = ps.table(kind, complete=False)
    if any(fits(name, d.extensions) for name, d in partial.items()):
        return partial
    return ps.table(kind)


def extensions(kind: str) -> set[str]:
    """The file extensions the installed readers (or writers) claim, from the index of what plugins offer
    (:mod:`infuse.plugin_index`, no plugin imported), and those of the plugins already registered."""
    claimed = {e for offer in offers(kind) for e in offer.extensions}
    return claimed | {e for d in plugins().table(kind, complete=False).values() for e in d.extensions}


def readers() -> dict[str, Reader]:
    return table("reader")


def writers() -> dict[str, Writer]:
    return table("writer")


def mappers() -> dict[str, Mapper]:
    return table("mapper")


def retargeters() -> dict[str, Retargeter]:
    return table("retargeter")


def commands() -> dict[str, Command]:
    return table("command")
