"""CLI: ``infuse packs``, ``infuse pack build|show|import|new|test``, ``infuse infuse CHARACTER --packs ...``."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from ..errors import UsageError
from ..hookspecs import hookimpl
from ..plugin_types import Command
from .build import build_pack, summary
from .importers import FIRST_VERSION, import_bvh_folder, import_smartbody
from .infusion import infuse_character
from .manifest import KINDS
from .pack import installed_packs, load_pack
from .publish import add_build_parser, add_new_parser, run_build, run_new
from .trial_command import add_test_parser, run_test

DEFAULT_CACHE = Path("~/.cache/infuse/infusions")


def _packs_args(p) -> None:
    p.add_argument("--json", action="store_true", help="print a JSON document")


def _packs(args) -> int:
    rows = []
    for name, installed in sorted(installed_packs().items()):
        pack = load_pack(installed.manifest)
        doc = pack.analysis
        rows.append({"name": name, "version": pack.version, "kind": pack.kind, "clips": len(pack.manifest.clips),
                     "built": pack.built, "manifest": str(pack.manifest.path), "description": pack.manifest.description,
                     "blend_spaces": {g: t["dimension"] for g, t in (doc or {}).get("tessellations", {}).items()}})
    if args.json:
        json.dump(rows, sys.stdout, indent=1)
        print()
        return 0
    if not rows:
        print("no behaviour packs installed")
    for r in rows:
        spaces = ", ".join(f"{g} {d}D" for g, d in r["blend_spaces"].items()) or (
            "not built" if not r["built"] else "no blend space")
        print(f"{r['name']:<20} {r['version']:<8} {r['kind']:<10} {r['clips']:>3} clips  {spaces}  {r['description']}")
    return 0


def _pack_args(p) -> None:
    sub = p.add_subparsers(dest="pack_action", required=True)
    add_build_parser(sub)
    add_new_parser(sub)
    add_test_parser(sub)
    s = sub.add_parser("show", help="print a built pack's clips, parameters, tessellation and checks")
    s.add_argument("pack", help="pack folder, manifest or installed pack name")
    i = sub.add_parser("import", help="copy a SmartBody behaviour set or BVH clips into a pack folder with its manifest")
    i.add_argument("source_kind", choices=["smartbody", "bvh"])
    i.add_argument("source", help="SmartBody behaviour-set folder, or a folder of BVH files")
    i.add_argument("-o", "--output", required=True, help="pack folder to create (outside the source)")
    i.add_argument("--name", help="pack name")
    i.add_argument("--glob", default="*.bvh", help="BVH files to take (e.g. '*_feminine_*.bvh')")
    i.add_argument("--version", dest="pack_version", default=FIRST_VERSION, help=f"pack version (default {FIRST_VERSION})")
    i.add_argument("--kind", choices=KINDS, default="locomotion", help="what BVH clips show (default locomotion)")
    i.add_argument("--no-build", action="store_true", help="only write the manifest")


def _pack(args) -> int:
    if args.pack_action == "build":
        return run_build(args)
    if args.pack_action == "new":
        return run_new(args)
    if args.pack_action == "test":
        return run_test(args)
    if args.pack_action == "show":
        print(summary(load_pack(args.pack)))
        return 0
    if args.source_kind == "smartbody":
        manifest = import_smartbody(args.source, args.output, name=args.name, version=args.pack_version)
    else:
        manifest = import_bvh_folder(args.source, args.output, name=args.name, pattern=args.glob, kind=args.kind,
                                     version=args.pack_version)
    print(f"wrote {manifest}")
    if not args.no_build:
        pack = build_pack(manifest)
        print(summary(pack))
    return 0


def _infuse_args(p) -> None:
    from ..cli.builtin import add_read_options
    from ..cli.map_command import add_mapping_options

    p.add_argument("character", help="character file (glb, BVH, sk, ...)")
    p.add_argument("--packs", required=True, help="comma-separated pack names, folders or manifests")
    p.add_argument("-o", "--output", help=f"cache folder or .npz file (default {DEFAULT_CACHE})")
    p.add_argument("--no-cache", action="store_true", help="neither read nor write a cache")
    add_mapping_options(p)
    add_read_options(p)


def _infuse(args) -> int:
    from ..cli.builtin import load_from_args
    from ..cli.map_command import mapping_from_args
    from ..asset import Character

    names = [n.strip() for n in args.packs.split(",") if n.strip()]
    if not names:
        raise UsageError("--packs names no pack")
    asset = load_from_args(args, "character")
    mapping = mapping_from_args(args, asset)
    cache = None if args.no_cache else (args.output or DEFAULT_CACHE)
    infusion = infuse_character(Character(Path(args.character).stem, asset), names, mapping=mapping, cache=cache)
    how = "loaded from the cache" if infusion.cached else "infused"
    print(f"{args.character}: {len(asset.skeleton.names)} joints, {how} in {infusion.seconds:.3f} s")
    for name, space in infusion.spaces.items():
        print(f"  {name} {space.version} ({space.kind}): {len(space.clips)} clips")
        for group, t in space.tessellations.items():
            print(f"    {group}: {t.describe()}")
            for label, point in zip(t.labels, t.points):
                values = "  ".join(f"{c} {v:+7.3f}" for c, v in zip(t.coordinates, point))
                print(f"      {label:<32} {values}")
    if infusion.cache_file is not None:
        print(f"cache {infusion.cache_file}")
    return 0


@hookimpl
def infuse_commands():
    return [
        Command("packs", "list installed behaviour packs", _packs_args, _packs),
        Command("pack", "build, show, import or start a behaviour pack (pack new, pack build --wheel)", _pack_args, _pack),
        Command("infuse", "map a character, retarget behaviour packs onto it and cache its blend spaces", _infuse_args, _infuse),
    ]
