"""three.js for the pages infuse serves (the viewer, the live page), taken from the npm package ``three`` that ``make setup`` installs.

The project ships no copy of three.js. At first use the modules the page needs (``three``, the
glTF loader, orbit controls and whatever they import) are copied from the installed package into
``static/vendor/three/`` beside this module (not under version control), with their relative
imports rewritten into bare specifiers (``./three.core.js`` -> ``three/build/three.core.js``) so an
import map can resolve every module, also from blob URLs inside a single offline HTML file.

Where the package is looked for, in order: ``$INFUSE_THREE_DIR`` (a folder holding three's
``package.json``), then ``<venv>/tools/node_modules/three`` (``make setup``).
"""
from __future__ import annotations

import json
import os
import re
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from infuse.errors import MissingFeatureError

THREE_VERSION = "0.187.0"  # the version scripts/setup.sh installs
ENV_THREE_DIR = "INFUSE_THREE_DIR"
VENDOR_DIR = Path(__file__).resolve().parent / "static" / "vendor"
ENTRY_MODULES = ("build/three.module.js", "examples/jsm/loaders/GLTFLoader.js", "examples/jsm/controls/OrbitControls.js")
MANIFEST = "manifest.json"

# import/export statements at the start of a line (doc comments such as " * @three_import ..." are not)
_STATIC_IMPORT = re.compile(r"""^([ \t]*(?:import|export)\b[^;'"]*?\bfrom[ \t]*)(['"])([^'"\n]+)\2""", re.M)
_BARE_IMPORT = re.compile(r"""^([ \t]*import[ \t]*)(['"])([^'"\n]+)\2""", re.M)


@dataclass(frozen=True)
class Vendor:
    """The vendored modules: ``modules`` maps each import specifier to its file under ``root``."""

    root: Path
    version: str
    modules: dict[str, str]

    def path(self, specifier: str) -> Path:
        return self.root / self.modules[specifier]

    def source(self, specifier: str) -> bytes:
        return self.path(specifier).read_bytes()


def specifier_of(relative: str) -> str:
    """The bare import specifier of a file of the three package (path relative to the package root)."""
    if relative == "build/three.module.js":
        return "three"
    if relative.startswith("examples/jsm/"):
        return "three/addons/" + relative[len("examples/jsm/"):]
    return "three/" + relative


def _relative_of(specifier: str) -> str | None:
    """The package file a bare specifier names, or ``None`` for a specifier outside three."""
    if specifier == "three":
        return "build/three.module.js"
    if specifier.startswith("three/addons/"):
        return "examples/jsm/" + specifier[len("three/addons/"):]
    if specifier.startswith("three/build/"):
        return specifier[len("three/"):]
    return None


def three_source_dir() -> Path | None:
    """The installed npm package ``three`` (a folder with its package.json), or ``None``."""
    candidates = []
    if os.environ.get(ENV_THREE_DIR):
        candidates.append(Path(os.environ[ENV_THREE_DIR]))
    candidates.append(Path(sys.prefix) / "tools" / "node_modules" / "three")
    for folder in candidates:
        if (folder / "package.json").is_file() and (folder / ENTRY_MODULES[0]).is_file():
            return folder
    return None


def _package_version(folder: Path) -> str:
    return str(json.loads((folder / "package.json").read_text(encoding="utf-8")).get("version", "?"))


def collect_modules(source: Path) -> dict[str, bytes]:
    """Every module the entry modules reach, as {package-relative path: source with bare specifiers}."""
    out: dict[str, bytes] = {}
    pending = list(ENTRY_MODULES)
    while pending:
        relative = pending.pop()
        if relative in out:
            continue
        file = source / relative
        if not file.is_file():
            raise MissingFeatureError(source, f"three.js module {relative} is missing; run `make setup`")
        text = file.read_text(encoding="utf-8")
        base = Path(relative).parent

        def rewrite(match: re.Match) -> str:
            spec = match.group(3)
            if spec.startswith("."):
                target = os.path.normpath((base / spec).as_posix()).replace(os.sep, "/")
                spec = specifier_of(target)
            target = _relative_of(spec)
            if target is None:
                raise MissingFeatureError(source, f"{relative} imports {spec!r}, which is not part of three")
            pending.append(target)
            return f"{match.group(1)}{match.group(2)}{spec}{match.group(2)}"

        text = _STATIC_IMPORT.sub(rewrite, text)
        text = _BARE_IMPORT.sub(rewrite, text)
        out[relative] = text.encode("utf-8")
    return out


def _write_vendor(source: Path, target: Path) -> None:
    """Copy the rewritten modules into ``target`` (a fresh folder renamed into place)."""
    modules = collect_modules(source)
    target.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".vendor.", dir=target.parent))
    try:
        staging.chmod(0o755)
        for relative, data in modules.items():
            file = staging / "three" / relative
            file.parent.mkdir(parents=True, exist_ok=True)
            file.write_bytes(data)
        if (source / "LICENSE").is_file():
            shutil.copyfile(source / "LICENSE", staging / "three" / "LICENSE")
        manifest = {"version": _package_version(source),
                    "modules": {specifier_of(r): "three/" + r for r in sorted(modules)}}
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
        if target.exists():
            old = target.with_name(f".{target.name}.old.{os.getpid()}")
            target.rename(old)
            shutil.rmtree(old, ignore_errors=True)
        staging.rename(target)
    except OSError:
        shutil.rmtree(staging, ignore_errors=True)
        if not (target / MANIFEST).is_file():  # another process may have won the race
            raise


def _read_manifest(target: Path) -> dict | None:
    try:
        manifest = json.loads((target / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not all((target / f).is_file() for f in manifest.get("modules", {}).values()):
        return None
    return manifest


def ensure_vendor(source: Path | None = None, target: Path = VENDOR_DIR) -> Vendor:
    """The vendored three.js, copied from ``source`` (default :func:`three_source_dir`) when missing or stale.

    Raises :class:`~infuse.errors.MissingFeatureError` (exit code 3) when neither a copy nor the
    npm package is there.
    """
    source = source if source is not None else three_source_dir()
    if source is not None and not (source / "package.json").is_file():
        source = None
    manifest = _read_manifest(target)
    if source is not None and (manifest is None or manifest.get("version") != _package_version(source)):
        try:
            _write_vendor(source, target)
        except OSError as exc:
            raise MissingFeatureError(target, f"cannot copy three.js here ({exc.strerror or exc}); "
                                              f"run `make setup` as the owner of this folder") from None
        manifest = _read_manifest(target)
    if manifest is None:
        raise MissingFeatureError(None, f"the viewer needs three.js: run `make setup` (it installs the npm package "
                                        f"three@{THREE_VERSION}), or set {ENV_THREE_DIR} to an installed three package folder")
    return Vendor(target, str(manifest["version"]), dict(manifest["modules"]))
