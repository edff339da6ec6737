"""The core's own CLI commands (info, convert, plugins), registered as a plugin like any other."""
from __future__ import annotations

import json
import sys


from .. import fileio, registry
from ..hookspecs import hookimpl
from ..plugin_types import Command


def add_read_options(parser) -> None:
    """Options shared by every command that reads a file."""
    parser.add_argument("--units", help="override the file's length unit (m, cm, mm, dm, inch, ft, cmu)")
    parser.add_argument("--up-axis", choices=["Y", "Z"], help="override the file's up axis")
    parser.add_argument("--format", dest="read_format", help="reader name, when the extension is ambiguous")
    parser.add_argument("--allow-external", action="store_true",
                        help="let the file's references (buffers, images, media) lead outside its folder")


def read_options(args) -> dict:
    opts = {}
    if getattr(args, "units", None):
        opts["units"] = args.units
    if getattr(args, "up_axis", None):
        opts["up_axis"] = args.up_axis
    if getattr(args, "allow_external", False):
        opts["allow_external"] = True
    return opts


def load_from_args(args, path_attr: str = "file"):
    return fileio.load(getattr(args, path_attr), format=getattr(args, "read_format", None), **read_options(args))


def asset_summary(asset) -> dict:
    """The JSON document ``infuse info --json`` prints."""
    sk = asset.skeleton
    first = next(iter(asset.motions.values()), None)
    return {
        "file": str(asset.path),
        "format": asset.format,
        "joints": list(sk.names),
        "parents": [int(p) for p in sk.parents],
        "frames": first.num_frames if first else 0,
        "fps": first.fps if first else None,
        "clips": [{"name": n, "frames": m.num_frames, "fps": m.fps, "duration_s": round(m.duration, 6),
                   "animated_joints": int(m.animated_mask.sum()), "morph_targets": list(m.morph_names)}
                  for n, m in asset.motions.items()],
        "units": asset.source_units,
        "units_detected_by": asset.units_detected_by,
        "up_axis": asset.source_up_axis,
        "height_m": round(sk.height(), 6),
        "morph_targets": list(asset.morph_targets),
        "humanoid": dict(asset.humanoid),
        "warnings": list(asset.warnings),
        "meta": fileio.json_ready(asset.meta),
    }


def _info_args(p):
    p.add_argument("file")
    p.add_argument("--json", action="store_true", help="print a JSON document")
    p.add_argument("--max-lines", type=int, default=400, help="longest joint tree to print")
    add_read_options(p)


def _info(args) -> int:
    asset = load_from_args(args)
    summary = asset_summary(asset)
    if args.json:
        json.dump(summary, sys.stdout, indent=1)
        print()
        return 0
    print(f"{summary['file']}: {summary['format']}, {len(summary['joints'])} joints, "
          f"height {summary['height_m']:.3f} m, units {summary['units']} ({summary['units_detected_by']}), up {summary['up_axis']}")
    for c in summary["clips"]:
        tracks = "" if c["animated_joints"] == len(summary["joints"]) else f", {c['animated_joints']} joints animated"
        tracks += f", {len(c['morph_targets'])} morph weights" if c["morph_targets"] else ""
        print(f"  clip {c['name']!r}: {c['frames']} frames at {c['fps']:g} fps ({c['duration_s']:.2f} s){tracks}")
    if summary["morph_targets"]:
        print(f"  {len(summary['morph_targets'])} morph targets: {', '.join(summary['morph_targets'][:12])}"
              + (" ..." if len(summary["morph_targets"]) > 12 else ""))
    print(asset.skeleton.describe_tree(args.max_lines))
    return 0


def _convert_args(p):
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--to-format", help="writer name, when the output extension is ambiguous")
    add_read_options(p)


def _convert(args) -> int:
    asset = load_from_args(args, "input")
    fileio.save(asset, args.output, format=args.to_format)
    print(f"wrote {args.output}")
    return 0


def _plugins_args(p):
    p.add_argument("--json", action="store_true")


def _plugins(args) -> int:
    records = registry.plugins().records
    if args.json:
        json.dump([r.__dict__ for r in records], sys.stdout, indent=1)
        print()
        return 0
    rows = [("name", "kind", "distribution", "version", "status")]
    rows += [(r.name, r.kind, r.distribution, r.version, "ok" if r.error is None else f"BROKEN: {r.error}") for r in records]
    widths = [max(len(r[i]) for r in rows) for i in range(4)]
    for r in rows:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths)) + "  " + r[4])
    defaults = [(kind, *registry.default_name(kind)) for kind in registry.KINDS]
    print("defaults: " + ", ".join(f"{kind} {name} ({source})" for kind, name, source in defaults if name))
    kinds = sorted({k for d in registry.table("controller").values() for k in d.behaviour_kinds})
    chosen = [(kind, registry.realizer(kind)) for kind in kinds]
    replaced = [f"{kind} by {d.name}" for kind, d in chosen if d is not None and d.name != kind]
    if replaced:
        print("BML behaviours realized by another controller: " + ", ".join(replaced))
    return 0


@hookimpl
def infuse_commands():
    return [
        Command("info", "describe a character or motion file (joints, clips, units, morph targets)", _info_args, _info),
        Command("convert", "convert between file formats (BVH, glTF/GLB, ...)", _convert_args, _convert),
        Command("plugins", "list installed plugins: name, kind, distribution, version", _plugins_args, _plugins),
    ]
