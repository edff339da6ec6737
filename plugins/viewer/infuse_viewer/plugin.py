"""Registers ``infuse view`` (entry point group ``infuse.commands``)."""
from __future__ import annotations

import infuse
from infuse.plugin_types import Command


def _add_arguments(parser):
    from .command import add_arguments

    add_arguments(parser)


def _run(args):
    from .command import run

    return run(args)


@infuse.hookimpl
def infuse_commands():
    return [Command("view", "show a character, its clips, mapping, audio and targets in a browser (or one HTML file)",
                    _add_arguments, _run)]
