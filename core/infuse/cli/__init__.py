"""The ``infuse`` command line. Sub-commands come from plugins through the ``infuse_commands`` hook.

Exit codes: 0 ok; 2 bad input or usage; 3 the input cannot be used for that; 1 a bug.
No traceback reaches the user unless ``INFUSE_DEBUG=1`` is set.
"""
from __future__ import annotations

import argparse
import os
import sys
import traceback

from .. import __version__, registry
from ..errors import InfuseError


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # usage errors exit 2 with one line, like bad input
        self.print_usage(sys.stderr)
        print(f"infuse: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="infuse", description="Turn any humanoid 3D model into an animated character.")
    parser.add_argument("--version", action="version", version=f"infuse {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, command in sorted(registry.commands().items()):
        p = sub.add_parser(name, help=command.help, description=command.help)
        command.add_arguments(p)
        p.set_defaults(_run=command.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
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
