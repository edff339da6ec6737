"""A new virtual environment with infuse installed from this checkout, made without the network.

The core and every plugin of ``plugins/`` are built and installed into it by pip (``--no-deps
--no-index``, not editable), so it sees none of this checkout's editable installs. The third-party
packages they need (numpy, scipy, ...) are not installed again: the new environment reaches the
ones of the running environment through a folder of links named in a ``.pth`` file. One such
environment serves every test of a run, whichever xdist worker runs it (:func:`shared_venv`).
"""
from __future__ import annotations

import fcntl
import os
import re
from contextlib import contextmanager
import subprocess
import sys
import tomllib
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: Packages the new environment needs beyond the runtime requirements: the build backend and the test runner.
TOOLS = ("setuptools", "wheel", "pytest")


def infuse_projects() -> list[Path]:
    """The core and the plugin projects of this checkout."""
    return [REPO] + sorted(p.parent for p in REPO.glob("plugins/*/pyproject.toml"))


def _requirement_name(requirement: str) -> str | None:
    """The distribution a requirement line names, None for one under an extra or an environment marker that is false."""
    if ";" in requirement:
        from packaging.markers import Marker

        marker = Marker(requirement.split(";", 1)[1])
        if "extra" in str(marker) or not marker.evaluate():
            return None
    return re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", requirement.strip())[0]


def third_party_closure(projects: list[Path]) -> list:
    """The installed distributions that ``projects`` need at run time, with their own requirements, and :data:`TOOLS`."""
    ours = set()
    seeds = list(TOOLS)
    for p in projects:
        table = tomllib.loads((p / "pyproject.toml").read_text(encoding="utf-8"))["project"]
        ours.add(table["name"].lower())
        seeds += table.get("dependencies", [])
    found, todo = {}, [s for s in (_requirement_name(r) for r in seeds) if s]
    while todo:
        name = todo.pop()
        key = re.sub(r"[-_.]+", "-", name).lower()
        if key in found or key in ours:
            continue
        try:
            dist = distribution(name)
        except PackageNotFoundError:
            continue  # an optional requirement this environment does without
        found[key] = dist
        todo += [n for n in (_requirement_name(r) for r in dist.requires or []) if n]
    return list(found.values())


def link_third_party(folder: Path, dists: list) -> None:
    """Link each distribution's top-level files (packages, modules, metadata) into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for dist in dists:
        site = Path(dist.locate_file(""))
        for top in {f.parts[0] for f in dist.files or [] if f.parts and f.parts[0] != ".."}:
            target = folder / top
            if not target.exists() and (site / top).exists():
                target.symlink_to(site / top)


def make_venv(root: Path, timeout_s: float = 120.0) -> Path:
    """Create the environment at ``root`` and install infuse into it; returns its ``bin`` folder."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(root)], check=True, timeout=timeout_s)
    python = root / "bin" / "python"
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    projects = infuse_projects()
    link_third_party(root / "third_party", third_party_closure(projects))
    (site / "third_party.pth").write_text(str(root / "third_party") + "\n")
    pip_install(root, [str(p) for p in projects], timeout_s)
    return root / "bin"


def pip_install(root: Path, targets: list[str], timeout_s: float = 120.0) -> None:
    """``pip install --no-deps --no-index --no-build-isolation TARGETS`` into the environment at ``root``."""
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(root / "bin" / "python"), "install", "--quiet",
                           "--no-deps", "--no-index", "--no-build-isolation", *targets],
                          capture_output=True, text=True, timeout=timeout_s)
    assert proc.returncode == 0, proc.stderr[-3000:]



@contextmanager
def locked(path: Path):
    """Hold an exclusive lock on ``path`` (created) for the ``with`` block: one process at a time."""
    with open(path, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def shared_venv(tmp_path_factory) -> tuple[Path, Path]:
    """The run's environment (built by the first test to ask, the others wait) and the lock that
    guards installing into it; the temporary folder is the one every xdist worker of the run shares."""
    root = tmp_path_factory.getbasetemp()
    root = root.parent if os.environ.get("PYTEST_XDIST_WORKER") else root
    venv, lock = root / "infuse-venv", root / "infuse-venv.lock"
    with locked(lock):
        if not (venv / "ready").is_file():
            make_venv(venv)
            (venv / "ready").write_text("")
    return venv, lock
