"""The live viewer page of ``infuse serve`` in headless Chromium: it loads the characters, connects over
WebSocket and plays the pose stream; the figure moves as BML arrives, where the stream says it is."""
from __future__ import annotations

import time

import numpy as np

from infuse.kinematics import forward_kinematics
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file

from corpus_data import corpus_file
from live_support import BML_NS, Recorder, scene_file, serving
from viewer_support import chromium_context

WALK = f'<bml xmlns="{BML_NS}" id="walk"><locomotion id="l1" target="0.0 0.6"/></bml>'


def _hand(page, character: str, joint: str) -> np.ndarray:
    return np.array(page.evaluate("([c, j]) => window.infuseLive.jointPosition(c, j)", [character, joint]))


def test_live_page_moves_as_bml_arrives(tmp_path):
    path = scene_file(tmp_path)
    scene = build_scene(read_scene_file(path), quiet=True)
    rig = scene.runtime.rig("bob")
    wrist = rig.joint("r_wrist")
    name = rig.skeleton.names[wrist]
    with serving(path, "--allow-add") as (process, port, http_port), chromium_context() as browser:
        page = browser.new_page()
        problems = []
        page.on("pageerror", lambda error: problems.append(str(error)))
        page.goto(f"http://127.0.0.1:{http_port}/")
        page.wait_for_function("window.infuseLive.ready && window.infuseLive.frames > 10", timeout=60_000)
        assert page.evaluate("window.infuseLive.error") is None
        before = _hand(page, "bob", name)
        time.sleep(0.3)
        assert np.linalg.norm(_hand(page, "bob", name) - before) < 0.15  # idling: the hand sways, no more
        client = Recorder(port)
        client.wait_for(lambda m: m["type"] == "hello")
        client.request({"type": "subscribe", "frames": True})
        assert client.request({"type": "bml", "character": "bob", "bml": WALK})["type"] == "accepted"
        time.sleep(2.0)
        shown, after = page.evaluate("([c, j]) => [window.infuseLive.frame, window.infuseLive.jointPosition(c, j)]",
                                     ["bob", name])
        after = np.array(after)
        # a character joins: the page loads it and shows it where the stream puts it
        added = client.request({"type": "add", "name": "carl", "file": str(corpus_file("runxaway-models/Xbot.glb")),
                                "position": [1.5, 0.0, 1.0], "facing": "ann"}, timeout_s=120)
        assert added["type"] == "accepted" and added["character"] == "carl", added
        page.wait_for_function("window.infuseLive.jointPosition('carl', 'mixamorig:Hips') !== null", timeout=60_000)
        time.sleep(0.5)
        carl = np.array(page.evaluate("window.infuseLive.jointPosition('carl', 'mixamorig:Hips')"))
        page.screenshot(path=str(tmp_path / "live.png"))
        client.close()
    assert not problems, problems
    assert np.linalg.norm(after - before) > 0.6  # Bob walked: his hand went with him
    # the page shows the streamed pose: its wrist where FK on the stream's frame puts it
    frame = client.frames.get(shown)
    assert frame is not None
    pose = frame["characters"]["bob"]
    _, positions = forward_kinematics(rig.skeleton, np.array(pose["rotations"]).reshape(1, -1, 4), np.array(pose["root"])[None])
    assert np.linalg.norm(positions[0, wrist] - after) < 0.01
    assert np.linalg.norm(carl[[0, 2]] - [1.5, 1.0]) < 0.2  # Carl stands where he was put
