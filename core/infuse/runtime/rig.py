"""What the runtime knows about one character: its skeleton, its canonical joints and its axes.

Controllers address joints by canonical name through the character's
:class:`~infuse.mapping.Mapping`, and express rotations in *aligned frames*
(:mod:`infuse.runtime.swing`): for joint ``j`` the constant rotation ``A_j = G_j⁻¹ · B``, with ``G_j``
the joint's global rotation in the reference pose and ``B`` the character's body frame there, turns
the joint's frame so its axes are the character's left (+X), up (+Y) and forward (+Z) in that pose. The body frame comes from the
*reference pose* and the mapping: up from the pelvis to the head, left from the right hip to the
left hip (or the shoulders, or the eyes), forward = left × up. So "forward" (of the eyes, of the
head) is derived per character, never assumed.

The reference pose is the rest pose when it stands upright (head above pelvis); some files keep
every bone along one axis at rest, and then the first frame of the character's first clip is used.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeVar

import numpy as np

from .. import quaternions as quat
from ..asset import Character
from ..mapping import Mapping
from ..skeleton import Skeleton
from .limb_ik import is_carried

#: The limbs IK turns, root to end, by canonical name ("{s}": each side, "l" and "r").
LIMBS = (("{s}_hip", "{s}_knee", "{s}_ankle"), ("{s}_shoulder", "{s}_elbow", "{s}_wrist"))
# Canonical joints tried, in order, for the top of the body and for the left-right axis.
_UP_JOINTS = ("skullbase", "spine5", "spine4", "spine3", "spine2")
_SIDE_PAIRS = (("l_hip", "r_hip"), ("l_shoulder", "r_shoulder"), ("l_acromioclavicular", "r_acromioclavicular"),
               ("eyeball_left", "eyeball_right"), ("l_knee", "r_knee"))
State = TypeVar("State")
#: What controllers keep for a character's Asset across runtimes, by the asset's id(): an entry goes
#: when its asset is collected (a finalizer), before another object can take that id.
_ASSET_STATES: dict[int, dict[type, Any]] = {}


def body_frame(positions: np.ndarray, joints: dict[str, int]) -> tuple[np.ndarray, str | None]:
    """The body frame of a pose with global joint ``positions`` (J, 3), as a quaternion (x, y, z, w)
    taking +X to the character's left, +Y to its up and +Z to its forward, and a note when it had to
    be assumed (None when derived)."""
    base = joints.get("base")
    top = next((joints[n] for n in _UP_JOINTS if n in joints), None)
    pair = next(((joints[a], joints[b]) for a, b in _SIDE_PAIRS if a in joints and b in joints), None)
    if base is None or top is None or pair is None:
        return quat.IDENTITY.copy(), "the mapping lacks the pelvis, head or a left/right pair; the core axes are assumed"
    up = positions[top] - positions[base]
    left = positions[pair[0]] - positions[pair[1]]
    if np.linalg.norm(up) < 1e-6 or np.linalg.norm(left) < 1e-6:
        return quat.IDENTITY.copy(), "the pose is degenerate; the core axes are assumed"
    up = up / np.linalg.norm(up)
    left = left - np.dot(left, up) * up
    if np.linalg.norm(left) < 1e-6:
        return quat.IDENTITY.copy(), "the pose is degenerate; the core axes are assumed"
    left = left / np.linalg.norm(left)
    forward = np.cross(left, up)
    return quat.from_matrix(np.stack((left, up, forward), axis=1)), None


def reference_pose(character: Character, joints: dict[str, int]) -> tuple[np.ndarray, np.ndarray, str]:
    """Global rotations (J, 4) and positions (J, 3) of the pose the character's axes are read from,
    and which pose it is (``"rest"`` or ``"first frame of <clip>"``); see the module doc."""
    sk = character.skeleton
    rest = (sk.rest_global_rotations, sk.rest_global_positions, "rest")
    base = joints.get("base")
    top = next((joints[n] for n in _UP_JOINTS if n in joints), None)
    if base is None or top is None:
        return rest
    up = sk.rest_global_positions[top] - sk.rest_global_positions[base]
    if up[1] > 0.5 * np.linalg.norm(up):
        return rest
    clips = list(character.clips.values()) + list(character.asset.motions.values())
    clip = next((m for m in clips if m.num_frames and m.skeleton.names == sk.names), None)
    if clip is None:
        return rest
    from ..kinematics import motion_fk

    g_rot, g_pos = motion_fk(clip.replace(local_rotations=clip.local_rotations[:1], root_translations=clip.root_translations[:1],
                                          joint_translations=None if clip.joint_translations is None else clip.joint_translations[:1]))
    return g_rot[0], g_pos[0], f"first frame of {clip.name or 'its clip'}"


@dataclass
class Rig:
    """A character as the runtime drives it.

    - ``name``: the character's name in the runtime; ``character``: the :class:`~infuse.Character`;
    - ``mapping``: canonical name -> joint; ``joints``: canonical name -> joint index (mapped names only);
    - ``position`` (3,) metres and ``rotation`` (4,): where the character stands in the world; its
      skeleton's own frame is moved by ``rotation``, then ``position`` (all else here is in its own frame);
    - ``body``: (4,) the body frame in the reference pose (see the module doc); ``reference``: which pose
      that is; ``reference_rotations``: (J, 4) its global rotations; ``aligned``: (J, 4) every joint's ``A_j``;
    - ``morph_targets``: the character's morph target names, the columns of its face channel state;
    - ``notes``: what had to be assumed about the character; ``state``: what controllers keep per
      character between blocks (one look at a time, the packs infused on it), by key: a controller's
      own class of state (:meth:`state_of`). It lives as long as the rig, so it goes with its runtime;
      what is shared by every runtime playing a character made of the same asset is :meth:`asset_state_of`'s.
    """

    name: str
    character: Character
    mapping: Mapping
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: quat.IDENTITY.copy())
    joints: dict[str, int] = field(init=False)
    body: np.ndarray = field(init=False)
    reference: str = field(init=False)
    reference_rotations: np.ndarray = field(init=False)
    notes: list[str] = field(default_factory=list)
    state: dict[Any, Any] = field(default_factory=dict)

    def __post_init__(self):
        self.joints = self.mapping.indices(self.skeleton)
        self.reference_rotations, positions, self.reference = reference_pose(self.character, self.joints)
        self.body, note = body_frame(positions, self.joints)
        if note:
            self.notes.append(note)
        elif self.reference != "rest":
            self.notes.append(f"the rest pose does not stand upright; the axes are read from the {self.reference}")

    @property
    def skeleton(self) -> Skeleton:
        return self.character.skeleton

    def state_of(self, kind: type[State]) -> State:
        """The character's state of class ``kind`` (made by ``kind()`` the first time it is asked for):
        what one controller keeps for this character between blocks and activities."""
        value = self.state.get(kind)
        if value is None:
            value = self.state[kind] = kind()
        return value

    def asset_state_of(self, kind: type[State]) -> State:
        """The state of class ``kind`` kept for the character's :class:`~infuse.Asset` (its skeleton and
        mesh), shared by every runtime and scene that plays a character made of it: what is worth working
        out once per asset (a pack infused on it). Made by ``kind()`` the first time; it goes when the
        asset goes. What it holds must not refer back to the asset, or it would keep it alive."""
        asset = self.character.asset
        key = id(asset)
        states = _ASSET_STATES.get(key)
        if states is None:
            states = _ASSET_STATES[key] = {}
            weakref.finalize(asset, _ASSET_STATES.pop, key, None)
        value = states.get(kind)
        if value is None:
            value = states[kind] = kind()
        return value

    def place(self, rotations: np.ndarray, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Global rotations (..., 4) and positions (..., 3) of the character's own frame moved to its
        place in the world (``rotation`` then ``position``)."""
        if not self.placed:
            return rotations, positions
        return quat.multiply(self.rotation, rotations), quat.rotate(self.rotation, positions) + self.position

    def side_of(self, world_point) -> str:
        """"left" or "right": the side of the character, as it is placed (its reference body frame), that
        ``world_point`` (3,) metres is on, from the pelvis."""
        own = quat.rotate(quat.conjugate(self.rotation), np.asarray(world_point, dtype=np.float64) - self.position)
        left = quat.rotate(self.body, np.array([1.0, 0.0, 0.0]))
        base = self.joints.get("base")
        centre = self.skeleton.rest_global_positions[base] if base is not None else np.zeros(3)
        return "left" if float(np.dot(own - centre, left)) >= 0.0 else "right"

    @property
    def placed(self) -> bool:
        """Whether the character stands elsewhere than its file puts it."""
        return bool(np.any(self.position != 0.0) or np.any(self.rotation != quat.IDENTITY))

    @cached_property
    def aligned(self) -> np.ndarray:
        """(J, 4) rotations ``A_j = G_j⁻¹ · B`` from each joint's frame to its aligned frame
        (``G_j``: the joint's global rotation in the reference pose)."""
        return quat.multiply(quat.conjugate(self.reference_rotations), self.body)

    @cached_property
    def carried_limbs(self) -> np.ndarray:
        """(K, 3) the mapped limbs of :data:`LIMBS` (a, b, c joints) whose end c hangs outside the limb
        (:func:`~infuse.runtime.limb_ik.is_carried`: a foot hanging from the root in a rig built for IK),
        carried by the end of b's bone; (0, 3) when there are none."""
        found = []
        for limb in LIMBS:
            for s in "lr":
                joints = [self.joints.get(n.format(s=s)) for n in limb]
                if None not in joints and is_carried(self.skeleton, joints):
                    found.append(joints)
        return np.array(found, dtype=np.int64).reshape(-1, 3)

    @cached_property
    def morph_targets(self) -> tuple[str, ...]:
        return tuple(self.character.morph_targets or ())

    @cached_property
    def morph_index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.morph_targets)}

    def joint(self, canonical: str) -> int | None:
        """The joint index of a canonical name, or None when the character has no such joint."""
        return self.joints.get(canonical)

    def morph_named(self, *candidates: str) -> str | None:
        """The first morph target named like one of ``candidates`` (case, separators and a mesh prefix
        before a ``.`` ignored), or None."""
        for c in candidates:
            name = self._morph_keys.get(_name_key(c))
            if name is not None:
                return name
        return None

    @cached_property
    def _morph_keys(self) -> dict[str, str]:
        keys: dict[str, str] = {}
        for name in self.morph_targets:
            keys.setdefault(_name_key(name.rsplit(".", 1)[-1]), name)
        return keys


def _name_key(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch.isalnum())
