"""Every distribution of the repository is named by one scheme and depends on the core it is released with."""
from __future__ import annotations

import tomllib
from pathlib import Path

from packaging.requirements import Requirement

import infuse
from infuse.scaffold.distribution import CORE_DISTRIBUTION, core_requirement

ROOT = Path(__file__).resolve().parents[1]


def _projects() -> dict[Path, dict]:
    files = [ROOT / "pyproject.toml", *sorted(ROOT.glob("plugins/*/pyproject.toml")),
             *sorted(ROOT.glob("behaviour_libs/*/pyproject.toml")), *sorted(ROOT.glob("examples/*/pyproject.toml"))]
    return {f.parent: tomllib.loads(f.read_text(encoding="utf-8"))["project"] for f in files}


def test_the_core_is_infuse_anim_at_the_version_it_reports():
    core = _projects()[ROOT]
    assert core["name"] == CORE_DISTRIBUTION == "infuse-anim" and core["version"] == infuse.__version__


def test_every_other_distribution_is_infuse_anim_something_and_depends_on_this_core():
    projects = {p: t for p, t in _projects().items() if p != ROOT}
    assert len(projects) >= 20
    for folder, table in projects.items():
        prefix = f"{CORE_DISTRIBUTION}-pack-" if folder.parent.name == "behaviour_libs" else f"{CORE_DISTRIBUTION}-"
        assert table["name"].startswith(prefix), folder
        core = [Requirement(r) for r in table["dependencies"] if Requirement(r).name == CORE_DISTRIBUTION]
        assert [str(r) for r in core] == [core_requirement()], folder
        assert infuse.__version__ in core[0].specifier
        assert not any(Requirement(r).name == "infuse" for r in table["dependencies"]), folder  # an unrelated project


def test_every_distribution_declares_the_core_licence():
    projects = _projects()
    licence = projects[ROOT]["license"]
    assert licence == "MIT" and [f for f, t in projects.items() if t.get("license") != licence] == []
