"""The ``infuse`` command line. Sub-commands come from plugins through the ``infuse_commands`` hook.

The list of commands and their help lines come from :mod:`infuse.cli.index` without importing any
plugin; only the plugin of the command that runs is imported.

Exit codes: 0 ok; 2 bad input or usage; 3 the input cannot be used for that; 1 a bug.
No traceback reaches the user unless ``INFUSE_DEBUG=1`` is set.
"""
from __future__ import annotations

import argparse
import os
import sys
import traceback
from collections.abc import Iterable

from .. import __version__
from ..errors import InfuseError


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # usage errors exit 2 with one line, like bad input
        self.print_usage(sys.stderr)
        print(f"infuse: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser(complete: Iterable[str] | None = None, listed: bool = True) -> argparse.ArgumentParser:
    """The ``infuse`` parser: every installed command with its help line, and the arguments of the
    commands named in ``complete`` (of every command when it is ``None``, importing every command plugin).
    ``listed=False`` leaves the commands out (for ``--version``)."""
    parser = _Parser(prog="infuse", description="Turn any humanoid 3D model into an animated character.")
    parser.add_argument("--version", action="version", version=f"infuse {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    if not listed:
        return parser
    from .index import command_index  # reads installed metadata: not for --version

    if complete is None:
        from .. import registry

        commands = registry.commands()
        help_lines = {name: command.help for name, command in commands.items()}
    else:
        commands = _load_commands(set(complete))
        help_lines = {name: offered[0].description for name, offered in command_index().items()}
    for name in sorted(help_lines | {n: c.help for n, c in commands.items()}):
        command = commands.get(name)
        help_line = command.help if command is not None else help_lines[name]
        p = sub.add_parser(name, help=help_line, description=help_line)
        if command is not None:
            command.add_arguments(p)
            p.set_defaults(_run=command.run)
    return parser


def _load_commands(names: set[str]) -> dict:
    """The installed commands among ``names`` (name -> Command), importing only their plugins."""
    from .index import command_index, load_command

    found = {}
    for name in names:
        offered = command_index().get(name)
        command = load_command(name, offered) if offered else None
        if command is None and offered:  # the index was out of date and has been rebuilt
            offered = command_index().get(name)
            command = load_command(name, offered) if offered else None
        if command is not None:
            found[name] = command
    return found


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    wanted = next((a for a in argv if not a.startswith("-")), None)  # the options before a command take no value
    listed = wanted is not None or "--version" not in argv
    try:
        parser = build_parser([wanted] if wanted else [], listed)
    except InfuseError as exc:  # a malformed configuration file
        print(f"infuse: error: {exc}", file=sys.stderr)
        return exc.exit_code
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except InfuseError as exc:
        print(f"infuse: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("infuse: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # a bug: one line unless debugging
        if os.environ.get("INFUSE_DEBUG"):
            traceback.print_exc()
        print(f"infuse: internal error (a bug; set INFUSE_DEBUG=1 for details): {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
