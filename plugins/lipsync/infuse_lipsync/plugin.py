"""Registers ``infuse speak`` (entry point group ``infuse.commands``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Command

from . import command


@hookimpl
def infuse_commands():
    return [Command("speak", "say a text with a character: writes the lip-sync animation, the WAV and the phoneme/viseme "
                             "timeline", command.add_arguments, command.run)]
