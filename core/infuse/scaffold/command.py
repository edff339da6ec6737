"""CLI: ``infuse plugin new KIND NAME``, a new plugin project (see :mod:`infuse.scaffold.plugin`)."""
from __future__ import annotations

from ..hookspecs import hookimpl
from ..plugin_types import Command
from .templates import KINDS


def _plugin_args(p) -> None:
    sub = p.add_subparsers(dest="plugin_action", required=True)
    n = sub.add_parser("new", help="make a plugin project that installs, shows in 'infuse plugins' and tests itself")
    n.add_argument("kind", choices=[*sorted(KINDS), "behaviour-pack"], help="the kind of plugin (a behaviour pack: 'infuse pack new')")
    n.add_argument("name", help="plugin name: lower-case words joined by hyphens (e.g. studio-names)")
    n.add_argument("-o", "--output", help="project folder to create (default ./NAME)")
    n.add_argument("--description", help="one line saying what the plugin does")


def _plugin(args) -> int:
    from .plugin import new_plugin_project

    project = new_plugin_project(args.kind, args.name, args.output, args.description)
    print(f"wrote {project}/ ({args.kind} {args.name}); next: pip install -e {project} && infuse plugins && pytest {project}/tests")
    return 0


@hookimpl
def infuse_commands():
    return [Command("plugin", "start a plugin project: infuse plugin new KIND NAME", _plugin_args, _plugin)]
