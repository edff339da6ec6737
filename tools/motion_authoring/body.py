"""The body the authoring tools animate: the canonical skeleton, its measurements and a two-bone IK.

Everything is in the core frame (metres, +Y up, +Z forward, +X the character's left) and every
function is vectorized over frames. The canonical skeleton has identity rest rotations, so a joint's
global rotation is the rotation of its rest bone directions, and ``local = G_parent⁻¹ · G``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.skeleton import Skeleton

X = np.array([1.0, 0.0, 0.0])
Y = np.array([0.0, 1.0, 0.0])
Z = np.array([0.0, 0.0, 1.0])


def rot(axis: np.ndarray, angle) -> np.ndarray:
    """Quaternions (..., 4) about a fixed ``axis`` (3,) by ``angle`` radians (...)."""
    angle = np.asarray(angle, dtype=np.float64)
    return quat.from_axis_angle(np.broadcast_to(axis, angle.shape + (3,)), angle)


def smooth(x) -> np.ndarray:
    """Quintic ease 6x⁵ - 15x⁴ + 10x³ of ``x`` clipped to [0, 1] (zero slope and curvature at both ends)."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


def power(q: np.ndarray, fraction: float) -> np.ndarray:
    """``q`` raised to ``fraction`` (the same axis, the angle scaled): splits a rotation over joints."""
    return quat.from_rotvec(quat.to_rotvec(q) * fraction)


@dataclass(frozen=True)
class Body:
    """The canonical skeleton (69 required joints) and the lengths the generators need."""

    skeleton: Skeleton

    @classmethod
    def canonical(cls) -> "Body":
        return cls(canonical_skeleton(extras=False))

    def i(self, name: str) -> int:
        return self.skeleton.index[name]

    def rest(self, name: str) -> np.ndarray:
        """Global rest position (3,) of a joint, metres."""
        return self.skeleton.rest_global_positions[self.i(name)]

    def offset(self, name: str) -> np.ndarray:
        """Rest offset (3,) of a joint from its parent, metres."""
        return self.skeleton.rest_translations[self.i(name)]

    @cached_property
    def thigh(self) -> float:
        return float(np.linalg.norm(self.offset("l_knee")))

    @cached_property
    def shin(self) -> float:
        return float(np.linalg.norm(self.offset("l_ankle")))

    @cached_property
    def leg(self) -> float:
        return self.thigh + self.shin

    @cached_property
    def ankle_height(self) -> float:
        """Ankle joint height above the sole at rest (the ground is y = 0 under the feet)."""
        return float(self.rest("l_ankle")[1])

    @cached_property
    def heel(self) -> np.ndarray:
        """Heel contact point relative to the ankle, in the foot's rest frame."""
        return np.array([0.0, -self.ankle_height, -0.05])

    @cached_property
    def ball(self) -> np.ndarray:
        """Contact point under the ball of the foot, relative to the ankle, in the foot's rest frame."""
        b = self.rest("l_forefoot") - self.rest("l_ankle")
        return np.array([0.0, -self.ankle_height, b[2]])

    def locals_from_globals(self, globals_: dict[str, np.ndarray], frames: int) -> np.ndarray:
        """(F, J, 4) local rotations from global rotations of some joints (others keep their parent's)."""
        sk = self.skeleton
        g = np.empty((frames, sk.num_joints, 4))
        local = np.empty_like(g)
        for j, name in enumerate(sk.names):
            p = sk.parents[j]
            parent = g[:, p] if p >= 0 else quat.identity((frames,))
            g[:, j] = globals_[name] if name in globals_ else parent
            local[:, j] = quat.multiply(quat.conjugate(parent), g[:, j])
        return quat.normalize(local)


def frame_rotation(d0: np.ndarray, f0: np.ndarray, d1: np.ndarray, f1: np.ndarray) -> np.ndarray:
    """Rotations (F, 4) taking the frame (bone direction ``d0``, side ``f0``) to (``d1``, ``f1``).

    ``f`` vectors are made orthogonal to their ``d``; all inputs broadcast to (F, 3).
    """
    def basis(d, f):
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        f = f - np.sum(f * d, axis=-1, keepdims=True) * d
        f = f / np.linalg.norm(f, axis=-1, keepdims=True)
        return np.stack((d, f, np.cross(d, f)), axis=-1)

    d0, f0, d1, f1 = np.broadcast_arrays(d0, f0, d1, f1)
    m = basis(d1, f1) @ np.swapaxes(basis(d0, f0), -1, -2)
    return quat.from_matrix(m)


def two_bone(root: np.ndarray, goal: np.ndarray, upper: float, lower: float, pole: np.ndarray,
             rest_upper: np.ndarray, rest_lower: np.ndarray, rest_pole: np.ndarray, max_reach: float = 0.999):
    """Global rotations (F, 4) of a two-bone limb whose end reaches ``goal`` (F, 3) from ``root`` (F, 3).

    The middle joint bends toward ``pole`` (F, 3), a direction; ``rest_upper``/``rest_lower`` are the
    rest bone vectors and ``rest_pole`` the rest bend direction. Goals beyond ``max_reach`` of the
    limb's length are pulled in along the line to the root. Returns (upper rotation, lower rotation,
    middle joint position).
    """
    to_goal = goal - root
    dist = np.linalg.norm(to_goal, axis=-1, keepdims=True)
    dist_c = np.clip(dist, abs(upper - lower) + 1e-6, max_reach * (upper + lower))
    axis = to_goal / np.maximum(dist, 1e-9)
    bend = pole - np.sum(pole * axis, axis=-1, keepdims=True) * axis
    bend = bend / np.maximum(np.linalg.norm(bend, axis=-1, keepdims=True), 1e-9)
    along = (upper * upper - lower * lower + dist_c * dist_c) / (2.0 * dist_c)
    height = np.sqrt(np.maximum(upper * upper - along * along, 0.0))
    middle = root + axis * along + bend * height
    end = root + axis * dist_c
    g_upper = frame_rotation(rest_upper, rest_pole, middle - root, bend)
    g_lower = frame_rotation(rest_lower, rest_pole, end - middle, bend)
    return g_upper, g_lower, middle
