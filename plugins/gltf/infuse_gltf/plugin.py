"""Registers the glTF reader, writer and the ``validate-gltf`` command with infuse
(entry points ``infuse.readers``, ``infuse.writers``, ``infuse.commands``)."""
from __future__ import annotations

import infuse
from infuse.plugin_types import Command, Reader, Writer

EXTENSIONS = (".glb", ".gltf", ".vrm", ".vrma")


def _read(path, **options):
    from .reader import read

    return read(path, **options)


def _write(asset, path, **options):
    from .writer import write

    return write(asset, path, **options)


@infuse.hookimpl
def infuse_readers():
    return [Reader("gltf", EXTENSIONS, _read, "glTF 2.0 (.gltf/.glb), VRM 0.x/1.0 and VRM Animation")]


@infuse.hookimpl
def infuse_writers():
    return [Writer("gltf", EXTENSIONS, _write, "glTF 2.0 (.gltf/.glb) and VRM: the character with new clips")]


def _validate_args(parser) -> None:
    parser.add_argument("files", nargs="+", help=".glb/.gltf/.vrm/.vrma files")
    parser.add_argument("--max-messages", type=int, default=10, help="errors and warnings shown per file")


def _validate(args) -> int:
    """Exit 0 when no file has validator errors, 2 when one has (3 when the validator is missing)."""
    from pathlib import Path

    from . import validate

    for f in args.files:
        if not Path(f).is_file():
            raise infuse.InputError(f, None, "file not found")
    worst = 0
    for path, report in zip(args.files, validate.validate_files(args.files)):
        issues = report.get("issues", {})
        print(f"{path}: {issues.get('numErrors', 0)} errors, {issues.get('numWarnings', 0)} warnings, "
              f"{issues.get('numInfos', 0)} infos")
        shown = [m for m in issues.get("messages", []) if m.get("severity") in (0, 1)][:args.max_messages]
        for m in shown:
            level = "error" if m["severity"] == 0 else "warning"
            print(f"  {level} {m.get('code')} {m.get('pointer', '')}: {m.get('message')}")
        if issues.get("numErrors", 0):
            worst = 2
    return worst


@infuse.hookimpl
def infuse_commands():
    return [Command("validate-gltf", "check glTF/GLB/VRM files with the Khronos glTF validator", _validate_args, _validate)]
