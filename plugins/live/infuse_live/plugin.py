"""Registers ``infuse serve`` (entry point group ``infuse.commands``)."""
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
    return [Command("serve", "run a scene's characters live: BML in over WebSocket/HTTP, feedback, poses and VMC out",
                    _add_arguments, _run)]
