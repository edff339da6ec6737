"""``infuse pack build --wheel``: the wheel of a pack project, made by pip through the project's own build backend.

The project is copied without its ``build/``, ``dist/`` and egg-info folders and built there, so a
file deleted from the project never lingers in the wheel from an earlier build. With setuptools 77
or later installed beside infuse the build uses it and needs no network (``--no-build-isolation``);
otherwise pip fetches the backend the project names.
"""
from __future__ import annotations

import importlib.metadata
import importlib.util
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

from ..errors import InputError, MissingFeatureError, UnusableInputError, UsageError
from .manifest import read_manifest

#: The first setuptools that reads a licence expression (``license = "CC-BY-4.0"``), as new projects write.
SETUPTOOLS_MAJOR = 77
#: What a build leaves in a project, never copied into the next build.
_BUILD_LEFTOVERS = shutil.ignore_patterns("build", "dist", "*.egg-info", "__pycache__", ".git", ".pytest_cache")


def _setuptools_major() -> int:
    """The major version of the setuptools beside infuse, 0 when there is none."""
    try:
        return int(importlib.metadata.version("setuptools").split(".")[0])
    except (importlib.metadata.PackageNotFoundError, ValueError):
        return 0


def find_project(folder: str | Path) -> Path:
    """The project holding ``folder``: the nearest folder at or above it with a ``pyproject.toml``."""
    start = Path(folder).resolve()
    for d in [start, *start.parents]:
        if (d / "pyproject.toml").is_file():
            return d
    raise UsageError(f"{folder}: no pyproject.toml here or above; make a pack project with 'infuse pack new'")


def project_table(project: Path) -> dict:
    """The ``[project]`` table of ``project/pyproject.toml``, checked for a name and a version."""
    path = project / "pyproject.toml"
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(path, None, f"not a TOML file: {exc}") from None
    table = doc.get("project")
    if not isinstance(table, dict):
        raise InputError(path, "project", "missing [project] table")
    for key in ("name", "version"):
        if not isinstance(table.get(key), str) or not table[key]:
            raise InputError(path, f"project.{key}", "expected a non-empty string")
    return table


def check_versions(project: Path, manifests: list[Path]) -> str:
    """The project's version, when every pack manifest in it has the same one; InputError names the one that differs."""
    version = project_table(project)["version"]
    for path in manifests:
        m = read_manifest(path)
        if m.version != version:
            raise InputError(m.path, "pack.version", f"{m.version!r} but pyproject.toml says {version!r}; give both the same version")
    return version


def build_wheel(project: str | Path, dist: str | Path | None = None) -> Path:
    """Build ``project``'s wheel into ``dist`` (default ``PROJECT/dist``); returns the wheel's path."""
    project = Path(project).resolve()
    table = project_table(project)
    if importlib.util.find_spec("pip") is None:
        raise MissingFeatureError(project, "building a wheel needs pip in this Python: python -m ensurepip")
    dist = Path(dist).resolve() if dist is not None else project / "dist"
    dist.mkdir(parents=True, exist_ok=True)
    isolation = ["--no-build-isolation"] if _setuptools_major() >= SETUPTOOLS_MAJOR else []
    with tempfile.TemporaryDirectory(prefix="infuse-wheel-") as tmp:
        source = Path(tmp) / project.name
        shutil.copytree(project, source, ignore=_BUILD_LEFTOVERS)
        out = Path(tmp) / "dist"
        proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", *isolation, "--quiet", "-w", str(out), str(source)],
                              capture_output=True, text=True)
        wheels = sorted(out.glob("*.whl"))
        if proc.returncode != 0 or len(wheels) != 1:
            lines = [ln.strip() for ln in (proc.stderr + proc.stdout).splitlines() if ln.strip()]
            reason = next((ln for ln in reversed(lines) if "error" in ln.lower()), lines[-1] if lines else "no wheel written")
            raise UnusableInputError(project / "pyproject.toml", f"building the wheel of {table['name']} failed: {reason}")
        target = dist / wheels[0].name
        shutil.copyfile(wheels[0], target)
    return target
