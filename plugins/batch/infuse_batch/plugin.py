"""Registers the ``infuse batch`` command."""
from __future__ import annotations

import infuse
from infuse.plugin_types import Command

from . import command


@infuse.hookimpl
def infuse_commands():
    return [Command("batch", "retarget motion folders onto many characters, or infuse them with packs, "
                             "on local processes or a Dask cluster", command.add_arguments, command.run)]
