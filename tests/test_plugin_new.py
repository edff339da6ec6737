"""``infuse plugin new KIND NAME``: a project for every kind, registering in the kind's group, importing only the
public plugin API; bad requests exit 2 with one line. (Installed and tested in a new environment:
``test_publish_new_environment.py``.)"""
from __future__ import annotations

import ast
import tomllib

import pytest
from packaging.requirements import Requirement

import infuse
from infuse.api import is_public
from infuse.cli import main as cli_main
from infuse.registry import KINDS as REGISTRY_KINDS
from infuse.scaffold.distribution import CORE_DISTRIBUTION
from infuse.scaffold.templates import KINDS

from cli_errors import answer_lines
from test_plugin_api import imported_modules


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_project_of_every_kind(kind, tmp_path, capsys):
    assert cli_main(["plugin", "new", kind, "tip-top", "-o", str(tmp_path / "p")]) == 0
    project = tmp_path / "p"
    meta = tomllib.loads((project / "pyproject.toml").read_text())["project"]
    assert meta["name"] == "infuse-anim-tip-top" and meta["version"] == "0.1.0"
    assert meta["entry-points"] == {REGISTRY_KINDS[kind].group: {"tip-top": "infuse_tip_top.plugin"}}
    (core,) = [Requirement(r) for r in meta["dependencies"] if Requirement(r).name == CORE_DISTRIBUTION]
    assert infuse.__version__ in core.specifier
    plugin = project / "infuse_tip_top" / "plugin.py"
    hooks = [f.name for f in ast.parse(plugin.read_text()).body if isinstance(f, ast.FunctionDef)
             and any(getattr(d, "id", None) == "hookimpl" for d in f.decorator_list)]
    assert hooks == [REGISTRY_KINDS[kind].hook]
    for path in sorted(project.rglob("*.py")):
        compile(path.read_text(), str(path), "exec")  # no template placeholder is left unfilled
        assert "$" not in path.read_text(), path
    private = [m for _, m in imported_modules(plugin, "infuse_tip_top") if m.split(".")[0] == "infuse" and not is_public(m)]
    assert private == []
    (test_file,) = (project / "tests").glob("test_*.py")
    assert test_file.read_text().count("\ndef test_") >= 2
    assert "infuse-anim-tip-top" in (project / "README.md").read_text()
    assert f"({kind} tip-top)" in capsys.readouterr().out


def _error(capsys, argv, *needles) -> None:
    code = cli_main(argv)
    out = capsys.readouterr()
    (line,) = answer_lines(out.err)
    assert code == 2 and line.startswith("infuse: error:") and "Traceback" not in out.err, out.err
    assert all(n in line for n in needles), line


def test_bad_requests_exit_2_with_one_line(tmp_path, capsys):
    _error(capsys, ["plugin", "new", "behaviour-pack", "waves", "-o", str(tmp_path / "a")], "infuse pack new")
    _error(capsys, ["plugin", "new", "mapper", "heuristic", "-o", str(tmp_path / "b")], "already installed")
    _error(capsys, ["plugin", "new", "reader", "bvh", "-o", str(tmp_path / "c")], "'infuse_bvh'")
    _error(capsys, ["plugin", "new", "controller", "Tip_Top", "-o", str(tmp_path / "d")], "'Tip_Top'")
    _error(capsys, ["plugin", "new", "controller", "tip-top", "--description", 'says """hi"""', "-o", str(tmp_path / "f")],
           "one printable line")
    (tmp_path / "e").mkdir()
    (tmp_path / "e" / "mine.txt").write_text("mine")
    _error(capsys, ["plugin", "new", "controller", "tip-top", "-o", str(tmp_path / "e")], "already exists")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e"]
