"""SmartBody joint state as arrays, and how ``.skm`` channel values drive it (vectorized over frames).

A :class:`Rig` holds every joint's rest data in metres and radians. :func:`animate` applies an
``.skm``'s channels the way SmartBody's SkChannel/SkJoint do:

- ``XPos``/``YPos``/``ZPos`` set the joint's position value; the local translation is
  ``offset + position``. Values are clamped to the joint's limits, so a dof the skeleton does not
  declare (frozen at 0) ignores them.
- ``Quat`` (a rotation vector) is the joint's raw rotation ``q``; the local rotation is
  ``prerot * q * postrot``. A joint whose Quat channel is not active ignores it.
- ``XRot``/``YRot``/``ZRot`` (degrees) set Euler values, clamped to limits, composed in the joint's
  Euler order, then wrapped by ``prerot``/``postrot`` the same way.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from infuse import quaternions as quat

from .sk import EULER_TYPES, POS_CHANNELS, ROT_CHANNELS, SkFile, euler_quaternions
from .skm import SkmFile


@dataclass
class Rig:
    """Per-joint arrays (J = joints): lengths in metres, angles in radians, quaternions (x, y, z, w)."""

    names: list[str]
    parents: np.ndarray  # (J,)
    offsets: np.ndarray  # (J,3)
    prerot: np.ndarray  # (J,4)
    postrot: np.ndarray  # (J,4)
    is_euler: np.ndarray  # (J,) bool
    rot_active: np.ndarray  # (J,) bool
    euler_types: list[str]
    euler_values: np.ndarray  # (J,3)
    euler_limited: np.ndarray  # (J,3) bool
    euler_limits: np.ndarray  # (J,3,2)
    pos_values: np.ndarray  # (J,3)
    pos_limited: np.ndarray  # (J,3) bool
    pos_limits: np.ndarray  # (J,3,2)

    @classmethod
    def from_sk(cls, sk: SkFile, metres_per_unit: float) -> "Rig":
        js = sk.joints
        s = metres_per_unit
        return cls(
            names=[j.name for j in js],
            parents=np.array([j.parent for j in js], dtype=np.int64),
            offsets=np.array([j.offset for j in js]) * s,
            prerot=np.array([j.prerot for j in js]),
            postrot=np.array([j.postrot for j in js]),
            is_euler=np.array([j.rot_type == "euler" for j in js]),
            rot_active=np.array([j.rot_active for j in js]),
            euler_types=[j.euler_type for j in js],
            euler_values=np.array([j.euler_values for j in js]),
            euler_limited=np.array([j.euler_limited for j in js]),
            euler_limits=np.array([j.euler_limits for j in js]),
            pos_values=np.array([j.pos_values for j in js]) * s,
            pos_limited=np.array([j.pos_limited for j in js]),
            pos_limits=np.array([j.pos_limits for j in js]) * s,
        )

    @classmethod
    def free_roots(cls, names: list[str]) -> "Rig":
        """Joints with no hierarchy, all roots at the origin, every channel free (no ``.sk`` known)."""
        n = len(names)
        ident = np.broadcast_to(quat.IDENTITY, (n, 4)).copy()
        return cls(list(names), np.full(n, -1, dtype=np.int64), np.zeros((n, 3)), ident, ident.copy(),
                   np.zeros(n, dtype=bool), np.ones(n, dtype=bool), ["YXZ"] * n, np.zeros((n, 3)),
                   np.zeros((n, 3), dtype=bool), np.zeros((n, 3, 2)), np.zeros((n, 3)),
                   np.zeros((n, 3), dtype=bool), np.zeros((n, 3, 2)))

    def rotations(self, raw: np.ndarray, euler: np.ndarray) -> np.ndarray:
        """Local rotations (F,J,4) = ``prerot * value * postrot`` from raw Quat values and Euler angles."""
        value = np.array(raw)
        for t in EULER_TYPES:
            sel = self.is_euler & (np.array(self.euler_types) == t)
            if sel.any():
                value[:, sel] = euler_quaternions(t, euler[:, sel])
        return quat.normalize(quat.multiply(self.prerot, quat.multiply(value, self.postrot)))

    def rest(self) -> tuple[np.ndarray, np.ndarray]:
        """Rest local translations (J,3) and rotations (J,4): channels at their initial values."""
        raw = quat.identity((1, len(self.names)))
        return self.offsets + self.pos_values, self.rotations(raw, self.euler_values[None])[0]


def _clamp(raw: np.ndarray, limited: np.ndarray, limits: np.ndarray) -> np.ndarray:
    return np.where(limited, np.clip(raw, limits[..., 0], limits[..., 1]), raw)


def animate(rig: Rig, skm: SkmFile, metres_per_unit: float) -> tuple[np.ndarray, np.ndarray, dict]:
    """Local rotations (F,J,4) and translations (F,J,3, metres) of ``rig`` driven by ``skm``.

    Also returns notes: ``limited_channels`` (values changed by the joint's limits or frozen dofs,
    as SmartBody does) and ``ignored_channels`` (rotation channels the joint does not take).
    """
    frames = skm.values.shape[0]
    index = {n: i for i, n in enumerate(rig.names)}
    joints = np.array([index[c.joint] for c in skm.channels], dtype=np.int64)
    types = np.array([c.type for c in skm.channels])
    cols = skm.columns()
    labels = np.array([f"{c.joint} {c.type}" for c in skm.channels])
    notes: dict[str, list[str]] = {"limited_channels": [], "ignored_channels": []}

    pos = np.broadcast_to(rig.pos_values, (frames,) + rig.pos_values.shape).copy()
    is_pos = np.isin(types, list(POS_CHANNELS))
    if is_pos.any():
        j, d, c = joints[is_pos], np.array([POS_CHANNELS[t] for t in types[is_pos]]), cols[is_pos]
        raw = skm.values[:, c] * metres_per_unit
        pos[:, j, d] = _clamp(raw, rig.pos_limited[j, d], rig.pos_limits[j, d])
        changed = np.any(np.abs(pos[:, j, d] - raw) > 1e-9, axis=0)
        notes["limited_channels"] += labels[is_pos][changed].tolist()

    raw_quat = quat.identity((frames, len(rig.names)))
    is_quat = types == "Quat"
    if is_quat.any():
        j, c = joints[is_quat], cols[is_quat]
        takes = rig.rot_active[j] & ~rig.is_euler[j]
        rotvec = skm.values[:, c[takes, None] + np.arange(3)]
        raw_quat[:, j[takes]] = quat.from_rotvec(rotvec)
        dropped = ~takes & np.any(skm.values[:, c[:, None] + np.arange(3)] != 0.0, axis=(0, 2))
        notes["ignored_channels"] += labels[is_quat][dropped].tolist()

    euler = np.broadcast_to(rig.euler_values, (frames,) + rig.euler_values.shape).copy()
    is_rot = np.isin(types, list(ROT_CHANNELS))
    if is_rot.any():
        j, d, c = joints[is_rot], np.array([ROT_CHANNELS[t] for t in types[is_rot]]), cols[is_rot]
        takes = rig.rot_active[j] & rig.is_euler[j]
        raw = np.deg2rad(skm.values[:, c])
        clamped = _clamp(raw, rig.euler_limited[j, d], rig.euler_limits[j, d])
        euler[:, j[takes], d[takes]] = clamped[:, takes]
        changed = takes & np.any(np.abs(clamped - raw) > 1e-12, axis=0)
        notes["limited_channels"] += labels[is_rot][changed].tolist()
        notes["ignored_channels"] += labels[is_rot][~takes & np.any(raw != 0.0, axis=0)].tolist()

    return rig.rotations(raw_quat, euler), rig.offsets + pos, notes
