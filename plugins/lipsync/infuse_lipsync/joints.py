"""Joint faces: channel weights -> local joint rotations (and translations), vectorized over frames.

- :class:`JawRig`: a plain jaw joint. Opening rotates it about the character's left axis (+X in the
  core frame), which moves the chin down and back; the axis is expressed in the jaw's parent frame
  from the rest pose, so it works whatever the joint's own axes are.
- :class:`PoseFace`: SmartBody face poses (one ``.skm`` pose per channel and ``face_neutral``).
  Each pose is stored as its difference from the neutral pose, per joint (a rotation vector in the
  joint's local frame, and a translation); a blend of channels adds the weighted differences
  (exponential-map blending) on top of the neutral pose, the way SmartBody's face controller adds
  its viseme and action-unit poses.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UnusableInputError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

LEFT_AXIS = np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True)
class JawRig:
    """``joint`` and the axis (unit, in its parent's frame) that opens the jaw."""

    joint: str
    index: int
    axis: np.ndarray
    rest_rotation: np.ndarray

    @classmethod
    def from_skeleton(cls, skeleton: Skeleton, joint: str) -> "JawRig":
        j = skeleton.index[joint]
        parent = skeleton.parents[j]
        parent_rot = skeleton.rest_global_rotations[parent] if parent >= 0 else quat.identity()
        axis = quat.rotate(quat.conjugate(parent_rot), LEFT_AXIS)
        return cls(joint, j, axis / np.linalg.norm(axis), skeleton.rest_rotations[j].copy())

    def rotations(self, opening: np.ndarray, max_angle: float) -> np.ndarray:
        """(K, 4) local rotations for ``opening`` (K,) in 0..1 of ``max_angle`` radians."""
        delta = quat.from_axis_angle(np.broadcast_to(self.axis, (len(opening), 3)), np.asarray(opening) * max_angle)
        return quat.multiply(delta, np.broadcast_to(self.rest_rotation, (len(opening), 4)))


@dataclass(frozen=True)
class PoseFace:
    """Face poses as differences from the neutral pose on the joints they move.

    ``joints`` (M,) indices into the skeleton; ``neutral_rotations`` (M, 4) and
    ``neutral_translations`` (M, 3); per pose, ``rotvecs[pose]`` (M, 3) and ``offsets[pose]`` (M, 3).
    """

    skeleton: Skeleton
    joints: np.ndarray
    neutral_rotations: np.ndarray
    neutral_translations: np.ndarray
    rotvecs: dict[str, np.ndarray]
    offsets: dict[str, np.ndarray]

    @classmethod
    def load(cls, skeleton: Skeleton, poses: dict[str, Path], names: list[str]) -> "PoseFace":
        """Read the ``names`` poses (and ``face_neutral`` when present) with the installed SmartBody reader."""
        import infuse

        def read(name: str):
            asset = infuse.load(poses[name])
            motion = next(iter(asset.motions.values()), None)
            if motion is None or motion.num_frames == 0:
                raise UnusableInputError(poses[name], "the face pose holds no frame")
            rot = np.array(skeleton.rest_rotations)
            trans = np.array(skeleton.rest_translations)
            src = motion.skeleton.index
            common = [(skeleton.index[n], src[n]) for n in skeleton.names if n in src]
            dst_i, src_i = np.array(common, dtype=int).T if common else (np.zeros(0, int), np.zeros(0, int))
            rot[dst_i] = motion.local_rotations[-1][src_i]
            if motion.joint_translations is not None:
                trans[dst_i] = motion.joint_translations[-1][src_i]
            return rot, trans

        neutral_rot, neutral_trans = read("face_neutral") if "face_neutral" in poses else (
            np.array(skeleton.rest_rotations), np.array(skeleton.rest_translations))
        rotvecs, offsets = {}, {}
        for name in names:
            rot, trans = read(name)
            rotvecs[name] = quat.to_rotvec(quat.multiply(quat.conjugate(neutral_rot), rot))
            offsets[name] = trans - neutral_trans
        moved = np.zeros(skeleton.num_joints, bool)
        for name in names:
            moved |= (np.abs(rotvecs[name]) > 1e-7).any(axis=1) | (np.abs(offsets[name]) > 1e-7).any(axis=1)
        joints = np.flatnonzero(moved)
        return cls(skeleton, joints, neutral_rot[joints], neutral_trans[joints],
                   {n: v[joints] for n, v in rotvecs.items()}, {n: v[joints] for n, v in offsets.items()})

    def blend(self, weights: np.ndarray, bindings: list[list[tuple[str, float]]]) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (K, M, 4) and translations (K, M, 3) of :attr:`joints` for channel ``weights``
        (K, C); channel ``c`` drives the poses of ``bindings[c]`` at their weights."""
        M = len(self.joints)
        R = np.zeros((weights.shape[1], M, 3))
        T = np.zeros((weights.shape[1], M, 3))
        for c, binding in enumerate(bindings):
            for pose, w in binding:
                R[c] += w * self.rotvecs[pose]
                T[c] += w * self.offsets[pose]
        rotvec = np.einsum("kc,cmd->kmd", weights, R)
        rotations = quat.multiply(np.broadcast_to(self.neutral_rotations, rotvec.shape[:2] + (4,)), quat.from_rotvec(rotvec))
        translations = self.neutral_translations[None] + np.einsum("kc,cmd->kmd", weights, T)
        return rotations, translations


def face_motion(skeleton: Skeleton, fps: float, K: int, rotations: dict[int, np.ndarray], translations: dict[int, np.ndarray] | None,
                name: str, morph_names: tuple[str, ...] = (), morph_weights: np.ndarray = np.zeros((0, 0))) -> Motion:
    """A clip of ``K`` frames of the whole skeleton at rest except the face joints, which are its animated
    joints: ``rotations`` joint index -> (K, 4) local rotations, ``translations`` joint index -> (K, 3)
    local translations (metres); ``morph_weights`` (K, M) of ``morph_names``."""
    local = np.tile(skeleton.rest_rotations[None], (K, 1, 1))
    for j, r in rotations.items():
        local[:, j] = r
    joint_translations = None
    if translations:
        joint_translations = np.tile(skeleton.rest_translations[None], (K, 1, 1))
        for j, t in translations.items():
            joint_translations[:, j] = t
    root = np.tile(skeleton.rest_translations[0], (K, 1))
    animated = np.zeros(skeleton.num_joints, dtype=bool)
    animated[list(rotations)] = True
    return Motion(skeleton, fps, local, root, joint_translations, name=name, morph_names=morph_names,
                  morph_weights=morph_weights, animated_joints=animated)
