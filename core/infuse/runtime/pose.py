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
from .layers import Mode, clamp


def _weights(weight, frames: int) -> np.ndarray:
    """(F, 1, 1) weights from None (1), a number or an (F,) array."""
    if weight is None:
        return np.ones((frames, 1, 1))
    w = np.asarray(weight, dtype=np.float64)
    if w.shape == (frames,):  # the usual case, a view (read only by the callers) with nothing to broadcast
        return w.reshape(frames, 1, 1)
    return np.broadcast_to(w.reshape(-1, 1, 1) if w.ndim else w, (frames, 1, 1))


def weighted_rotations(rotations: np.ndarray, weight) -> np.ndarray:
    """Rotations (F, K, 4) scaled toward the identity by ``weight`` (F,) or a number (normalized lerp)."""
    r = quat.canonical_sign(rotations)
    w = _weights(weight, r.shape[0])
    out = r * w
    out[..., 3] += 1.0 - w[..., 0]
    return quat.normalize(out)


def _weighted_columns(rotations: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Rotations (F, K, 4) scaled toward the identity by ``weight`` (F, K), as :func:`weighted_rotations`."""
    r = quat.canonical_sign(rotations)
    out = r * weight[..., None]
    out[..., 3] += 1.0 - weight
    return quat.normalize(out)


class PoseBlock:
    """The pose of one character (its :class:`~infuse.runtime.rig.Rig`) on ``frames`` frames, starting at the rest pose.

    ``rotations`` (F, J, 4), ``morphs`` (F, M), ``written`` (M,) and ``roots`` (F, 3): writable arrays to
    hold the pose in, already at rest (views of a :class:`PoseTable`); made here when not given.
    """

    def __init__(self, rig, frames: int, rotations: np.ndarray | None = None, morphs: np.ndarray | None = None,
                 written: np.ndarray | None = None, roots: np.ndarray | None = None):
        sk = rig.skeleton
        self.rig = rig
        self.frames = frames
        self.local_rotations = np.repeat(sk.rest_rotations[None], frames, axis=0) if rotations is None else rotations
        self.root_translations = np.repeat(sk.rest_translations[:1], frames, axis=0) if roots is None else roots
        #: (F, J, 3) once a controller moves joints other than the root, from the start on a character
        #: whose limbs carry ends hanging outside them (placed by their translations, :meth:`carry_ends`)
        self.joint_translations: np.ndarray | None = None
        if len(rig.carried_limbs):
            self.joint_translations = np.repeat(sk.rest_translations[None], frames, axis=0)
        self.morph_weights = np.zeros((frames, len(rig.morph_targets))) if morphs is None else morphs
        self.morph_written = np.zeros(len(rig.morph_targets), dtype=bool) if written is None else written
        self._fk: tuple[np.ndarray, np.ndarray] | None = None

    def moved(self) -> None:
        """Forget the cached forward kinematics: the joints were written from outside (a :class:`PoseTable`)."""
        self._fk = None

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

    def carry_ends(self) -> None:
        """Put each limb end that hangs outside its limb (the rig's ``carried_limbs``) on the end of its
        middle joint's bone, keeping its rotation (:func:`~infuse.runtime.limb_ik.carry_ends`): whatever
        the controllers blended, a foot hanging from the root stays on its shin."""
        limbs = self.rig.carried_limbs
        if len(limbs):
            from .limb_ik import carry_ends  # limb IK builds on this module's FK

            carry_ends(self.rig.skeleton, self.local_rotations, self.root_translations, self.joint_translations, limbs)
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
        self.morph_weights[:, columns] = clamp(current, 0.0, 1.0)
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


class PoseTable:
    """Every character's pose over one block in shared arrays, so that a controller acting on many
    characters reads and writes them all in one step.

    ``local_rotations`` (F, N, 4) holds the N joints of every character side by side, one character's
    from ``first_joint[name]`` on; ``root_translations`` (F, C, 3) the C characters' roots, in the
    order of ``character_index[name]``; ``morph_weights`` (F, M) and ``morph_written`` (M,) their morph
    targets, from ``first_morph[name]`` on. ``poses`` are the characters' :class:`PoseBlock` objects,
    whose arrays are views of these. ``layout`` is a :class:`TableLayout` of the characters.
    """

    def __init__(self, layout: "TableLayout", frames: int):
        self.layout = layout
        self.frames = frames
        self.local_rotations = np.repeat(layout.rest_rotations[None], frames, axis=0)
        self.root_translations = np.repeat(layout.rest_roots[None], frames, axis=0)
        self.morph_weights = np.zeros((frames, layout.morph_count))
        self.morph_written = np.zeros(layout.morph_count, dtype=bool)
        self.poses = {rig.name: PoseBlock(rig, frames, self.local_rotations[:, j0:j1], self.morph_weights[:, m0:m1],
                                          self.morph_written[m0:m1], self.root_translations[:, c])
                      for c, (rig, (j0, j1), (m0, m1)) in enumerate(zip(layout.rigs, layout.joint_spans, layout.morph_spans))}

    @property
    def character_index(self) -> dict[str, int]:
        return self.layout.character_index

    @property
    def first_joint(self) -> dict[str, int]:
        return self.layout.first_joint

    @property
    def first_morph(self) -> dict[str, int]:
        return self.layout.first_morph

    def add_offsets(self, columns: np.ndarray, offsets: np.ndarray, weight: np.ndarray | None, poses) -> None:
        """Post-multiply local offsets (F, K, 4) onto table joints ``columns`` (K,), scaled by ``weight``
        (F, K) (None: 1) (as :meth:`PoseBlock.add_offsets` does, column by column); ``poses``: the
        characters' :class:`PoseBlock` objects written."""
        self.set_rotations(columns, offsets, weight, Mode.ADDITIVE, poses)

    def set_rotations(self, columns: np.ndarray, rotations: np.ndarray, weight: np.ndarray | None, mode: Mode, poses) -> None:
        """Write local rotations (F, K, 4) of table joints ``columns`` (K,) with weights (F, K) (None: 1), as
        :meth:`PoseBlock.set_rotations` writes each character's: a column whose weights are all 0 is
        left as it is, one whose weights are all at least 1 takes the rotations (or offsets) unweighted.
        ``poses``: the characters' :class:`PoseBlock` objects written."""
        if columns.size == 0:
            return
        additive = Mode(mode) is Mode.ADDITIVE
        if weight is not None and weight.min() >= 1.0:
            weight = None  # every column fully on: one test instead of the columns' own
        if weight is None:  # fully on
            self.local_rotations[:, columns] = quat.multiply(self.local_rotations[:, columns], rotations) if additive else rotations
        else:
            positive = np.asarray((weight > 0.0).any(axis=0))  # (K,)
            full = np.asarray((weight >= 1.0).all(axis=0))
            current = self.local_rotations[:, columns]
            if additive:
                offsets = rotations if full.all() else np.where(full[:, None], rotations, _weighted_columns(rotations, weight))
                result = quat.multiply(current, offsets)
            elif full.all():
                result = rotations
            else:
                result = np.where(full[:, None], rotations, quat.slerp(current, rotations, weight))
            if not positive.all():
                result = np.where(positive[:, None], result, current)
            self.local_rotations[:, columns] = result
        for pose in poses:
            pose.moved()

    def set_roots(self, characters: np.ndarray, translations: np.ndarray, weight: np.ndarray, mode: Mode, poses) -> None:
        """Write the root translations (F, n, 3) metres of characters ``characters`` (n,) (their
        ``character_index``) with weights (F, n), as :meth:`PoseBlock.set_root` writes each character's;
        ``poses``: their :class:`PoseBlock` objects."""
        w = weight[..., None]
        current = self.root_translations[:, characters]
        if Mode(mode) is Mode.ADDITIVE:
            current += w * translations
        else:
            current += w * (translations - current)
        self.root_translations[:, characters] = current
        for pose in poses:
            pose.moved()

    def set_morphs(self, columns: np.ndarray, values: np.ndarray, weight: np.ndarray, mode: Mode) -> None:
        """Write morph weights (F, K) of table morph columns ``columns`` (K,) with weights (F, K), as
        :meth:`PoseBlock.set_morphs` writes each character's."""
        if columns.size == 0:
            return
        current = self.morph_weights[:, columns]
        if Mode(mode) is Mode.ADDITIVE:
            current = current + weight * values
        else:
            current = current + weight * (values - current)
        self.morph_weights[:, columns] = clamp(current, 0.0, 1.0)
        self.morph_written[columns] = True


class TableLayout:
    """Where each of ``rigs`` sits in a :class:`PoseTable`: ``joint_spans`` and ``morph_spans``, (start,
    end) columns per character, ``first_joint`` / ``first_morph`` / ``character_index`` by name,
    ``rest_rotations`` (N, 4) and ``rest_roots`` (C, 3) every character's rest pose side by side and
    ``morph_count`` the morph targets of all. Made once for a set of characters."""

    def __init__(self, rigs):
        self.rigs = list(rigs)
        joints = np.cumsum([0] + [rig.skeleton.num_joints for rig in self.rigs])
        morphs = np.cumsum([0] + [len(rig.morph_targets) for rig in self.rigs])
        self.joint_spans = list(zip(joints[:-1].tolist(), joints[1:].tolist()))
        self.morph_spans = list(zip(morphs[:-1].tolist(), morphs[1:].tolist()))
        self.first_joint = {rig.name: span[0] for rig, span in zip(self.rigs, self.joint_spans)}
        self.first_morph = {rig.name: span[0] for rig, span in zip(self.rigs, self.morph_spans)}
        self.character_index = {rig.name: c for c, rig in enumerate(self.rigs)}
        self.morph_count = int(morphs[-1])
        self.rest_rotations = (np.concatenate([rig.skeleton.rest_rotations for rig in self.rigs]) if self.rigs
                               else np.zeros((0, 4)))
        self.rest_roots = np.array([rig.skeleton.rest_translations[0] for rig in self.rigs]).reshape(-1, 3)


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
    - ``levels``: (members, parents) per depth below the roots, each an int, a slice or an array
      (:func:`_places`: a view, not a copy, where it can); ``inner`` / ``inner_parents``: the chain
      joints below a root (a slice where they follow one another) and their parents;
    - ``roots``: chain roots other than joint 0, ``root``: joint 0's place in the chain or None;
    - ``paths`` (N, N): 1 where a column is the row's joint or one of its ancestors, so each joint's
      position is ``paths @`` (the root translation and every rotated offset on the way);
    - ``out`` (K,): the requested joints.
    """

    chain: np.ndarray
    source: np.ndarray
    levels: tuple
    inner: np.ndarray | slice
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


def _places(places: list[int]) -> int | slice | np.ndarray:
    """Indices ``places`` into a chain as the cheapest index that picks them, in order: one place, a slice
    (evenly spaced, or one place for every row: a length-one slice that broadcasts), else an array."""
    if len(places) == 1:
        return places[0]
    step = places[1] - places[0]
    if step >= 0 and all(b - a == step for a, b in zip(places, places[1:])):
        return slice(places[0], places[0] + 1) if step == 0 else slice(places[0], places[-1] + 1, step)
    return np.array(places, dtype=np.int64)


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
        levels.append((_places(members), _places(parents)))
    paths = np.zeros((len(chain), len(chain)))
    for k in range(len(chain)):
        a = k
        while a >= 0:
            paths[k, a] = 1.0
            a = parent[a]
    inner = [k for k in range(len(chain)) if parent[k] >= 0]
    spread = _places(inner) if len(inner) > 1 else None  # the inner joints as a slice where they follow one another
    return ChainPlan(np.array(chain), np.array([column[j] for j in chain]), tuple(levels),
                     spread if isinstance(spread, slice) else np.array(inner, dtype=np.int64),
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
