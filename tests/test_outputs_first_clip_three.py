"""The clip a command makes is what Blender and three.js play: the first animation of the glb it
writes (Blender makes it the active action; three.js code plays ``gltf.animations[0]``), checked
in the file and in three.js (the viewer page in headless Chromium loads the file with three.js's
GLTFLoader and plays ``animations[0]``), for ``retarget``, ``speak``, ``batch`` and ``run`` outputs."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from corpus_data import REPO, corpus_file, require_corpus
from infuse.cli import main
from infuse_gltf.container import parse_file
from infuse_viewer.content import sources
from infuse_viewer.server import Site, ViewerServer
from infuse.three import ensure_vendor
from viewer_support import ViewerPage, chromium_context

WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
BRAD = "smartbody/mesh/brad/Brad.dae"
XBOT = "runxaway-models/Xbot.glb"
RPM = "talkinghead/avatars/brunette-t.glb"


@pytest.fixture(scope="module")
def outputs(tmp_path_factory) -> dict[Path, str]:
    """Files written by the commands, each with the name of the clip it made."""
    require_corpus()
    folder = tmp_path_factory.mktemp("first-clip")
    (folder / "cast").mkdir()
    (folder / "cast" / "Xbot.glb").symlink_to(corpus_file(XBOT))
    (folder / "mocap").mkdir()
    (folder / "mocap" / "walk.bvh").symlink_to(corpus_file(WALK))
    (folder / "Xbot.glb").symlink_to(corpus_file(XBOT))
    (folder / "avatar.glb").symlink_to(corpus_file(RPM))
    scene = re.findall(r"^```toml\n(.*?)^```", (REPO / "docs/quickstart.md").read_text(encoding="utf-8"), flags=re.M | re.S)
    (folder / "meeting.toml").write_text(scene[0], encoding="utf-8")
    # Brad's own 12 s rest clip follows the new one: it must not be the one played
    runs = [["retarget", str(corpus_file(WALK)), "--to", str(corpus_file(BRAD)), "-o", str(folder / "brad.glb"), "--keep-clips"],
            ["speak", str(folder / "avatar.glb"), "Hello there.", "-o", str(folder / "hello.glb")],
            ["batch", str(folder / "cast"), "--motions", str(folder / "mocap"), "-o", str(folder / "batch")],
            ["run", str(folder / "meeting.toml"), "-o", str(folder / "meeting")]]
    for argv in runs:
        assert main(argv) == 0, argv
    return {folder / "brad.glb": "dataset-1_walk_normal_001", folder / "hello.glb": "speech",
            folder / "batch" / "Xbot" / "walk.glb": "walk", folder / "meeting" / "ann.glb": "scene",
            folder / "meeting" / "bob.glb": "scene"}


def test_the_new_clip_is_the_first_animation(outputs):
    for path, clip in outputs.items():
        names = [a["name"] for a in parse_file(path).json["animations"]]
        assert names[0] == clip, (path.name, names)
    assert [a["name"] for a in parse_file(next(iter(outputs))).json["animations"]] == ["dataset-1_walk_normal_001", "Brad"]


def test_three_js_plays_the_new_clip(outputs):
    with chromium_context() as browser:
        for path, clip in outputs.items():
            with ViewerServer(Site(sources(path), ensure_vendor(), path.name)) as server, \
                    ViewerPage(browser, server.url) as view:
                state = view.state()
                assert state["clips"][0] == clip and state["clip"] == clip, (path.name, state["clips"])
                assert view.errors == []
