"""The viewer page in real headless Chromium (Playwright): characters, clips, mapping overlay, audio,
targets, the offline HTML file, a folder of models and skeleton-only input."""
from __future__ import annotations

import json
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import infuse
from corpus_data import corpus_file
from infuse.cli import main
from infuse.mapping import map_skeleton
from infuse_viewer.content import LOW_CONFIDENCE, sources
from infuse_viewer.server import Site, ViewerServer
from infuse.three import ensure_vendor
from viewer_support import (TARGETS, ViewerPage, add_wave_clip, changed_fraction, chromium_context, glb_animation_names,
                            write_tone)

INFUSE = Path(sys.executable).with_name("infuse")
ROBOT = "adibkn1-robot/RobotExpressive.glb"
XBOT = "runxaway-models/Xbot.glb"
BVH = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_002.bvh"


@pytest.fixture(scope="module")
def browser():
    with chromium_context() as context:
        yield context


@pytest.fixture(scope="module")
def site_for():
    """The server's content for a path, made once per path in this module (files are read and mapped once)."""
    cache: dict[Path, Site] = {}

    def site(path: Path) -> Site:
        if path not in cache:
            cache[path] = Site(sources(path), ensure_vendor(), path.name)
        return cache[path]

    return site


@contextmanager
def viewing(browser, site: Site):
    """The page of ``site`` served on 127.0.0.1 and open in ``browser``."""
    with ViewerServer(site) as server, ViewerPage(browser, server.url) as view:
        yield view


@pytest.fixture(scope="module")
def xbot_folder(tmp_path_factory) -> Path:
    """Xbot with a wave clip added here, a tone with the same stem, a targets sidecar; and the robot beside it."""
    folder = tmp_path_factory.mktemp("viewer-xbot")
    infuse.save(add_wave_clip(infuse.load(corpus_file(XBOT))), folder / "Xbot_wave.glb")
    write_tone(folder / "Xbot_wave.wav")
    (folder / "Xbot_wave.targets.json").write_text(json.dumps(TARGETS), encoding="utf-8")
    (folder / "RobotExpressive.glb").symlink_to(corpus_file(ROBOT))
    return folder


def test_robot_clips_play_and_scrub(browser, site_for, tmp_path):
    robot = corpus_file(ROBOT)
    expected = glb_animation_names(robot)
    assert len(expected) == 14
    with viewing(browser, site_for(robot)) as view:
        assert view.clip_list() == expected
        state = view.state()
        assert state["clips"] == expected and state["clip"] == expected[0] and state["mode"] == "mesh"

        view.show_time(0.3)
        first = view.screenshot(tmp_path / "robot_0.3.png")
        view.show_time(1.6)
        second = view.screenshot(tmp_path / "robot_1.6.png")
        assert changed_fraction(first, second) > 0.002

        # a clip chosen in the list plays from 0 with its own length
        view.page.click('#clips li[data-clip="Wave"]')
        view.frames()
        state = view.state()
        assert state["clip"] == "Wave" and state["time"] < 0.5
        assert abs(state["duration"] - infuse.load(robot).motions["Wave"].duration) < 0.05
        assert view.errors == []


def test_mapping_overlay_names_and_low_confidence(browser, site_for):
    robot = corpus_file(ROBOT)
    mapping = map_skeleton(infuse.load(robot))
    by_joint: dict[str, list[str]] = {}
    for name, joint in mapping.joints.items():
        if joint is not None:
            by_joint.setdefault(joint, []).append(name)
    expected_low = {j for j, names in by_joint.items() if min(mapping.confidence[n] for n in names) < LOW_CONFIDENCE}
    assert expected_low, "the robot's mapping has low-confidence joints to show"
    with viewing(browser, site_for(robot)) as view:
        view.show_time(0.0)
        joints = view.page.evaluate("window.infuseViewer.jointsOnScreen()")
        assert {j["name"] for j in joints if j["low"]} == expected_low
        for j in joints:
            assert sorted(j["canonical"]) == sorted(by_joint.get(j["name"], []))
        assert view.page.eval_on_selector_all("#low-joints li", "items => items.length") == len(expected_low)

        # hovering a joint names it: take the mapped joint farthest on screen from any other
        shown = [j for j in joints if j["visible"]]
        xy = np.array([[j["x"], j["y"]] for j in shown])
        gaps = np.linalg.norm(xy[:, None] - xy[None], axis=-1) + np.eye(len(shown)) * 1e9
        target = next(shown[k] for k in np.argsort(-gaps.min(axis=1)) if shown[k]["canonical"])
        view.page.mouse.move(target["x"], target["y"])
        view.frames()
        tip = view.page.evaluate("window.infuseViewer.tip()")
        assert tip is not None and target["name"] in tip
        assert all(name in tip for name in target["canonical"])
        assert view.errors == []


def test_audio_follows_play_and_scrub(browser, site_for, xbot_folder):
    with viewing(browser, site_for(xbot_folder / "Xbot_wave.glb")) as view:
        page = view.page
        page.evaluate("window.infuseViewer.pause()")
        assert view.state()["audio"]["src"].endswith(".wav")

        def scrub(seconds: float) -> None:
            page.eval_on_selector("#timeline", f"el => {{ el.value = '{seconds}'; el.dispatchEvent(new Event('input')); }}")

        scrub(0.4)
        state = view.state()
        assert abs(state["time"] - 0.4) < 1e-6 and abs(state["audio"]["currentTime"] - 0.4) < 0.02
        page.click("#play")  # a click: the browser lets the sound start
        page.wait_for_function("window.infuseViewer.state().audio.currentTime > 0.55", timeout=60_000)
        assert view.state()["playing"]
        page.click("#play")
        assert view.state()["audio"]["paused"]
        scrub(1.25)
        state = view.state()
        assert abs(state["time"] - 1.25) < 1e-6 and abs(state["audio"]["currentTime"] - 1.25) < 0.02
        assert view.errors == []


def test_gaze_and_reach_targets(browser, site_for, xbot_folder, tmp_path):
    with viewing(browser, site_for(xbot_folder / "Xbot_wave.glb")) as view:
        view.show_time(0.5)
        targets = {t["name"]: t for t in view.state()["targets"]}
        assert set(targets) == set(TARGETS)
        assert targets["gaze"]["kind"] == "gaze" and targets["reach_right"]["kind"] == "reach"
        assert np.allclose(targets["gaze"]["position"], TARGETS["gaze"]["position"])
        track = TARGETS["reach_right"]
        halfway = 0.5 * np.add(track["positions"][0], track["positions"][1])
        assert np.allclose(targets["reach_right"]["position"], halfway, atol=1e-6)
        assert targets["gaze"]["linked"] and targets["reach_right"]["linked"]  # lines from skullbase and r_wrist
        labels = view.page.eval_on_selector_all("#labels div.target", "items => items.map(d => d.textContent)")
        assert sorted(labels) == sorted(TARGETS)

        shown = view.screenshot(tmp_path / "targets_on.png")
        view.page.uncheck("#show-targets")
        view.frames()
        hidden = view.screenshot(tmp_path / "targets_off.png")
        assert changed_fraction(shown, hidden) > 0.001
        assert view.errors == []


def test_offline_html_file_works_from_file_url(browser, site_for, xbot_folder, tmp_path):
    out = tmp_path / "xbot.html"
    assert main(["view", str(xbot_folder / "Xbot_wave.glb"), "--html", str(out)]) == 0
    requests: list[str] = []

    def record(request):
        requests.append(request.url)

    browser.on("request", record)
    try:
        with ViewerPage(browser, out.as_uri()) as view:
            assert view.clip_list() == ["wave"]
            state = view.state()
            assert state["mode"] == "mesh" and state["audio"]["src"] and len(state["targets"]) == 2
            view.show_time(0.2)
            first = view.screenshot(tmp_path / "offline_0.2.png")
            view.show_time(1.0)
            second = view.screenshot(tmp_path / "offline_1.0.png")
            assert changed_fraction(first, second) > 0.002
            assert view.errors == []
    finally:
        browser.remove_listener("request", record)
    assert requests and all(u.startswith(("file:", "blob:", "data:")) for u in requests), requests


def test_folder_lists_every_glb(browser, site_for, xbot_folder):
    with viewing(browser, site_for(xbot_folder)) as view:
        names = view.page.eval_on_selector_all("#files li", "items => items.map(li => li.textContent)")
        assert names == ["RobotExpressive", "Xbot_wave"]
        assert view.clip_list() == glb_animation_names(xbot_folder / "RobotExpressive.glb")
        view.page.click("#files li:nth-child(2)")
        view.page.wait_for_function("window.infuseViewer.state().entry === 1")
        view.frames()
        assert view.clip_list() == ["wave"]
        assert view.state()["audio"]["src"]
        assert view.errors == []


def test_bvh_shows_bones(browser, site_for, tmp_path):
    bvh = corpus_file(BVH)
    skeleton = infuse.load(bvh).skeleton
    with viewing(browser, site_for(bvh)) as view:
        state = view.state()
        assert state["mode"] == "skeleton" and state["clips"] == [bvh.stem]
        # every link is drawn but those that stretch (the root left at the origin), plus the end sites
        assert skeleton.num_joints - 3 <= state["bones"] <= skeleton.num_joints - 1 + len(skeleton.end_site_parents)
        view.show_time(0.2)
        first = view.screenshot(tmp_path / "bvh_0.2.png")
        view.show_time(0.9)
        second = view.screenshot(tmp_path / "bvh_0.9.png")
        assert changed_fraction(first, second) > 0.002

        # the bones are drawn: the middle of every bone on screen is lighter than the background
        joints = {j["name"]: j for j in view.page.evaluate("window.infuseViewer.jointsOnScreen()")}
        mids = np.array([[(j["x"] + joints[j["parent"]]["x"]) / 2, (j["y"] + joints[j["parent"]]["y"]) / 2]
                         for j in joints.values() if j["parent"] in joints])
        assert len(mids) >= 15
        luminance = second.astype(float).mean(axis=-1)
        background = np.median(luminance[:40, -40:])  # top right corner: sky
        lit = [luminance[int(y) - 1:int(y) + 2, int(x) - 1:int(x) + 2].max() > background + 60 for x, y in mids]
        assert np.mean(lit) > 0.9
        assert view.errors == []


def test_screenshot_command(tmp_path):
    # a process of its own: Playwright's sync API runs one browser session per thread, and this
    # module's browser is open
    from PIL import Image

    robot = str(corpus_file(ROBOT))
    out = tmp_path / "robot.png"
    run = subprocess.run([str(INFUSE), "view", robot, "--screenshot", str(out), "--clip", "Wave", "--time", "0.9",
                          "--size", "640x400"], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    pixels = np.asarray(Image.open(out).convert("RGB"))
    assert pixels.shape == (400, 640, 3)
    # the robot is there: many pixels of its yellow body
    r, g, b = (pixels[..., k].astype(int) for k in range(3))
    assert np.mean((r > 150) & (g > 90) & (b < 90) & (r > b + 80)) > 0.01
    run = subprocess.run([str(INFUSE), "view", robot, "--screenshot", str(tmp_path / "x.png"), "--clip", "Moonwalk"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 2 and "no clip named 'Moonwalk'" in run.stderr
    assert not (tmp_path / "x.png").exists()
