"""Publishing packs: ``infuse pack new`` makes a complete project, ``pack import`` a self-contained pack folder,
``pack build --wheel`` checks the versions (the wheel in a new environment: ``test_publish_new_environment.py``)."""
from __future__ import annotations

import shutil
import zipfile
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement

import infuse
from infuse.cli import main as cli_main
from infuse.packs import load_pack, read_manifest
from infuse.packs.project import FIGURES_END, FIGURES_START
from infuse.scaffold.distribution import CORE_DISTRIBUTION, LICENSE_PLACEHOLDER

from cli_errors import answer_lines
from corpus_data import corpus_file

BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data"
FEMININE = "*_feminine_*.bvh"
EXAMPLE_PACK = Path(__file__).resolve().parents[1] / "examples" / "example_pack" / "infuse_example_pack" / "pack"


def _listing(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.stat().st_mtime_ns for p in folder.rglob("*")}


def _error(capsys, code: int, *needles: str) -> str:
    out = capsys.readouterr()
    (line,) = answer_lines(out.err)
    assert code == 2 and line.startswith("infuse: error:") and "Traceback" not in out.err, out.err
    for needle in needles:
        assert needle in line, line
    return line


@pytest.fixture(scope="module")
def bandai_project(tmp_path_factory):
    """``infuse pack new bandai-fem --import bvh BANDAI --glob FEMININE`` in a new folder; the source's listing before."""
    source = corpus_file(BANDAI)
    before = _listing(source.parent)
    root = tmp_path_factory.mktemp("projects")
    assert cli_main(["pack", "new", "bandai-fem", "--import", "bvh", str(source), "--glob", FEMININE,
                     "-o", str(root / "bandai-fem")]) == 0
    return root / "bandai-fem", source, before


def test_pack_new_writes_a_complete_project(bandai_project):
    project, source, before = bandai_project
    assert _listing(source.parent) == before  # the source is only read
    package = project / "infuse_pack_bandai_fem"
    manifest = read_manifest(package / "pack")
    takes = sorted(source.glob(FEMININE))
    assert [c.file.name for c in manifest.clips] == [t.name for t in takes]
    for path in [manifest.skeleton, *(c.file for c in manifest.clips)]:
        assert path.is_relative_to(package / "pack") and path.read_bytes() == (source / path.name).read_bytes()
    raw = tomllib.loads((package / "pack" / "manifest.toml").read_text())
    assert not any(Path(c["file"]).is_absolute() or ".." in c["file"] for c in raw["clips"])
    assert manifest.version == "0.1.0" and manifest.name == "bandai-fem"

    meta = tomllib.loads((project / "pyproject.toml").read_text())["project"]
    assert meta["name"] == "infuse-anim-pack-bandai-fem" and meta["version"] == manifest.version
    assert meta["entry-points"]["infuse.behaviour_packs"] == {"bandai-fem": "infuse_pack_bandai_fem.plugin"}
    (core,) = [Requirement(r) for r in meta["dependencies"] if Requirement(r).name == CORE_DISTRIBUTION]
    assert infuse.__version__ in core.specifier and "0.0.1" not in core.specifier
    assert meta["license"] == LICENSE_PLACEHOLDER and meta["license-files"] == ["LICENSE"]
    assert (project / "LICENSE").read_bytes() == (source.parent / "LICENSE").read_bytes()  # the dataset's licence

    pack = load_pack(package / "pack")
    assert pack.built and len(pack.analysis["clips"]) == len(takes) == 7
    readme = (project / "README.md").read_text()
    figures = readme[readme.index(FIGURES_START):readme.index(FIGURES_END)]
    for clip in pack.analysis["clips"]:  # the figures the builder measured, as it prints them
        assert clip["name"] in figures and f"speed {clip['parameters']['speed']:5.2f} m/s" in figures
    for group, tessellation in pack.tessellations().items():
        assert f"blend space {group}: {tessellation.describe()}" in figures
    assert "pip install infuse-anim-pack-bandai-fem" in readme


def test_pack_import_writes_a_self_contained_folder(tmp_path, capsys):
    source = corpus_file(BANDAI)
    assert cli_main(["pack", "import", "bvh", str(source), "--glob", "*_dash_*.bvh", "-o", str(tmp_path / "dash")]) == 0
    text = (tmp_path / "dash" / "manifest.toml").read_text()
    assert str(source) not in text and 'version = "0.1.0"' in text
    moved = tmp_path / "elsewhere"
    shutil.move(tmp_path / "dash", moved)  # a folder that names no file outside itself moves and stays built
    pack = load_pack(moved)
    assert pack.built and all(c.file.is_relative_to(moved) for c in pack.manifest.clips)
    capsys.readouterr()
    code = cli_main(["pack", "import", "bvh", str(source), "--glob", "*_dash_*.bvh", "-o", str(source)])
    _error(capsys, code, str(source), "must not be the folder its clips come from")
    assert not (source / "manifest.toml").exists()


def test_pack_new_from_a_smartbody_set_and_from_a_pack_folder(tmp_path):
    behaviour_set = corpus_file("smartbody/behaviorsets/reaching")
    assert cli_main(["pack", "new", "sb-reach", "--import", "smartbody", str(behaviour_set), "--license", "LicenseRef-SmartBody",
                     "-o", str(tmp_path / "sb-reach")]) == 0
    manifest = read_manifest(tmp_path / "sb-reach" / "infuse_pack_sb_reach" / "pack")
    assert manifest.kind == "reach" and manifest.skeleton.name == "skeleton.sk"
    assert len(manifest.clips) == len(list((behaviour_set / "motions").glob("*.skm")))
    assert tomllib.loads((tmp_path / "sb-reach" / "pyproject.toml").read_text())["project"]["license"] == "LicenseRef-SmartBody"
    assert (tmp_path / "sb-reach" / "LICENSE").is_file()

    assert cli_main(["pack", "new", "waves", "--from", str(EXAMPLE_PACK), "-o", str(tmp_path / "waves")]) == 0
    copy = load_pack(tmp_path / "waves" / "infuse_pack_waves" / "pack")
    original = load_pack(EXAMPLE_PACK)
    assert copy.built and copy.name == "waves" and copy.version == original.version
    assert [c["parameters"] for c in copy.analysis["clips"]] == [c["parameters"] for c in original.analysis["clips"]]
    assert not (tmp_path / "waves" / "LICENSE").exists()  # none lies beside the example

    # The same clips imported as a folder of BVH reaches: the hand is found from the motion, the figures agree.
    assert cli_main(["pack", "new", "bvh-waves", "--import", "bvh", str(EXAMPLE_PACK / "clips"), "--kind", "reach",
                     "-o", str(tmp_path / "bvh-waves")]) == 0
    imported = load_pack(tmp_path / "bvh-waves" / "infuse_pack_bvh_waves" / "pack")
    assert imported.kind == "reach" and {c["hand"] for c in imported.analysis["clips"]} == {"right"}
    by_name = {c["name"]: c["parameters"] for c in original.analysis["clips"]}
    assert all(c["parameters"] == pytest.approx(by_name[c["name"]], abs=1e-6) for c in imported.analysis["clips"])


def test_bad_requests_exit_2_with_one_line(tmp_path, capsys):
    source = str(corpus_file(BANDAI))
    _error(capsys, cli_main(["pack", "new", "Bandai Fem", "--import", "bvh", source, "-o", str(tmp_path / "x")]), "'Bandai Fem'")
    _error(capsys, cli_main(["pack", "new", "reaching", "--import", "bvh", source, "-o", str(tmp_path / "x")]), "already installed")
    _error(capsys, cli_main(["pack", "new", "fem", "--import", "bvh", source, "--version", "v1", "-o", str(tmp_path / "x")]),
           "'v1'", "PEP 440")
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "notes.txt").write_text("mine")
    _error(capsys, cli_main(["pack", "new", "fem", "--import", "bvh", source, "-o", str(tmp_path / "taken")]), "already exists")
    assert (tmp_path / "taken" / "notes.txt").read_text() == "mine"
    _error(capsys, cli_main(["pack", "new", "fem", "--import", "bvh", source, "--glob", "*.nothing", "-o", str(tmp_path / "y")]),
           "no BVH files matching")
    assert not (tmp_path / "y").exists()  # nothing half-made is left

    assert cli_main(["pack", "new", "fem", "--import", "bvh", source, "--glob", "*_dash_feminine_*.bvh",
                     "-o", str(tmp_path / "fem")]) == 0
    capsys.readouterr()
    pyproject = tmp_path / "fem" / "pyproject.toml"
    pyproject.write_text(pyproject.read_text().replace('version = "0.1.0"', 'version = "0.2.0"'))
    code = cli_main(["pack", "build", str(tmp_path / "fem"), "--wheel"])
    _error(capsys, code, "manifest.toml:pack.version", "'0.2.0'")
    assert not (tmp_path / "fem" / "dist").exists()

    # A pack folder that is no project's pack gets no wheel, even below some other project.
    assert cli_main(["pack", "import", "bvh", source, "--glob", "*_dash_feminine_*.bvh", "-o", str(tmp_path / "other" / "loose")]) == 0
    (tmp_path / "other" / "pyproject.toml").write_text('[project]\nname = "other"\nversion = "0.1.0"\n')
    capsys.readouterr()
    _error(capsys, cli_main(["pack", "build", str(tmp_path / "other" / "loose"), "--wheel"]), "not the pack of a pack project",
           "infuse pack new NAME --from")
    assert not (tmp_path / "other" / "dist").exists()



def test_the_wheel_holds_the_pack_and_nothing_left_from_an_earlier_build(tmp_path, capsys):
    source = str(corpus_file(BANDAI))
    project = tmp_path / "dash"
    assert cli_main(["pack", "new", "dash", "--import", "bvh", source, "--glob", "*_dash_*.bvh", "-o", str(project)]) == 0
    stale = project / "build" / "lib" / "infuse_pack_dash" / "stale.py"  # what an earlier setuptools build leaves
    stale.parent.mkdir(parents=True)
    stale.write_text("raise SystemExit('left over')\n")
    readme = project / "README.md"
    figures = readme.read_text()
    readme.write_text(figures.replace("check: all clips pass", "check: old figures"))
    capsys.readouterr()
    assert cli_main(["pack", "build", str(project / "infuse_pack_dash" / "pack"), "--wheel"]) == 0  # from inside the project
    out = capsys.readouterr().out
    assert readme.read_text() == figures and f"license is still {LICENSE_PLACEHOLDER}" in out
    (wheel,) = (project / "dist").glob("*.whl")
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        entry_points = z.read("infuse_anim_pack_dash-0.1.0.dist-info/entry_points.txt").decode()
    pack = load_pack(project / "infuse_pack_dash" / "pack")
    shipped = {f"infuse_pack_dash/pack/{p.relative_to(pack.manifest.folder).as_posix()}"
               for p in [pack.manifest.path, pack.manifest.analysis, pack.npz_path, *(c.file for c in pack.manifest.clips)]}
    assert shipped <= names and "infuse_pack_dash/plugin.py" in names
    assert "infuse_anim_pack_dash-0.1.0.dist-info/licenses/LICENSE" in names
    assert not any("stale" in n or n.startswith("tests/") for n in names)
    assert "[infuse.behaviour_packs]\ndash = infuse_pack_dash.plugin" in entry_points
