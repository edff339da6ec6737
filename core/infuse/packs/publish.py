"""CLI of pack publishing: ``infuse pack new`` and ``infuse pack build [FOLDER] [--wheel]``.

``pack build`` takes a pack folder, a manifest or a pack project (default: the working folder); in a
project it builds every pack manifest and rewrites the README's figures, and ``--wheel`` then writes
the project's wheel.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import UsageError
from ..scaffold.distribution import LICENSE_PLACEHOLDER
from .build import build_pack, summary
from .manifest import KINDS, read_manifest
from .project import IMPORT_KINDS, new_pack_project, pack_manifests, refresh_figures
from .wheel import build_wheel, check_versions, find_project, project_table


def add_new_parser(sub) -> None:
    n = sub.add_parser("new", help="make an installable pack project from a pack folder or by importing clips")
    n.add_argument("name", help="pack name: lower-case words joined by hyphens (e.g. bandai-fem)")
    source = n.add_mutually_exclusive_group(required=True)
    source.add_argument("--from", dest="from_folder", metavar="FOLDER", help="a pack folder or manifest to copy")
    source.add_argument("--import", dest="import_source", nargs=2, metavar=("KIND", "SRC"),
                        help=f"import clips: KIND is {' or '.join(IMPORT_KINDS)}, SRC a BVH folder or a SmartBody behaviour set")
    n.add_argument("--glob", default="*.bvh", help="BVH files to take (e.g. '*_feminine_*.bvh')")
    n.add_argument("--kind", choices=KINDS, default="locomotion", help="what imported BVH clips show (default locomotion)")
    n.add_argument("-o", "--output", help="project folder to create (default ./NAME)")
    n.add_argument("--version", dest="pack_version", help="first version (default 0.1.0, or the copied pack's)")
    n.add_argument("--description", help="one line saying what the pack holds")
    n.add_argument("--license", help=f"SPDX licence expression of the clips (default {LICENSE_PLACEHOLDER}: fill it in)")
    n.add_argument("--mapper", help="mapper for the pack skeleton (default heuristic)")


def add_build_parser(sub) -> None:
    b = sub.add_parser("build", help="analyse a pack's clips and store the results in the pack; --wheel: the project's wheel")
    b.add_argument("folder", nargs="?", default=".", help="pack folder, manifest or pack project (default: here)")
    b.add_argument("--mapper", help="mapper for the pack skeleton (default heuristic)")
    b.add_argument("--wheel", action="store_true", help="then build the project's wheel (into PROJECT/dist)")
    b.add_argument("--dist", help="folder for the wheel (default PROJECT/dist)")


def run_new(args) -> int:
    kind, source = args.import_source if args.import_source else (None, None)
    project, pack = new_pack_project(args.name, from_folder=args.from_folder, import_kind=kind, source=source, pattern=args.glob,
                                     clip_kind=args.kind, dest=args.output, version=args.pack_version, description=args.description,
                                     license=args.license, mapper=args.mapper)
    print(summary(pack))
    print(f"wrote {project}/ (distribution {project_table(project)['name']}); next: cd {project} && infuse pack build --wheel")
    return 0


def run_build(args) -> int:
    folder = Path(args.folder)
    in_project = (folder / "pyproject.toml").is_file()
    manifests = pack_manifests(folder.resolve()) if in_project else [read_manifest(folder).path]
    if not manifests:
        raise UsageError(f"{folder}: a project without a pack (no */pack/manifest.toml)")
    project = folder.resolve() if in_project else (find_project(folder) if args.wheel else None)
    if args.wheel and project is not None:
        if not set(manifests) <= set(pack_manifests(project)):
            raise UsageError(f"{folder}: not the pack of a pack project ({project}/*/pack/manifest.toml); "
                             f"make one with 'infuse pack new NAME --from {folder}'")
        check_versions(project, manifests if in_project else pack_manifests(project))
    for manifest in manifests:
        pack = build_pack(manifest, mapper=args.mapper)
        print(summary(pack))
        print(f"wrote {pack.manifest.analysis}")
        if project is not None and refresh_figures(project / "README.md", pack):
            print(f"wrote the figures in {project / 'README.md'}")
    if args.wheel and project is not None:
        print(f"wrote {build_wheel(project, args.dist)}")
        if project_table(project).get("license", LICENSE_PLACEHOLDER) == LICENSE_PLACEHOLDER:
            print(f"note: {project / 'pyproject.toml'}: license is still {LICENSE_PLACEHOLDER}; "
                  "set the clips' licence before publishing")
    return 0
