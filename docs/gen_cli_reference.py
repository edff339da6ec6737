"""Write docs/cli.md from the real ``infuse`` argument parsers (every installed command).

    python docs/gen_cli_reference.py           # rewrite docs/cli.md
    python docs/gen_cli_reference.py --check   # exit 1 when docs/cli.md differs from the installed commands

The help text is formatted at a fixed width so the page does not depend on the terminal.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from infuse import registry
from infuse.cli import build_parser

OUTPUT = Path(__file__).resolve().parent / "cli.md"
WIDTH = 100

HEADER = """\
# Command line reference

Generated from the installed commands by `docs/gen_cli_reference.py`; do not edit by hand.
Every sub-command comes from a plugin through the `infuse_commands` hook (see
[Writing plugins](plugins.md)), so the list grows with what is installed: `infuse --help` shows
what a given installation offers.

Exit codes, for every command:

| code | meaning |
|---|---|
| 0 | done |
| 1 | a bug in infuse or a plugin (one line; set `INFUSE_DEBUG=1` for the traceback) |
| 2 | bad input or usage: one line naming the file, the place in it and the problem |
| 3 | the input cannot be used for that (not a humanoid, an optional extra missing...) |

Commands that read a file take `--units` and `--up-axis` to override what the file says or what
was guessed (see [Conventions](conventions.md)); commands that map a skeleton take `--mapper NAME`
and `--map MAP.json` (see [Skeleton mapping](mapping.md)).
"""


def _fixed_width(parser: argparse.ArgumentParser) -> None:
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=WIDTH, max_help_position=32)


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _distributions() -> dict[str, str]:
    """Command name -> the distribution that registers it."""
    plugins = registry.plugins()
    plugins.load_kind("command")
    out: dict[str, str] = {}
    for plugin_name, commands in plugins.offers("command"):  # in precedence order, as the registry picks
        for command in commands:
            out.setdefault(command.name, plugin_name.split(":", 1)[0])
    return out


def _section(path: list[str], parser: argparse.ArgumentParser, level: int, dists: dict[str, str]) -> list[str]:
    _fixed_width(parser)
    title = "infuse " + " ".join(path)
    lines = [f"{'#' * level} `{title}`", ""]
    if parser.description:
        lines += [parser.description[0].upper() + parser.description[1:] + ".", ""]
    if len(path) == 1 and path[0] in dists:
        lines += [f"From the `{dists[path[0]]}` distribution.", ""]
    lines += ["```text", _help_without_description(parser), "```", ""]
    for name, child in _subparsers(parser).items():
        if child.description is None:  # sub-actions declared with help= only
            child.description = _help_of(parser, name)
        lines += _section(path + [name], child, level + 1, dists)
    return lines


def _help_without_description(parser: argparse.ArgumentParser) -> str:
    description, parser.description = parser.description, None  # it heads the section instead
    try:
        return parser.format_help().rstrip()
    finally:
        parser.description = description


def _help_of(parser: argparse.ArgumentParser, name: str) -> str | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                if choice.dest == name:
                    return choice.help
    return None


def reference() -> str:
    parser = build_parser()
    _fixed_width(parser)
    commands = _subparsers(parser)
    dists = _distributions()
    lines = [HEADER, "## `infuse`", "", "```text", parser.format_help().rstrip(), "```", ""]
    for name in sorted(commands):
        lines += _section([name], commands[name], 2, dists)
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--check", action="store_true", help="compare instead of writing")
    check = args.parse_args(argv).check
    text = reference()
    if check:
        current = OUTPUT.read_text(encoding="utf-8") if OUTPUT.is_file() else ""
        if current != text:
            print(f"{OUTPUT.name} is out of date with the installed commands: run python docs/gen_cli_reference.py",
                  file=sys.stderr)
            return 1
        return 0
    OUTPUT.write_text(text, encoding="utf-8")
    print(f"wrote {OUTPUT.name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
