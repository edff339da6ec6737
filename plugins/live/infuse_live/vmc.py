"""The VMC protocol out: one character's pose and expressions as OSC over UDP, every frame.

What VMC receivers (VSeeFace, VMagicMirror, EVMC4U in Unity, VMC4B in Blender, three-vrm apps) read,
every frame:

- ``/VMC/Ext/OK 1``; ``/VMC/Ext/T time``: the sender is alive, its time in seconds;
- ``/VMC/Ext/Root/Pos "root" px py pz qx qy qz qw``: the avatar's origin (here the world origin);
- ``/VMC/Ext/Bone/Pos NAME px py pz qx qy qz qw`` per humanoid bone (Unity ``HumanBodyBones`` names:
  ``Hips``, ``Spine``, ``LeftUpperArm``...), local to the nearest sent ancestor, as VRM's normalized bones
  take it: rotations from a T-pose facing +Z whose bone frames are the world's (the receiver's avatar at
  rest), and the position of the bone's origin from its parent's. The character's own rest (an A-pose,
  say) is told apart from that T-pose bone by bone: each bone's T-pose direction (from the canonical
  skeleton) is swung onto the character's in its reference pose, so a receiver's arm points where the
  character's does;
- ``/VMC/Ext/Blend/Val NAME value`` for each morph target of the character (zeros included), then
  ``/VMC/Ext/Blend/Apply``.

A frame that does not fit in one datagram of :data:`MAX_PACKET_BYTES` goes as several bundles, in that order.

Coordinates are Unity's (left-handed, +Y up, the character facing +Z): x is negated, and a quaternion
(x, y, z, w) becomes (x, -y, -z, w). Positions are metres. Frames are sent from a thread of their own;
a receiver that is gone costs nothing but the UDP sends.
"""
from __future__ import annotations

import socket
import threading
import time

import numpy as np

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.canonical import canonical_joint
from infuse.live import LiveFrame, LiveScene
from infuse.runtime.rig import reference_pose

from .osc import FrameMessages

#: Unity HumanBodyBones name -> canonical joint, parents before children.
VRM_BONES = {
    "Hips": "base", "Spine": "spine1", "Chest": "spine2", "UpperChest": "spine3", "Neck": "spine4", "Head": "skullbase",
    "LeftEye": "eyeball_left", "RightEye": "eyeball_right",
    **{f"{Side}{bone}": f"{s}_{canonical}" for Side, s in (("Left", "l"), ("Right", "r"))
       for bone, canonical in (("Shoulder", "acromioclavicular"), ("UpperArm", "shoulder"), ("LowerArm", "elbow"),
                               ("Hand", "wrist"), ("UpperLeg", "hip"), ("LowerLeg", "knee"), ("Foot", "ankle"),
                               ("Toes", "forefoot"))},
    **{f"{Side}{finger}{segment}": f"{s}_{canonical}{k}" for Side, s in (("Left", "l"), ("Right", "r"))
       for finger, canonical in (("Thumb", "thumb"), ("Index", "index"), ("Middle", "middle"), ("Ring", "ring"),
                                 ("Little", "pinky"))
       for k, segment in ((1, "Proximal"), (2, "Intermediate"), (3, "Distal"))},
}
#: The canonical joint each bone points to in a T-pose (bones missing here keep the body's axes).
TPOSE_CHILD = {
    "spine1": "spine2", "spine2": "spine3", "spine3": "spine4", "spine4": "skullbase",
    **{f"{s}_{a}": f"{s}_{b}" for s in "lr" for a, b in (("acromioclavicular", "shoulder"), ("shoulder", "elbow"),
                                                          ("elbow", "wrist"), ("wrist", "middle1"), ("hip", "knee"),
                                                          ("knee", "ankle"), ("ankle", "forefoot"), ("forefoot", "toe"))},
    **{f"{s}_{f}{k}": f"{s}_{f}{k + 1}" for s in "lr" for f in ("thumb", "index", "middle", "ring", "pinky") for k in (1, 2, 3)},
}
#: core frame (right-handed, +X the character's left) -> Unity (left-handed, +X its right)
_FLIP_POSITION = np.array([-1.0, 1.0, 1.0])
_FLIP_ROTATION = np.array([1.0, -1.0, -1.0, 1.0])
#: Largest OSC bundle sent, bytes: what common receivers read in one datagram (python-osc reads 8 KB).
MAX_PACKET_BYTES = 8000


class VmcBones:
    """The humanoid bones of one character as VMC sends them: which joints (``names``, ``joints`` (B,)),
    their parents among the sent bones (``parents`` (B,), -1 for the hips) and the rotations (B, 4) taking
    each bone of a receiver's T-pose to the character's reference pose (``tpose``)."""

    def __init__(self, rig):
        self.skeleton = rig.skeleton
        found = [(name, rig.joint(canonical)) for name, canonical in VRM_BONES.items()]
        found = [(name, j) for name, j in found if j is not None]
        self.names = [name for name, _ in found]
        self.joints = np.array([j for _, j in found], dtype=np.int64)
        sent = {int(j): k for k, j in enumerate(self.joints)}
        # a foot hanging from the root (carried on its shin's end) is under its shin in a receiver's humanoid
        carriers = {int(c): int(b) for _, b, c in rig.carried_limbs}
        parents = []
        for j in self.joints:
            p = carriers.get(int(j), int(self.skeleton.parents[j]))
            while p >= 0 and p not in sent:
                p = int(self.skeleton.parents[p])
            parents.append(sent[p] if p >= 0 else -1)
        self.parents = np.array(parents, dtype=np.int64)
        reference_rotations, reference_positions, _ = reference_pose(rig.character, rig.joints)
        self.reference_inverse = quat.conjugate(reference_rotations[self.joints])
        # the T-pose of each bone, turned to the character's body axes, then swung onto its reference pose
        aligned = []
        for name in self.names:
            canonical = VRM_BONES[name]
            child = rig.joint(TPOSE_CHILD.get(canonical, ""))
            if child is None:
                aligned.append(rig.body)
                continue
            tpose = quat.rotate(rig.body, np.subtract(canonical_joint(TPOSE_CHILD[canonical]).position,
                                                      canonical_joint(canonical).position))
            own = reference_positions[child] - reference_positions[rig.joint(canonical)]
            aligned.append(quat.multiply(quat.between(tpose, own), rig.body))
        self.tpose = np.array(aligned)

    def local(self, rotations: np.ndarray, root: np.ndarray,
              translations: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Local positions (B, 3) and rotations (B, 4) of the sent bones, core frame, for one pose:
        ``rotations`` (J, 4) local joint rotations, ``root`` (3,) root translation, metres, and
        ``translations`` (J, 3) local joint translations, metres (None: the rest offsets)."""
        global_rotations, global_positions = forward_kinematics(
            self.skeleton, rotations[None], root[None], None if translations is None else translations[None])
        # (B, 4): the receiver's T-pose bone -> the character's reference pose -> now
        normalized = quat.multiply(quat.multiply(global_rotations[0, self.joints], self.reference_inverse), self.tpose)
        positions = global_positions[0, self.joints]
        has_parent = self.parents >= 0
        parent = np.where(has_parent, self.parents, 0)
        inverse_parent = np.where(has_parent[:, None], quat.conjugate(normalized[parent]), quat.IDENTITY)
        offsets = positions - np.where(has_parent[:, None], positions[parent], 0.0)
        return quat.rotate(inverse_parent, offsets), quat.multiply(inverse_parent, normalized)


def to_unity(positions: np.ndarray, rotations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Core-frame positions (..., 3) and rotations (..., 4) in Unity's left-handed frame."""
    return positions * _FLIP_POSITION, rotations * _FLIP_ROTATION


def from_unity(positions: np.ndarray, rotations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of :func:`to_unity` (it is its own inverse)."""
    return positions * _FLIP_POSITION, rotations * _FLIP_ROTATION


class VmcSender:
    """Sends ``character`` of a live scene to a VMC receiver at ``host``:``port`` (see the module doc)."""

    def __init__(self, live: LiveScene, character: str, host: str, port: int):
        self.live, self.character, self.host, self.port = live, character, host, int(port)
        rig = live.scene.runtime.rig(character)
        self.bones = VmcBones(rig)
        self.morphs = list(rig.morph_targets)
        family, _, _, _, self.address = socket.getaddrinfo(host, self.port, type=socket.SOCK_DGRAM)[0]
        self.socket = socket.socket(family, socket.SOCK_DGRAM)
        # Every frame's messages keep their addresses and names: written once, a frame's numbers in one go.
        self.messages = FrameMessages()
        self.messages.add("/VMC/Ext/OK", 1)
        self.messages.add("/VMC/Ext/T", floats=1)
        self.messages.add("/VMC/Ext/Root/Pos", "root", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
        for name in self.bones.names:
            self.messages.add("/VMC/Ext/Bone/Pos", name, floats=7)
        for name in self.morphs:  # zeros too: receivers keep the last value they were sent
            self.messages.add("/VMC/Ext/Blend/Val", name, floats=1)
        self.messages.add("/VMC/Ext/Blend/Apply")
        self.sent = 0
        self._frame: LiveFrame | None = None
        self._ready = threading.Condition()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name="infuse-live-vmc", daemon=True)
        self._unsubscribe = None

    def start(self) -> "VmcSender":
        self._unsubscribe = self.live.on_frame(self._offer)
        self._thread.start()
        return self

    def close(self) -> None:
        if self._unsubscribe is not None:
            self._unsubscribe()
        with self._ready:
            self._closed = True
            self._ready.notify()
        if self._thread.is_alive():
            self._thread.join(2.0)
        self.socket.close()

    def _offer(self, frame: LiveFrame) -> None:  # on the loop thread: hand over the latest frame only
        with self._ready:
            self._frame = frame
            self._ready.notify()

    def _run(self) -> None:
        while True:
            with self._ready:
                while self._frame is None and not self._closed:
                    self._ready.wait()
                if self._closed:
                    return
                frame, self._frame = self._frame, None
            try:
                for packet in self.packets(frame):
                    self.socket.sendto(packet, self.address)
                self.sent += 1
            except OSError:  # no receiver yet, or a network hiccup: the next frame tries again
                time.sleep(0.001)

    def packets(self, frame: LiveFrame) -> list[bytes]:
        """The OSC bundles of one frame (bytes), each at most :data:`MAX_PACKET_BYTES`, ``Blend/Apply`` in
        the last: 0.1 ms for a character of 54 bones and 67 morph targets, where building each message
        took 2.7 ms (a thread sharing the interpreter with the live loop)."""
        pose = frame.characters[self.character]
        positions, rotations = to_unity(*self.bones.local(pose.rotations, pose.root, pose.translations))
        values = np.concatenate(([frame.time_s], np.concatenate((positions, rotations), axis=1).ravel(), pose.morphs))
        return self.messages.bundles(values, MAX_PACKET_BYTES)
