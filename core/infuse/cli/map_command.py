"""``infuse map FILE``: map a skeleton to the canonical joint names, show or save the map.

Every command that maps a skeleton offers the same two options through
:func:`add_mapping_options` / :func:`mapping_from_args`: ``--mapper NAME`` (an installed mapper
plugin) and ``--map map.json`` (a saved, possibly partial, hand-edited map).
"""
from __future__ import annotations

import json
import sys

from ..hookspecs import hookimpl
from ..mapping import DEFAULT_MAPPER, format_table, map_skeleton
from ..plugin_types import Command
from .builtin import add_read_options, load_from_args


def add_mapping_options(parser) -> None:
    """Add ``--mapper`` and ``--map`` to a sub-command's parser."""
    parser.add_argument("--mapper", help=f"mapper plugin that names the joints (default {DEFAULT_MAPPER}; see 'infuse plugins')")
    parser.add_argument("--map", dest="map_file", metavar="MAP.json",
                        help="saved joint map; names it leaves out are filled in by the mapper")


def mapping_from_args(args, source):
    """The :class:`~infuse.mapping.Mapping` of ``source`` (an Asset or a Skeleton) as the options ask."""
    return map_skeleton(source, mapper=getattr(args, "mapper", None),
                        saved_map=getattr(args, "map_file", None))


def _map_args(p) -> None:
    p.add_argument("file")
    add_mapping_options(p)
    p.add_argument("--json", action="store_true", help="print the mapping document")
    p.add_argument("--save", metavar="MAP.json", help="write the mapping document to this file")
    add_read_options(p)


def _map(args) -> int:
    asset = load_from_args(args)
    mapping = mapping_from_args(args, asset)
    if args.save:
        mapping.save(args.save)
    doc = mapping.to_dict(extras=False)
    if args.json:
        json.dump(doc, sys.stdout, indent=1, ensure_ascii=False)
        print()
        return 0
    count = sum(v is not None for v in doc["mapping"].values())
    print(f"{args.file}: {count} of {len(doc['mapping'])} canonical joints mapped by {mapping.mapper} "
          f"(overall confidence {mapping.overall_confidence:.2f})")
    print(format_table(mapping, list(doc["mapping"])))
    if mapping.unmapped:
        print(f"  unmapped joints ({len(mapping.unmapped)}): {', '.join(mapping.unmapped)}")
    if args.save:
        print(f"wrote {args.save}")
    return 0


@hookimpl
def infuse_commands():
    return [Command("map", "map a skeleton to the canonical joint names (show, save or complete a joint map)", _map_args, _map)]
