"""The VMC stream of ``infuse serve --vmc``, received by a real python-osc server: the character's pose
rebuilt from ``/VMC/Ext/Root/Pos`` and ``/VMC/Ext/Bone/Pos`` alone (the humanoid hierarchy a receiver
knows, Unity coordinates) puts every bone within 1 mm of the runtime's forward kinematics, and
``/VMC/Ext/Blend/Val`` carries the morph weights of the same frame."""
from __future__ import annotations

import threading
import time
from dataclasses import replace

import numpy as np
from pythonosc.dispatcher import Dispatcher
from pythonosc.osc_server import BlockingOSCUDPServer

import infuse
from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.mapping import map_skeleton
from infuse.runtime.rig import Rig
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file
from infuse.canonical import canonical_joint
from infuse_live.vmc import TPOSE_CHILD, VRM_BONES, VmcBones, to_unity

from corpus_data import corpus_file
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


def rebuild(bones: dict[str, np.ndarray]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World rotations and positions (core frame, metres) of the received bones, from their local Unity
    transforms."""
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
    return world


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
    matched, errors, moving, directions = 0, [], [], []
    for t, vmc in receiver.frames.items():
        frame = client.frames.get(int(round(t * fps)))
        if frame is None or not vmc["applied"]:
            continue
        assert set(vmc["bones"]) == set(joints)
        pose = frame["characters"]["ann"]
        rotations = np.array(pose["rotations"]).reshape(-1, 4)
        _, positions = forward_kinematics(rig.skeleton, rotations[None], np.array(pose["root"])[None])
        rebuilt = rebuild(vmc["bones"])
        errors.append(max(np.linalg.norm(rebuilt[name][1] - positions[0, j]) for name, j in joints.items()))
        # a receiver's T-pose bone, turned by the received rotation, points along the character's bone
        for name, j in joints.items():
            child = rig.joint(TPOSE_CHILD.get(VRM_BONES[name], ""))
            if child is not None and rig.skeleton.parents[child] == j:
                tpose = np.subtract(canonical_joint(TPOSE_CHILD[VRM_BONES[name]]).position, canonical_joint(VRM_BONES[name]).position)
                pointed = quat.rotate(rebuilt[name][0], tpose)
                bone = positions[0, child] - positions[0, j]
                cosine = pointed @ bone / np.linalg.norm(pointed) / np.linalg.norm(bone)
                directions.append(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
        morphs = dict(zip(rig.morph_targets, pose["morphs"]))
        assert set(vmc["blend"]) == set(rig.morph_targets)
        assert max(abs(vmc["blend"][k] - morphs[k]) for k in morphs) < 1e-3
        moving.append(positions[0, joints["RightHand"]])
        matched += 1
    assert matched > 60, matched
    assert max(errors) < 1e-3, max(errors)
    assert max(directions) < 1.0, max(directions)
    # the frames compared show a moving character (the reach moves the right hand)
    assert np.ptp(np.array(moving), axis=0).max() > 0.05


def test_an_a_pose_rest_is_sent_as_a_turn_from_the_receivers_t_pose():
    """Xbot with its arms lowered 40 degrees at rest: standing at rest, a receiver's T-pose arm turned by
    the sent rotations points down along the character's arm, not straight out."""
    asset = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    mapping = map_skeleton(asset)
    sk = asset.skeleton
    rest_global = sk.rest_global_rotations
    rotations = np.array(sk.rest_rotations)
    for side, sign in (("l", -1.0), ("r", 1.0)):  # +X is the left: the left arm turns down about +Z by -40 degrees
        j = mapping.indices(sk)[f"{side}_shoulder"]
        down = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(sign * 40.0))
        rotations[j] = quat.multiply(rotations[j], quat.multiply(quat.conjugate(rest_global[j]), quat.multiply(down, rest_global[j])))
    a_pose = replace(asset, skeleton=replace(sk, rest_rotations=rotations), motions={})
    rig = Rig("a", infuse.Character("a", a_pose, mapping), mapping)
    bones = VmcBones(rig)
    positions, local = to_unity(*bones.local(rig.skeleton.rest_rotations, rig.skeleton.rest_translations[0]))
    world = rebuild({name: np.concatenate([p, q]) for name, p, q in zip(bones.names, positions, local)})
    _, global_positions = forward_kinematics(rig.skeleton, rig.skeleton.rest_rotations[None], rig.skeleton.rest_translations[:1])
    for side, name in (("l", "LeftUpperArm"), ("r", "RightUpperArm")):
        arm = global_positions[0, rig.joint(f"{side}_elbow")] - global_positions[0, rig.joint(f"{side}_shoulder")]
        tpose = np.subtract(canonical_joint(f"{side}_elbow").position, canonical_joint(f"{side}_shoulder").position)
        pointed = quat.rotate(world[name][0], tpose)
        angle = np.degrees(np.arccos(pointed @ arm / np.linalg.norm(pointed) / np.linalg.norm(arm)))
        assert angle < 0.5, (name, angle)
        assert arm[1] < -0.5 * np.linalg.norm(arm)  # the arm does point down at rest


def test_packets_are_the_osc_bundles_of_each_message_built_in_full():
    """A frame's bundles, written from messages whose fixed parts are kept (names, addresses, type tags)
    and whose numbers are converted at once, are byte for byte the bundles python-osc builds message by
    message from the same values; a frame of more than a datagram is split where python-osc's would be."""
    from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
    from pythonosc.osc_message_builder import OscMessageBuilder

    import infuse_live.vmc as vmc
    from infuse.live import LiveFrame, LiveScene
    from infuse.scene import Scene

    def message(address, *values):
        built = OscMessageBuilder(address)
        for value in values:
            built.add_arg(value, "s" if isinstance(value, str) else "i" if isinstance(value, int) else "f")
        return built.build()

    scene = Scene(fps=60, quiet=True)
    scene.add_character(corpus_file("talkinghead/avatars/brunette-t.glb"), "ann")
    live = LiveScene(scene)
    scene.bml("ann", f'<bml xmlns="{BML_NS}" id="s"><faceLexeme id="f" lexeme="smile" amount="0.8"/></bml>')
    index, characters = live._evaluate(30)[-1]
    frame = LiveFrame(index, index / 60, 0.0, characters)
    sender = vmc.VmcSender(live, "ann", "127.0.0.1", 9)
    pose = frame.characters["ann"]
    assert pose.morphs.any()
    positions, rotations = to_unity(*sender.bones.local(pose.rotations, pose.root, pose.translations))
    messages = [message("/VMC/Ext/OK", 1), message("/VMC/Ext/T", float(frame.time_s)),
                message("/VMC/Ext/Root/Pos", "root", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)]
    messages += [message("/VMC/Ext/Bone/Pos", name, *p, *q)
                 for name, p, q in zip(sender.bones.names, positions.tolist(), rotations.tolist())]
    messages += [message("/VMC/Ext/Blend/Val", name, float(v)) for name, v in zip(sender.morphs, pose.morphs.tolist())]
    messages.append(message("/VMC/Ext/Blend/Apply"))

    def bundles(most):
        out, built, size = [], OscBundleBuilder(IMMEDIATELY), 16
        for m in messages:
            if size + 4 + m.size > most:
                out.append(built.build().dgram)
                built, size = OscBundleBuilder(IMMEDIATELY), 16
            built.add_content(m)
            size += 4 + m.size
        return out + [built.build().dgram]
    assert sender.packets(frame) == bundles(vmc.MAX_PACKET_BYTES)
    values = np.concatenate(([frame.time_s], np.concatenate((positions, rotations), axis=1).ravel(), pose.morphs))
    split = bundles(1500)
    assert len(split) > 1 and sender.messages.bundles(values, 1500) == split
    sender.close()
