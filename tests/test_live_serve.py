"""``infuse serve`` driven over a real WebSocket with real BML (speech, gaze at a moving target, nod, walk,
reach, an interruption): feedback arrives in order, and the pose stream's frames are those of the same
scene realized offline from the same blocks at the times the server started them, stood on the ground
by the feet at rest (soles included)."""
from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np

from infuse.kinematics import forward_kinematics
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file

from live_support import BML_NS, SBM_NS, Recorder, scene_file, serving

SPEECH = f'''<bml xmlns="{BML_NS}" id="talk">
  <speech id="s1"><text>Hello Bob, it is <sync id="m"/>nice to see you here again today.</text></speech>
  <head id="h1" lexeme="NOD" start="s1:m"/>
</bml>'''
REACH = f'<bml xmlns="{BML_NS}" xmlns:sbm="{SBM_NS}" id="grab"><sbm:reach id="r1" target="cup" sbm:action="touch"/></bml>'
GAZE = f'<bml xmlns="{BML_NS}" id="look"><gazeShift id="g1" target="ball" influence="HEAD"/></bml>'
CUT = f'''<bml xmlns="{BML_NS}" id="cut" composition="REPLACE">
  <speech id="s2"><text>Oh wait.</text></speech>
</bml>'''


def _progress_in_order(feedback: list[dict], block: str) -> None:
    """A block's feedback: its prediction first, then progress by time, its start first and its end last."""
    events = [m for m in feedback if (m.get("block") or m.get("id", "").split(":")[0]) == block]
    kinds = [m["kind"] for m in events]
    assert kinds[0] == "blockPrediction", kinds
    progress = [m for m in events if m["kind"] in ("blockProgress", "syncPointProgress")]
    assert progress[0]["kind"] == "blockProgress" and progress[0]["sync"] == "start", progress[:2]
    assert progress[-1]["kind"] == "blockProgress" and progress[-1]["sync"] == "end", progress[-2:]
    times = [m["global_time"] for m in progress]
    assert times == sorted(times), times


def test_serve_streams_the_offline_scene_and_feedback_in_order(tmp_path):
    scene_path = scene_file(tmp_path)
    applied = []  # what the server started, in order: (kind, arguments, scene time)
    with serving(scene_path) as (process, port, _):
        client = Recorder(port)
        hello = client.wait_for(lambda m: m["type"] == "hello")
        assert set(hello["characters"]) == {"bob", "ann"}
        assert client.request({"type": "subscribe", "frames": True})["frames"] is True
        packed = Recorder(port)  # the same stream as binary messages
        assert packed.request({"type": "subscribe", "frames": True, "format": "binary"})["format"] == "binary"

        def target(position):
            reply = client.request({"type": "target", "name": "ball", "position": position})
            assert reply["type"] == "accepted", reply
            applied.append(("target", position, reply["time"]))

        def bml(character, text):
            reply = client.request({"type": "bml", "character": character, "bml": text})
            assert reply["type"] == "accepted", reply
            applied.append(("bml", (character, text), reply["time"]))
            return reply

        def call(method, character, **args):
            reply = client.request({"type": "call", "method": method, "character": character, "args": args})
            assert reply["type"] == "accepted", reply
            applied.append(("call", (method, character, args), reply["time"]))
            return reply

        target([0.6, 1.5, 1.0])
        bml("bob", GAZE)
        time.sleep(0.3)
        target([-0.4, 1.3, 0.6])  # the gaze follows the moved target
        bml("ann", SPEECH)
        call("walk_to", "bob", target=[0.0, 0.6])
        bml("ann", REACH)
        time.sleep(0.8)
        target([0.2, 1.7, 0.4])
        cut = bml("ann", CUT)  # interrupts the speech and the reach
        client.wait_for(lambda m: m.get("kind") == "blockProgress" and m["block"] == "cut" and m["sync"] == "end", 20)
        time.sleep(0.3)
        status = client.request({"type": "status", "blocks": True})
        client.close()
        packed.close()

    both = sorted(set(client.frames) & set(packed.frames))
    assert len(both) > 50
    for f in both:
        for name in ("bob", "ann"):
            for key in ("rotations", "root", "morphs"):
                assert np.allclose(packed.frames[f]["characters"][name][key], client.frames[f]["characters"][name][key],
                                   atol=2e-6 if key != "morphs" else 1e-4)
    feedback = [m for m in client.messages if m["type"] == "feedback"]
    for block in ("look", "talk", "grab", "cut"):
        assert any(m.get("block") == block for m in feedback), block
    for block in ("talk", "grab", "cut"):
        _progress_in_order(feedback, block)
    # the interrupted speech ends where the cut starts, and its audio is told to stop there
    talk_end = next(m for m in feedback if m["kind"] == "blockProgress" and m["block"] == "talk" and m["sync"] == "end")
    assert abs(talk_end["global_time"] - cut["time"]) < 1e-9
    audio = [m for m in client.messages if m["type"] == "audio"]
    assert any(m["block"] == "talk" and "wav" in m for m in audio)
    assert any(m["block"] == "talk" and m.get("stop") == cut["time"] for m in audio)
    assert status["shown"] > 100, status

    # The same scene offline: the same commands at the same times, in the same order, evaluated in the same
    # blocks (other blocks give them to rounding), in a fresh process as the server is
    # (espeak-ng's timings can differ by milliseconds between syntheses in one process).
    assert status["blocks"][0][0] == 0  # every block so far
    offline = _offline(tmp_path, scene_path, applied, status["blocks"])
    spec = read_scene_file(scene_path)
    rigs = build_scene(spec, quiet=True).runtime
    compared = 0
    for name in ("bob", "ann"):
        rig = rigs.rig(name)
        rotations, roots, morphs = (offline[f"{name}_{k}"] for k in ("rotations", "roots", "morphs"))
        frames = sorted(f for f in client.frames if f < len(rotations))
        live_rot = np.array([client.frames[f]["characters"][name]["rotations"] for f in frames]).reshape(len(frames), -1, 4)
        live_root = np.array([client.frames[f]["characters"][name]["root"] for f in frames])
        _, live_pos = forward_kinematics(rig.skeleton, live_rot, live_root)
        _, offline_pos = forward_kinematics(rig.skeleton, rotations[frames], roots[frames])
        error = np.abs(live_pos - offline_pos).max(axis=(1, 2))
        assert error.max() < 1e-4, (name, error.max(), [frames[i] for i in np.nonzero(error > 1e-4)[0][:10]], applied)
        live_morphs = np.array([client.frames[f]["characters"][name]["morphs"] for f in frames])
        if live_morphs.size:
            assert np.abs(live_morphs - morphs[frames]).max() < 1e-3
        compared += len(frames)
    assert compared > 100
    # the walk moved Bob, the speech moved Ann's mouth: the comparison is over a moving scene
    bob_root = np.array([client.frames[f]["characters"]["bob"]["root"] for f in sorted(client.frames)])
    assert np.ptp(bob_root[:, [0, 2]], axis=0).max() > 0.3


OFFLINE = """
import json, sys
import numpy as np
from infuse.grounding import foot_height, grounded
from infuse.live import MovableTarget
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file

job = json.load(sys.stdin)
scene = build_scene(read_scene_file(job["scene"]), quiet=True)
ball = MovableTarget((0.0, 0.0, 0.0))
todo = list(job["applied"])
for first, count in job["blocks"]:
    assert scene.runtime.frame == first
    while todo and round(todo[0][2] * scene.fps) == first:  # what the server applied before this block
        kind, what, at = todo.pop(0)
        if kind == "target":
            if "ball" not in scene.targets:
                scene.add_target("ball", ball)
            ball.point = np.asarray(what, dtype=float)
        elif kind == "bml":
            scene.bml(what[0], what[1])
        else:
            method, character, args = what
            getattr(scene, method)(character, **args)
    scene.step(count)
assert not todo
out = {}
for name in scene.characters:
    rig = scene.runtime.rig(name)  # stood on the ground by its feet at rest, soles included
    motion = grounded(scene.motion(name), foot_height(rig.character.asset, rig.mapping))
    out[f"{name}_rotations"], out[f"{name}_roots"] = motion.local_rotations, motion.root_translations
    out[f"{name}_morphs"] = scene.runtime.morph_weights(name)
np.savez(job["out"], **out)
"""


def _offline(folder, scene_path, applied, blocks) -> dict:
    """The scene realized offline, in a fresh process, from the commands the server applied, each before the
    block it applied before, in the server's blocks; a moved target stands at each position from its move."""
    out = folder / "offline.npz"
    job = {"scene": str(scene_path), "applied": applied, "blocks": blocks, "out": str(out)}
    subprocess.run([sys.executable, "-c", OFFLINE], input=json.dumps(job), text=True, check=True, timeout=300)
    return dict(np.load(out))
