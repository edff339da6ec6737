"""The contract between infuse and its plugins: every hook a plugin may implement.

A plugin is a module with functions marked ``@infuse.hookimpl`` whose names match the specs
below. It is found through an entry point in the group of its kind (:data:`infuse.registry.KINDS`);
the built-in features register the same way. Every hook returns a list of descriptors (see
:mod:`infuse.plugin_types`). A marked function whose name is not below is reported as a misspelled
hook and the plugin is skipped.
"""
from __future__ import annotations

import pluggy

hookspec = pluggy.HookspecMarker("infuse")
hookimpl = pluggy.HookimplMarker("infuse")


@hookspec
def infuse_readers():
    """Return a list of :class:`~infuse.plugin_types.Reader` for the file formats this plugin reads."""


@hookspec
def infuse_writers():
    """Return a list of :class:`~infuse.plugin_types.Writer` for the file formats this plugin writes."""


@hookspec
def infuse_mappers():
    """Return a list of :class:`~infuse.plugin_types.Mapper` (skeleton -> canonical joint names)."""


@hookspec
def infuse_retargeters():
    """Return a list of :class:`~infuse.plugin_types.Retargeter` (motion on A -> motion on B)."""


@hookspec
def infuse_controllers():
    """Return a list of :class:`~infuse.plugin_types.ControllerFactory` (controller kinds of the runtime)."""


@hookspec
def infuse_behaviour_packs():
    """Return a list of :class:`~infuse.plugin_types.BehaviourPack` (each names its manifest)."""


@hookspec
def infuse_tts_engines():
    """Return a list of :class:`~infuse.plugin_types.TTSEngine` (text-to-speech engines)."""


@hookspec
def infuse_bml_behaviours():
    """Return a list of :class:`~infuse.plugin_types.BMLBehaviour` (handlers of BML elements)."""


@hookspec
def infuse_bml_generators():
    """Return a list of :class:`~infuse.plugin_types.BMLGenerator` (add behaviours to BML blocks before scheduling)."""


@hookspec
def infuse_commands():
    """Return a list of :class:`~infuse.plugin_types.Command` to add to the ``infuse`` CLI."""
