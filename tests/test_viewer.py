"""``infuse view`` without a browser: vendored three.js, targets sidecars, what each file becomes for the
page, the server's routes and the command line (serving, Ctrl-C, the offline file, errors)."""
from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

import infuse
from corpus_data import corpus_file
from infuse.canonical import CANONICAL_NAMES
from infuse.cli import main
from infuse.errors import InputError, MissingFeatureError
from infuse.mapping import map_skeleton
from infuse import three as vendor
from infuse_viewer import content
from infuse_viewer.page import BASE64_TYPE, VIEWER_SPECIFIER
from infuse_viewer.server import Site, ViewerServer
from infuse_viewer.targets import parse_targets, to_file_frame
from viewer_support import TARGETS, glb_animation_names, write_tone

INFUSE = Path(sys.executable).with_name("infuse")
BVH = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_002.bvh"
ROBOT = "adibkn1-robot/RobotExpressive.glb"
IMPORT = re.compile(r"""^[ \t]*(?:import|export)\b[^;'"]*?\bfrom[ \t]*['"]([^'"\n]+)['"]""", re.M)


# -- three.js -----------------------------------------------------------------------------------------
def test_vendored_modules_import_only_each_other():
    v = vendor.ensure_vendor()
    assert {"three", "three/addons/loaders/GLTFLoader.js", "three/addons/controls/OrbitControls.js"} <= set(v.modules)
    for spec in v.modules:
        text = v.source(spec).decode("utf-8")
        for imported in IMPORT.findall(text):
            assert imported in v.modules, f"{spec} imports {imported!r}, which the import map does not name"
    assert "REVISION" in v.source("three").decode() + v.source("three/build/three.core.js").decode()


def test_vendor_copy_is_made_from_the_npm_package(tmp_path):
    source = vendor.three_source_dir()
    assert source is not None, "make setup installs the npm package three"
    v = vendor.ensure_vendor(source, tmp_path / "vendor")
    assert v.version == json.loads((source / "package.json").read_text())["version"]
    original = (source / "build/three.module.js").read_text()
    assert "from './three.core.js'" in original
    assert "from './three.core.js'" not in v.source("three").decode()
    assert "from 'three/build/three.core.js'" in v.source("three").decode()


def test_missing_three_says_to_run_make_setup(tmp_path):
    with pytest.raises(MissingFeatureError, match="make setup") as err:
        vendor.ensure_vendor(tmp_path / "no-three", tmp_path / "vendor")
    assert err.value.exit_code == 3


# -- targets ------------------------------------------------------------------------------------------
def test_targets_points_tracks_and_defaults():
    doc = dict(TARGETS, door=[1, 2, 3], look={"position": [0, 1, 2], "kind": "gaze", "from": "eyeball_left"})
    parsed = {t["name"]: t for t in parse_targets(doc)}
    assert parsed["door"] == {"name": "door", "kind": "point", "from": None, "times": [0.0], "positions": [[1.0, 2.0, 3.0]]}
    assert parsed["gaze"]["kind"] == "gaze" and parsed["gaze"]["from"] == "skullbase"
    assert parsed["reach_right"]["kind"] == "reach" and parsed["reach_right"]["from"] == "r_wrist"
    assert parsed["reach_right"]["times"] == [0.0, 1.0, 2.0]
    assert parsed["look"]["from"] == "eyeball_left"
    turned = {t["name"]: t for t in to_file_frame(list(parsed.values()), facing_turned=True)}
    assert turned["door"]["positions"] == [[-1.0, 2.0, -3.0]]


@pytest.mark.parametrize("doc, place", [
    ([1, 2, 3], None),
    ({"a": [1, 2]}, "a.position"),
    ({"a": [1, 2, float("nan")]}, "a.position"),
    ({"a": {"times": [0, 1], "positions": [[0, 0, 0]]}}, "a"),
    ({"a": {"times": [0, 0], "positions": [[0, 0, 0], [1, 1, 1]]}}, "a.times[1]"),
    ({"a": {"position": [0, 0, 0], "kind": "stare"}}, "a.kind"),
    ({"a": {"position": [0, 0, 0], "from": "LeftHand"}}, "a.from"),
    ({"a": {"position": [0, 0, 0], "colour": "red"}}, "a.colour"),
])
def test_malformed_targets_name_the_place(doc, place):
    with pytest.raises(InputError) as err:
        parse_targets(doc, "t.targets.json")
    assert err.value.place == place and err.value.file == "t.targets.json"


# -- what the page gets -------------------------------------------------------------------------------
def test_joint_nodes_follow_the_readers_names():
    nodes = [{"name": "Hips"}, {}, {"name": "Arm"}, {"name": "Arm"}, {"name": "Arm_7"}]
    # the reader calls the unnamed node "node1" and the second "Arm" "Arm_3"
    assert content.joint_nodes(nodes, ["Hips", "node1", "Arm", "Arm_3", "Arm_7"]) == \
        {"Hips": 0, "node1": 1, "Arm": 2, "Arm_3": 3, "Arm_7": 4}


def test_bvh_becomes_a_glb_with_its_joints_and_mapping():
    bvh = corpus_file(BVH)
    asset = infuse.load(bvh)
    prepared = content.prepare(content.Source(bvh))
    doc = content.glb_json(prepared.glb)
    assert [a["name"] for a in doc["animations"]] == list(asset.motions) == prepared.info["clips"]
    mapping = map_skeleton(asset)
    joints = [j for j in prepared.info["joints"] if not j.get("tip")]
    assert [j["name"] for j in joints] == list(asset.skeleton.names)
    for j, joint in enumerate(joints):
        assert doc["nodes"][joint["node"]]["name"] == joint["name"]
        parent = asset.skeleton.parents[j]
        assert joint["parent"] == parent
        names = [n for n, v in mapping.joints.items() if v == joint["name"]]
        assert joint["canonical"] == names
        if names:
            assert joint["confidence"] == pytest.approx(min(mapping.confidence[n] for n in names), abs=1e-3)
            assert joint["low"] == (joint["confidence"] < content.LOW_CONFIDENCE)
    tips = [j for j in prepared.info["joints"] if j.get("tip")]
    assert len(tips) == len(asset.skeleton.end_site_parents)
    assert prepared.info["mapping"]["mapped"] == sum(mapping.joints[n] is not None for n in CANONICAL_NAMES)


def test_a_root_left_behind_is_not_a_bone():
    # a root joint that stays at the origin while the hips run: its link to the hips stretches
    bvh = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_run_masculinity_001.bvh")
    asset = infuse.load(bvh)
    free = content.stretching_links(asset)
    assert free[asset.skeleton.index["Hips"]] and free.sum() == 1


def test_audio_and_targets_found_beside_the_model(tmp_path):
    glb = tmp_path / "robot.glb"
    glb.symlink_to(corpus_file(ROBOT))
    write_tone(tmp_path / "robot.wav")
    write_tone(tmp_path / "robot.Wave.wav")
    write_tone(tmp_path / "Dance.wav")
    (tmp_path / "robot.targets.json").write_text(json.dumps(TARGETS))
    prepared = content.prepare(content.Source(glb))
    assert dict((k, p.name) for k, p in prepared.audio) == {"*": "robot.wav", "Wave": "robot.Wave.wav", "Dance": "Dance.wav"}
    assert [t["name"] for t in prepared.info["targets"]] == list(TARGETS)
    assert prepared.glb == corpus_file(ROBOT).read_bytes()  # a GLB is sent as it is


# -- server -------------------------------------------------------------------------------------------
def _get(url: str, headers: dict | None = None):
    with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=60) as r:
        return r.status, r.headers, r.read()


def test_server_routes(tmp_path):
    glb = tmp_path / "robot.glb"
    glb.symlink_to(corpus_file(ROBOT))
    wav = write_tone(tmp_path / "robot.wav")
    (tmp_path / "broken.glb").write_bytes(b"glTF not really")
    v = vendor.ensure_vendor()
    with ViewerServer(Site(content.sources(tmp_path), v, "test")) as server:
        assert server.url.startswith("http://127.0.0.1:")
        status, headers, page = _get(server.url)
        assert status == 200 and headers["Content-Type"].startswith("text/html")
        importmap = json.loads(re.search(rb'<script type="importmap">(.*?)</script>', page, re.S)[1])
        for spec, url in importmap["imports"].items():
            status, headers, body = _get(server.url.rstrip("/") + url)
            assert headers["Content-Type"].startswith("text/javascript") and body
        assert VIEWER_SPECIFIER in importmap["imports"]
        # entries: broken.glb first (sorted), robot second
        with pytest.raises(urllib.error.HTTPError) as err:
            _get(server.url + "entries/0/info.json")
        assert err.value.code == 422 and "broken.glb" in json.loads(err.value.read())["error"]
        _, _, info = _get(server.url + "entries/1/info.json")
        info = json.loads(info)
        assert info["clips"] == glb_animation_names(glb) and info["audio"] == {"*": "/entries/1/audio/0.wav"}
        _, _, model = _get(server.url + "entries/1/model.glb")
        assert model == glb.read_bytes()
        status, headers, part = _get(server.url + "entries/1/audio/0.wav", {"Range": "bytes=100-199"})
        assert status == 206 and part == wav.read_bytes()[100:200]
        assert headers["Content-Range"] == f"bytes 100-199/{wav.stat().st_size}"
        for missing in ("entries/9/info.json", "entries/1/audio/5.wav", "vendor/../../etc/passwd", "static/page.html"):
            with pytest.raises(urllib.error.HTTPError) as err:
                _get(server.url + missing)
            assert err.value.code == 404


# -- command line -------------------------------------------------------------------------------------
def test_view_serves_until_interrupted():
    robot = corpus_file(ROBOT)
    proc = subprocess.Popen([str(INFUSE), "view", str(robot), "--no-open", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        url = re.search(r"http://127\.0\.0\.1:\d+/", line)
        assert url, line + proc.stderr.read()
        status, _, _ = _get(url[0])
        assert status == 200
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=90)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "stopped" in out and "Traceback" not in err


def test_view_html_writes_one_file(tmp_path):
    out = tmp_path / "robot.html"
    assert main(["view", str(corpus_file(ROBOT)), "--html", str(out)]) == 0
    html = out.read_text(encoding="utf-8")
    modules = re.findall(rf'<script type="{BASE64_TYPE}" data-module="([^"]+)"', html)
    assert set(modules) == set(vendor.ensure_vendor().modules) | {VIEWER_SPECIFIER}
    data = json.loads(re.search(r'<script type="application/json" id="infuse-data">(.*?)</script>', html, re.S)[1])
    assert data["mode"] == "offline" and data["entries"][0]["info"]["clips"] == glb_animation_names(corpus_file(ROBOT))
    assert not re.search(r'(src|href)="https?:', html)
    assert not list(tmp_path.glob(".*part*"))  # written atomically: no temporary file left


@pytest.mark.parametrize("case, says", [
    ("missing file", "file not found"),
    ("empty folder", "no .glb files"),
    ("bad targets", "not a JSON targets file"),
    ("bad threshold", "between 0 and 1"),
])
def test_view_errors_are_one_line(tmp_path, capsys, case, says):
    out = tmp_path / "o.html"
    robot = str(corpus_file(ROBOT))
    (tmp_path / "bad.targets.json").write_text("{")
    argv = {
        "missing file": ["view", str(tmp_path / "missing.bvh")],
        "empty folder": ["view", str(tmp_path)],
        "bad targets": ["view", robot, "--targets", str(tmp_path / "bad.targets.json")],
        "bad threshold": ["view", robot, "--low-confidence", "2"],
    }[case]
    assert main(argv + ["--html", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("infuse: warning:")]
    assert len(err) == 1 and says in err[0], err
    assert not out.exists()
