"""A live scene of a rig whose feet hang from the root (RobotExpressive): its frames carry the joint
translations that put the feet on the shins' ends, and the pose rebuilt from the stream (the frames
themselves, their JSON and binary messages, the VMC bones, the live page) puts the feet where the
offline scene does; an ordinary rig's frames carry none and keep their bytes."""
from __future__ import annotations

import json
import struct
import time

import numpy as np
from pythonosc.osc_bundle import OscBundle

from infuse.kinematics import forward_kinematics
from infuse.live import CharacterFrame, LiveFrame, LiveScene
from infuse.scene import Scene
from infuse_live.frames import binary_frame, frame_text
from infuse_live.vmc import VmcSender

from corpus_data import corpus_file
from live_support import BML_NS, Recorder, decode_binary_frame, serving
from test_live_vmc import rebuild
from viewer_support import chromium_context

FPS = 60
ROBOT = "adibkn1-robot/RobotExpressive.glb"


def _walking() -> Scene:
    scene = Scene(fps=FPS, quiet=True)
    scene.add_character(corpus_file(ROBOT), "robot", packs=["locomotion-female"])
    scene.walk_to("robot", (0.0, 2.0))
    return scene


def _feet(rig, rotations: np.ndarray, root: np.ndarray, translations: np.ndarray | None) -> np.ndarray:
    """World positions (F, 2, 3) of the carried feet for poses (F, J, 4), roots (F, 3), translations (F, J, 3)."""
    _, positions = forward_kinematics(rig.skeleton, rotations, root, translations)
    return positions[:, rig.carried_limbs[:, 2]]


def _messages(bundle: OscBundle):
    for content in bundle:
        yield from _messages(content) if isinstance(content, OscBundle) else [content]


def test_a_carried_feet_rig_walks_live_as_it_walks_offline():
    live = LiveScene(_walking())
    shown: dict[int, LiveFrame] = {}
    live.on_frame(lambda frame: shown.setdefault(frame.index, frame))
    with live:
        while max(shown, default=0) < 2 * FPS:
            time.sleep(0.05)
    blocks = list(live.stats.blocks)
    assert blocks[0][0] == 0 and all(a + n == b for (a, n), (b, _) in zip(blocks, blocks[1:]))
    rig = live.scene.runtime.rig("robot")
    assert len(rig.carried_limbs) == 2
    # the offline scene realized from the same block, evaluated in the same blocks
    offline = _walking()
    for _, count in blocks:
        offline.step(count)
    motion = offline.runtime.motion("robot")
    indices = np.array(sorted(i for i in shown if i < motion.num_frames))
    assert len(indices) > FPS
    expected = _feet(rig, motion.local_rotations[indices], motion.root_translations[indices],
                     motion.joint_translations[indices])
    frames = [shown[i].characters["robot"] for i in indices]
    rotations = np.array([c.rotations for c in frames])
    roots = np.array([c.root for c in frames])
    translations = np.array([c.translations for c in frames])
    assert translations.shape == (len(indices), rig.skeleton.num_joints, 3)
    # live frames stand on the ground: the same pose, lowered by one height for the whole walk
    lowered = motion.root_translations[indices] - roots
    assert np.abs(lowered[:, [0, 2]]).max() < 1e-9 and np.ptp(lowered[:, 1]) < 1e-9
    expected[..., 1] -= lowered[0, 1]
    streamed = _feet(rig, rotations, roots, translations)
    assert np.abs(streamed - expected).max() < 1e-6
    assert np.ptp(expected[..., 2]) > 0.5  # the feet did walk
    # without the translations the feet would stay at rest beside the root
    assert np.linalg.norm(_feet(rig, rotations, roots, None) - expected, axis=-1).max() > 0.05
    # the wire: binary (float32) and JSON (rounded to 1e-6) frames, and the VMC bones
    sender = VmcSender(live, "robot", "127.0.0.1", 9)
    decoded_binary, decoded_json, vmc = [], [], []
    for i in indices:
        data = binary_frame(shown[i])
        (length,) = struct.unpack_from("<I", data, 0)
        assert json.loads(data[4:4 + length])["characters"][0][3] is True
        decoded_binary.append(decode_binary_frame(data)["characters"]["robot"])
        decoded_json.append(json.loads(frame_text(shown[i]))["characters"]["robot"])
        bones = {m.params[0]: np.array(m.params[1:], dtype=np.float64)
                 for packet in sender.packets(shown[i]) for m in _messages(OscBundle(packet))
                 if m.address == "/VMC/Ext/Bone/Pos"}
        world = rebuild(bones)
        vmc.append([world[name][1] for name in ("LeftFoot", "RightFoot")])
    for decoded, tolerance in ((decoded_binary, 2e-6), (decoded_json, 5e-6)):
        rebuilt = _feet(rig, np.array([d["rotations"] for d in decoded]).reshape(len(indices), -1, 4),
                        np.array([d["root"] for d in decoded]),
                        np.array([d["translations"] for d in decoded]).reshape(len(indices), -1, 3))
        assert np.abs(rebuilt - expected).max() < tolerance
    order = [list(rig.carried_limbs[:, 2]).index(rig.joint(f"{s}_ankle")) for s in "lr"]  # VMC: left, right
    assert np.abs(np.array(vmc) - expected[:, order]).max() < 1e-6


def test_an_ordinary_rigs_frames_carry_no_translations():
    scene = Scene(fps=FPS, quiet=True)
    scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bot")
    scene.walk_to("bot", (0.0, 1.0))
    scene.run(1.0)
    assert scene.runtime.last_translations("bot", 30) is None
    rotations, root, morphs = scene.runtime.last_poses("bot", 1)
    frame = LiveFrame(60, 1.0, 0.0, {"bot": CharacterFrame(rotations[0], root[0], morphs[0])})
    # the layout of frames without translations, byte for byte
    header = json.dumps({"frame": 60, "time": 1.0, "characters": [["bot", len(rotations[0]), len(morphs[0])]]},
                        separators=(",", ":")).encode()
    body = np.concatenate([rotations[0].ravel(), root[0], morphs[0]]).astype("<f4").tobytes()
    assert binary_frame(frame) == struct.pack("<I", len(header)) + header + body
    assert "translations" not in json.loads(frame_text(frame))["characters"]["bot"]


def test_the_live_page_puts_carried_feet_where_the_stream_does(tmp_path):
    """``infuse serve`` of the robot walking, in headless Chromium: the page's foot is where FK on the
    streamed frame puts it, not at rest beside the root."""
    path = tmp_path / "robot.toml"
    path.write_text(f'fps = {FPS}\n[[character]]\nname = "robot"\nfile = "{corpus_file(ROBOT)}"\n'
                    'packs = ["locomotion-female"]\n')
    walk = f'<bml xmlns="{BML_NS}" id="walk"><locomotion id="l1" target="0.0 2.0"/></bml>'
    rig = _walking().runtime.rig("robot")
    foot = int(rig.joint("l_ankle"))
    with serving(path) as (process, port, http_port), chromium_context() as browser:
        page = browser.new_page()
        problems = []
        page.on("pageerror", lambda error: problems.append(str(error)))
        page.goto(f"http://127.0.0.1:{http_port}/")
        page.wait_for_function("window.infuseLive.ready && window.infuseLive.frames > 10", timeout=60_000)
        client = Recorder(port)
        client.wait_for(lambda m: m["type"] == "hello")
        client.request({"type": "subscribe", "frames": True})
        assert client.request({"type": "bml", "character": "robot", "bml": walk})["type"] == "accepted"
        time.sleep(1.5)
        shown, shown_foot = page.evaluate("([c, j]) => [window.infuseLive.frame, window.infuseLive.jointPosition(c, j)]",
                                          ["robot", rig.skeleton.names[foot]])
        client.close()
    assert not problems, problems
    pose = client.frames[shown]["characters"]["robot"]
    rotations, root = np.array(pose["rotations"]).reshape(1, -1, 4), np.array(pose["root"])[None]
    _, positions = forward_kinematics(rig.skeleton, rotations, root, np.array(pose["translations"]).reshape(1, -1, 3))
    _, at_rest = forward_kinematics(rig.skeleton, rotations, root)
    assert np.linalg.norm(positions[0, foot] - root[0]) > 0.1
    assert np.linalg.norm(positions[0, foot] - shown_foot) < 0.01
    assert np.linalg.norm(at_rest[0, foot] - shown_foot) > 0.05
