"""The VMC stream of ``infuse serve --vmc``, received by a real python-osc server: the character's pose
rebuilt from ``/VMC/Ext/Root/Pos`` and ``/VMC/Ext/Bone/Pos`` alone (the humanoid hierarchy a receiver
knows, Unity coordinates) puts every bone within 1 mm of the runtime's forward kinematics, and
``/VMC/Ext/Blend/Val`` carries the morph weights of the same frame."""
from __future__ import annotations

import threading
import time

import numpy as np
from pythonosc.dispatcher import Dispatcher
from pythonosc.osc_server import BlockingOSCUDPServer

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file
from infuse_live.vmc import VRM_BONES

from live_support import BML_NS, SBM_NS, Recorder, scene_file, serving

# Unity's humanoid hierarchy, as a receiver knows it: each bone's parent, nearest first when one is missing.
PARENTS = {"Spine": ["Hips"], "Chest": ["Spine"], "UpperChest": ["Chest", "Spine"], "Neck": ["UpperChest", "Chest", "Spine"],
           "Head": ["Neck", "UpperChest", "Chest"], "LeftEye": ["Head"], "RightEye": ["Head"],
           **{f"{s}Shoulder": ["UpperChest", "Chest", "Spine"] for s in ("Left", "Right")},
           **{f"{s}UpperArm": [f"{s}Shoulder", "UpperChest", "Chest"] for s in ("Left", "Right")},
           **{f"{s}LowerArm": [f"{s}UpperArm"] for s in ("Left", "Right")},
           **{f"{s}Hand": [f"{s}LowerArm"] for s in ("Left", "Right")},
           **{f"{s}UpperLeg": ["Hips"] for s in ("Left", "Right")},
           **{f"{s}LowerLeg": [f"{s}UpperLeg"] for s in ("Left", "Right")},
           **{f"{s}Foot": [f"{s}LowerLeg"] for s in ("Left", "Right")},
           **{f"{s}Toes": [f"{s}Foot"] for s in ("Left", "Right")},
           **{f"{s}{f}{seg}": [f"{s}{f}{prev}"] if prev else [f"{s}Hand"]
              for s in ("Left", "Right") for f in ("Thumb", "Index", "Middle", "Ring", "Little")
              for seg, prev in (("Proximal", None), ("Intermediate", "Proximal"), ("Distal", "Intermediate"))}}
TALK = f'''<bml xmlns="{BML_NS}" xmlns:sbm="{SBM_NS}" id="talk">
  <speech id="s1"><text>Let me show you the cup over there.</text></speech>
  <sbm:reach id="r1" target="cup" sbm:action="touch"/>
  <head id="h1" lexeme="NOD" repetition="2"/>
</bml>'''


class Receiver:
    """A python-osc UDP server keeping each frame's VMC messages (frames told apart by /VMC/Ext/T)."""

    def __init__(self):
        self.frames: dict[float, dict] = {}
        self._current: dict | None = None
        self._lock = threading.Lock()
        dispatcher = Dispatcher()
        dispatcher.map("/VMC/Ext/*", self._message)
        self.server = BlockingOSCUDPServer(("127.0.0.1", 0), dispatcher)
        self.port = self.server.server_address[1]
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def _message(self, address, *args):
        with self._lock:
            if address == "/VMC/Ext/T":
                self._current = self.frames.setdefault(float(args[0]), {"bones": {}, "blend": {}, "applied": False})
            elif self._current is None:
                return
            elif address == "/VMC/Ext/Root/Pos":
                self._current["root"] = args
            elif address == "/VMC/Ext/Bone/Pos":
                self._current["bones"][args[0]] = np.array(args[1:], dtype=np.float64)
            elif address == "/VMC/Ext/Blend/Val":
                self._current["blend"][args[0]] = float(args[1])
            elif address == "/VMC/Ext/Blend/Apply":
                self._current["applied"] = True

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def rebuild(bones: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """World positions (core frame, metres) of the received bones, from their local Unity transforms."""
    world = {}
    for name in ["Hips"] + [n for n in VRM_BONES if n != "Hips"]:
        if name not in bones:
            continue
        value = bones[name]
        position = value[:3] * np.array([-1.0, 1.0, 1.0])
        rotation = value[3:] * np.array([1.0, -1.0, -1.0, 1.0])
        parent = next((p for p in PARENTS.get(name, []) if p in world), None)
        if parent is None:
            world[name] = (rotation, position)
            continue
        parent_rotation, parent_position = world[parent]
        world[name] = (quat.multiply(parent_rotation, rotation), parent_position + quat.rotate(parent_rotation, position))
    return {name: p for name, (_, p) in world.items()}


def test_vmc_stream_rebuilds_the_pose_within_a_millimetre(tmp_path):
    path = scene_file(tmp_path)
    receiver = Receiver()
    try:
        with serving(path, "--vmc", f"127.0.0.1:{receiver.port}", "--vmc-character", "ann") as (process, port, _):
            client = Recorder(port)
            client.wait_for(lambda m: m["type"] == "hello")
            client.request({"type": "subscribe", "frames": True})
            assert client.request({"type": "bml", "character": "ann", "bml": TALK})["type"] == "accepted"
            time.sleep(2.5)
            client.close()
    finally:
        receiver.close()
    scene = build_scene(read_scene_file(path), quiet=True)
    rig = scene.runtime.rig("ann")
    fps = scene.fps
    joints = {name: rig.joint(canonical) for name, canonical in VRM_BONES.items() if rig.joint(canonical) is not None}
    assert {"Hips", "Spine", "Head", "LeftUpperArm", "RightHand", "LeftFoot", "RightIndexProximal"} <= set(joints)
    matched, errors, moving = 0, [], []
    for t, vmc in receiver.frames.items():
        frame = client.frames.get(int(round(t * fps)))
        if frame is None or not vmc["applied"]:
            continue
        assert set(vmc["bones"]) == set(joints)
        pose = frame["characters"]["ann"]
        rotations = np.array(pose["rotations"]).reshape(-1, 4)
        _, positions = forward_kinematics(rig.skeleton, rotations[None], np.array(pose["root"])[None])
        rebuilt = rebuild(vmc["bones"])
        errors.append(max(np.linalg.norm(rebuilt[name] - positions[0, j]) for name, j in joints.items()))
        morphs = dict(zip(rig.morph_targets, pose["morphs"]))
        assert set(vmc["blend"]) == set(rig.morph_targets)
        assert max(abs(vmc["blend"][k] - morphs[k]) for k in morphs) < 1e-3
        moving.append(positions[0, joints["RightHand"]])
        matched += 1
    assert matched > 60, matched
    assert max(errors) < 1e-3, max(errors)
    # the frames compared show a moving character (the reach moves the right hand)
    assert np.ptp(np.array(moving), axis=0).max() > 0.05
