"""Publishing into a new environment (marked ``venv``: it builds one, about a minute): infuse installed from this
checkout, then a pack's wheel made by the three commands and one project of every plugin kind installed into it."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from infuse.packs import load_pack
from infuse.scaffold.templates import KINDS

from corpus_data import corpus_file
from fresh_venv import locked, pip_install, shared_venv

pytestmark = pytest.mark.venv

BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data"
INFUSE = Path(sys.executable).with_name("infuse")  # this checkout's, where the author works


def run(command, cwd) -> str:
    proc = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


@pytest.fixture(scope="module")
def environment(tmp_path_factory):
    """The new environment, the lock to hold while installing into it, and a working folder outside every
    project (a project's own package folder would shadow the installed one)."""
    venv, lock = shared_venv(tmp_path_factory)
    elsewhere = tmp_path_factory.mktemp("elsewhere")
    return venv, lock, elsewhere


def test_three_commands_publish_a_pack_into_a_new_environment(environment, tmp_path):
    """pack new (the Bandai feminine takes), pack build --wheel, pip install of the wheel: infuse packs lists the
    pack from the new environment and infuse infuse retargets it onto X Bot."""
    venv, lock, elsewhere = environment
    source = corpus_file(BANDAI)
    xbot = corpus_file("runxaway-models/Xbot.glb")
    run([INFUSE, "pack", "new", "bandai-fem", "--import", "bvh", source, "--glob", "*_feminine_*.bvh"], tmp_path)
    project = tmp_path / "bandai-fem"
    out = run([INFUSE, "pack", "build", "--wheel"], project)
    (wheel,) = (project / "dist").glob("*.whl")
    assert wheel.name == "infuse_anim_pack_bandai_fem-0.1.0-py3-none-any.whl" and f"wrote {wheel}" in out

    built = load_pack(project / "infuse_pack_bandai_fem" / "pack")
    spaces = {group: t.dimension for group, t in built.tessellations().items()}
    assert built.built and len(built.analysis["clips"]) == 7 and spaces

    with locked(lock):
        pip_install(venv, ["--no-index", str(wheel)])
    listed = {p["name"]: p for p in json.loads(run([venv / "bin" / "infuse", "packs", "--json"], elsewhere))}
    pack = listed["bandai-fem"]
    assert pack["built"] and pack["clips"] == 7 and pack["blend_spaces"] == spaces
    assert Path(pack["manifest"]).is_relative_to(venv)  # the installed copy, not the project
    out = run([venv / "bin" / "infuse", "infuse", xbot, "--packs", "bandai-fem", "-o", tmp_path / "cache"], elsewhere)
    assert "bandai-fem 0.1.0 (locomotion): 7 clips" in out
    assert all(f"    {group}: " in out for group in spaces) and all(c["name"] in out for c in built.analysis["clips"])
    where = run([venv / "bin" / "python", "-c", "import infuse; print(infuse.__file__)"], elsewhere)
    assert Path(where.strip()).is_relative_to(venv)  # infuse itself is the new environment's
    out = run([venv / "bin" / "python", "-m", "pytest", "-q", "-p", "no:cacheprovider", project / "tests"], elsewhere)
    assert "2 passed" in out  # the project's own tests, on the installed pack


def test_a_new_plugin_of_every_kind_installs_lists_and_passes_its_tests(environment, tmp_path):
    venv, lock, elsewhere = environment
    projects = {}
    for kind in KINDS:
        name = f"my-{kind}"
        run([INFUSE, "plugin", "new", kind, name], tmp_path)
        projects[kind] = tmp_path / name
    with locked(lock):
        pip_install(venv, [str(p) for p in projects.values()])
    rows = [line.split() for line in run([venv / "bin" / "infuse", "plugins"], elsewhere).splitlines()]
    for kind in KINDS:
        assert [f"my-{kind}", kind, f"infuse-anim-my-{kind}", "0.1.0", "ok"] in rows
    proc = subprocess.run([str(venv / "bin" / "python"), "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           *(str(p / "tests") for p in projects.values())], cwd=elsewhere, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stdout[-3000:]
    written = sum(f.read_text().count("\ndef test_") for p in projects.values() for f in (p / "tests").glob("test_*.py"))
    assert f"{written} passed" in proc.stdout and written >= 2 * len(KINDS), proc.stdout[-3000:]
