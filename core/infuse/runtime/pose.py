"""A character's pose over a block of frames, as controllers build it layer by layer.

Arrays are frame-major and writable: ``local_rotations`` (F, J, 4) (x, y, z, w), ``root_translations``
(F, 3) metres (joint 0's local translation), ``joint_translations`` (F, J, 3) or None (other joints'
local translations, when a controller moves them) and ``morph_weights`` (F, M), the character's face
channel state, one column per morph target. Controllers write through the methods below, which apply a
:class:`~infuse.runtime.layers.Mode` and a per-frame weight in one vectorized step.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from .. import quaternions as quat
from ..kinematics import forward_kinematics
from ..skeleton import Skeleton
from .layers import Mode


def _weights(weight, frames: int) -> np.ndarray:
    """(F, 1, 1) weights from None (1), a number or an (F,) array."""
    if weight is None:
        return np.ones((frames, 1, 1))
    w = np.asarray(weight, dtype=np.float64)
    return np.broadcast_to(w.reshape(-1, 1, 1) if w.ndim else w, (frames, 1, 1))


def weighted_rotations(rotations: np.ndarray, weight) -> np.ndarray:
    """Rotations (F, K, 4) scaled toward the identity by ``weight`` (F,) or a number (normalized lerp)."""
    r = quat.canonical_sign(rotations)
    w = _weights(weight, r.shape[0])
    out = r * w
    out[..., 3] += 1.0 - w[..., 0]
    return quat.normalize(out)


class PoseBlock:
    """The pose of one character (its :class:`~infuse.runtime.rig.Rig`) on ``frames`` frames, starting at the rest pose."""

    def __init__(self, rig, frames: int):
        sk = rig.skeleton
        self.rig = rig
        self.frames = frames
        self.local_rotations = np.repeat(sk.rest_rotations[None], frames, axis=0)
        self.root_translations = np.repeat(sk.rest_translations[:1], frames, axis=0)
        #: (F, J, 3) once a controller moves joints other than the root
        self.joint_translations: np.ndarray | None = None
        self.morph_weights = np.zeros((frames, len(rig.morph_targets)))
        self.morph_written = np.zeros(len(rig.morph_targets), dtype=bool)
        self._fk: tuple[np.ndarray, np.ndarray] | None = None

    # -- joints ----------------------------------------------------------------------------------
    def set_rotations(self, joints, rotations: np.ndarray, weight=None, mode: Mode = Mode.OVERRIDE) -> None:
        """Write local rotations (F, K, 4) of joint indices ``joints`` (K,).

        OVERRIDE slerps from the current rotation to ``rotations`` by ``weight``; ADDITIVE treats
        ``rotations`` as local offsets post-multiplied onto the current rotation, scaled by ``weight``.
        """
        joints = np.asarray(joints, dtype=np.int64)
        if joints.size == 0:
            return
        if weight is not None:
            weight = np.asarray(weight, dtype=np.float64)
            if not (weight > 0.0).any():
                return
        every = joints.size == self.local_rotations.shape[1] and bool((joints == np.arange(joints.size)).all())
        if every:
            joints = slice(None)  # a slice writes in place, without gathering
        full = weight is None or bool((weight >= 1.0).all())
        additive = Mode(mode) is Mode.ADDITIVE
        if not additive and full:
            self.local_rotations[:, joints] = rotations
            self._fk = None
            return
        current = self.local_rotations[:, joints]
        if additive:
            offsets = rotations if full else weighted_rotations(rotations, weight)
            self.local_rotations[:, joints] = quat.multiply(current, offsets)
        else:
            w = _weights(weight, self.frames)[..., 0]
            self.local_rotations[:, joints] = quat.slerp(current, rotations, np.broadcast_to(w, current.shape[:2]))
        self._fk = None

    def add_offsets(self, joints, offsets: np.ndarray, weight=None) -> None:
        """Post-multiply local offsets (F, K, 4) onto joints ``joints``, scaled by ``weight``."""
        self.set_rotations(joints, offsets, weight, Mode.ADDITIVE)

    def set_translations(self, joints, translations: np.ndarray, weight=None, mode: Mode = Mode.OVERRIDE) -> None:
        """Write local translations (F, K, 3) metres of joints ``joints`` other than the root (a clip with
        position channels on inner joints): replace (blended by ``weight``) or add (scaled)."""
        joints = np.asarray(joints, dtype=np.int64)
        if joints.size == 0:
            return
        if self.joint_translations is None:
            rest = self.rig.skeleton.rest_translations
            self.joint_translations = np.repeat(rest[None], self.frames, axis=0)
        moved = self.joint_translations
        w = _weights(weight, self.frames)
        current = moved[:, joints]
        target = current + translations if Mode(mode) is Mode.ADDITIVE else translations
        moved[:, joints] = current + w * (target - current)
        self._fk = None

    def set_root(self, translations: np.ndarray, weight=None, mode: Mode = Mode.OVERRIDE) -> None:
        """Write the root translation (F, 3) metres: replace (blended by ``weight``) or add (scaled)."""
        w = _weights(weight, self.frames)[:, 0]
        if Mode(mode) is Mode.ADDITIVE:
            self.root_translations += w * translations
        else:
            self.root_translations += w * (translations - self.root_translations)
        self._fk = None

    # -- face channels ----------------------------------------------------------------------------
    def set_morphs(self, columns, values: np.ndarray, weight=None, mode: Mode = Mode.OVERRIDE) -> None:
        """Write morph weights (F, K) of morph columns ``columns`` (K,): replace (blended) or add;
        results are clipped to [0, 1]."""
        columns = np.asarray(columns, dtype=np.int64)
        if columns.size == 0:
            return
        w = _weights(weight, self.frames)[:, 0]
        current = self.morph_weights[:, columns]
        if Mode(mode) is Mode.ADDITIVE:
            current = current + w * values
        else:
            current = current + w * (values - current)
        self.morph_weights[:, columns] = np.clip(current, 0.0, 1.0)
        self.morph_written[columns] = True

    # -- reading ------------------------------------------------------------------------------------
    def global_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Global rotations (F, J, 4) and positions (F, J, 3) in the world, the character's placement
        included, of the pose as it stands (cached until a write)."""
        if self._fk is None:
            g_rot, g_pos = forward_kinematics(self.rig.skeleton, self.local_rotations, self.root_translations,
                                              self.joint_translations)
            self._fk = self.rig.place(g_rot, g_pos)
        return self._fk

    def chain_pose(self, joints) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (F, K, 4) and positions (F, K, 3) of joints ``joints`` only (see :func:`chain_fk`)."""
        if self._fk is not None:
            g_rot, g_pos = self._fk
            return g_rot[:, joints], g_pos[:, joints]
        return self.rig.place(*chain_fk(self.rig.skeleton, self.local_rotations, self.root_translations,
                                        self.joint_translations, joints))


def ancestors(skeleton, joints) -> list[int]:
    """The joints ``joints`` and all their ancestors, parents first."""
    parents = skeleton.parents
    needed: set[int] = set()
    for j in joints:
        j = int(j)
        while j >= 0 and j not in needed:
            needed.add(j)
            j = int(parents[j])
    return sorted(needed)


@dataclass(frozen=True)
class ChainPlan:
    """How :func:`chain_fk` walks down to some joints of a skeleton; indices are into ``chain``.

    - ``chain`` (N,): the joints and their ancestors, parents first; ``source`` (N,): their columns in
      the input arrays;
    - ``levels``: (members, parents) per depth below the roots, an int when a level is one joint (a
      view, not a copy); ``inner`` / ``inner_parents``: the chain joints below a root and their parents;
    - ``roots``: chain roots other than joint 0, ``root``: joint 0's place in the chain or None;
    - ``paths`` (N, N): 1 where a column is the row's joint or one of its ancestors, so each joint's
      position is ``paths @`` (the root translation and every rotated offset on the way);
    - ``out`` (K,): the requested joints.
    """

    chain: np.ndarray
    source: np.ndarray
    levels: tuple
    inner: np.ndarray
    inner_parents: np.ndarray
    roots: np.ndarray
    root: int | None
    paths: np.ndarray
    out: np.ndarray


#: Each skeleton's chain plans by joints and columns, for as long as the skeleton lives: a Skeleton is
#: immutable and hashed by identity, so its plans are its own and go with it.
_PLANS: weakref.WeakKeyDictionary[Skeleton, dict[tuple, ChainPlan]] = weakref.WeakKeyDictionary()


def chain_plan(skeleton, joints: tuple[int, ...], columns: tuple[int, ...] | None = None) -> ChainPlan:
    """The :class:`ChainPlan` of ``joints`` (made once per skeleton, joints and columns)."""
    plans = _PLANS.get(skeleton)
    if plans is None:
        plans = _PLANS[skeleton] = {}
    plan = plans.get((joints, columns))
    if plan is None:
        plan = plans[(joints, columns)] = _plan(skeleton, joints, columns)
    return plan


def _plan(skeleton, joints: tuple[int, ...], columns: tuple[int, ...] | None) -> ChainPlan:
    chain = ancestors(skeleton, joints)
    place = {j: k for k, j in enumerate(chain)}
    column = {j: j for j in chain} if columns is None else {int(j): k for k, j in enumerate(columns)}
    parent = [place.get(int(skeleton.parents[j]), -1) for j in chain]
    depth: list[int] = []
    for k in range(len(chain)):
        depth.append(0 if parent[k] < 0 else depth[parent[k]] + 1)
    levels = []
    for d in range(1, max(depth) + 1):
        members = [k for k in range(len(chain)) if depth[k] == d]
        parents = [parent[k] for k in members]
        levels.append((members[0], parents[0]) if len(members) == 1 else (np.array(members), np.array(parents)))
    paths = np.zeros((len(chain), len(chain)))
    for k in range(len(chain)):
        a = k
        while a >= 0:
            paths[k, a] = 1.0
            a = parent[a]
    inner = [k for k in range(len(chain)) if parent[k] >= 0]
    return ChainPlan(np.array(chain), np.array([column[j] for j in chain]), tuple(levels), np.array(inner, dtype=np.int64),
                     np.array([parent[k] for k in inner], dtype=np.int64),
                     np.array([k for k in range(len(chain)) if parent[k] < 0 and chain[k] != 0], dtype=np.int64),
                     place.get(0), paths, np.array([place[int(j)] for j in joints], dtype=np.int64))


def chain_fk(skeleton, local_rotations: np.ndarray, root_translations: np.ndarray, joint_translations, joints,
             columns=None):
    """Global rotations (..., K, 4) and positions (..., K, 3) of joints ``joints`` (K,).

    Forward kinematics down the joints' ancestor chains only, so a few joints of a large skeleton
    cost their depth, not the skeleton's size. ``local_rotations`` is (..., J, 4) (any leading axes:
    frames, characters), ``root_translations`` (..., 3), ``joint_translations`` (..., J, 3) or None.
    With ``columns`` (the joints the arrays hold, in order; at least :func:`ancestors` of ``joints``)
    the joint axis of ``local_rotations`` and ``joint_translations`` holds only those joints.

    Rotations compose depth by depth (all joints of one depth at once); the offsets are then rotated
    by their parents' rotations in one step and summed along each joint's path.
    """
    plan = chain_plan(skeleton, tuple(np.asarray(joints, dtype=np.int64).tolist()),
                      None if columns is None else tuple(np.asarray(columns, dtype=np.int64).tolist()))
    rot = np.asarray(local_rotations, dtype=np.float64)[..., plan.source, :]  # a gathered copy, composed in place below
    for members, parents in plan.levels:
        rot[..., members, :] = quat.multiply(rot[..., parents, :], rot[..., members, :])
    if joint_translations is None:
        offsets = skeleton.rest_translations[plan.chain]
    else:
        offsets = joint_translations[..., plan.source, :]
    steps = np.empty(rot.shape[:-1] + (3,))
    steps[..., plan.inner, :] = quat.rotate(rot[..., plan.inner_parents, :], offsets[..., plan.inner, :])
    if plan.roots.size:
        steps[..., plan.roots, :] = offsets[..., plan.roots, :]
    if plan.root is not None:
        steps[..., plan.root, :] = root_translations
    pos = plan.paths @ steps
    return rot[..., plan.out, :], pos[..., plan.out, :]
