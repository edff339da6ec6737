"""A skeleton seen through its canonical mapping: which joint carries which, and where joints sit.

Most rigs hang every joint from its parent. Some hang a mapped joint elsewhere (RobotExpressive's
feet are children of the ground bone, moved by IK in the original rig); such a *detached* joint is
placed relative to the joint of its canonical parent (its ankle follows the knee), at the offset it
has in the reference pose. :meth:`Rig.positions_of` runs forward kinematics over this position
tree, vectorized over frames.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from infuse import quaternions as quat
from infuse.canonical import canonical_joint
from infuse.skeleton import Skeleton

from . import cq


def canonical_parent(name: str, mapped) -> str | None:
    """The nearest canonical ancestor of ``name`` that is in ``mapped`` (``None`` for none)."""
    parent = canonical_joint(name).parent
    while parent is not None and parent not in mapped:
        parent = canonical_joint(parent).parent
    return parent


def canonical_children(mapped) -> dict[str, list[str]]:
    """For each name in ``mapped``: its nearest mapped canonical descendants, in table order."""
    kids: dict[str, list[str]] = {n: [] for n in mapped}
    for n in mapped:
        p = canonical_parent(n, mapped)
        if p is not None:
            kids[p].append(n)
    return kids


class Rig:
    """``skeleton`` with ``index`` (canonical name -> joint index) and a reference pose.

    - ``rotations``/``positions``: (J, 4) and (J, 3) global reference pose (core frame, metres).
    - ``position_parent``: (J,) the joint each joint's position hangs from (-1 for roots).
    - ``offsets``: (J, 3) offset in that joint's frame (the rest translation, or for a detached
      joint its reference offset from its canonical parent's joint).
    - ``carrier``: (J,) the nearest mapped joint at or above each joint in the skeleton (-1: none),
      whose alignment turns it.
    """

    def __init__(self, skeleton: Skeleton, index: dict[str, int], rotations: np.ndarray, positions: np.ndarray):
        self.skeleton = skeleton
        order = [n for n in index]  # callers pass table order
        self.index = {n: int(index[n]) for n in order}
        self.canonical_of = {j: n for n, j in self.index.items()}
        self.rotations = np.asarray(rotations, dtype=np.float64)
        self.positions = np.asarray(positions, dtype=np.float64)
        sk = skeleton
        j_count = sk.num_joints
        parents = sk.parents
        self.position_parent = np.array(parents, dtype=np.int64)
        self.offsets = np.array(sk.rest_translations, dtype=np.float64)
        self.detached: list[int] = []
        for name, j in self.index.items():
            cp = canonical_parent(name, self.index)
            if cp is None:
                continue
            pj = self.index[cp]
            if not self.is_ancestor(pj, j):
                self.detached.append(j)
                self.position_parent[j] = pj
                self.offsets[j] = quat.rotate(quat.conjugate(self.rotations[pj]), self.positions[j] - self.positions[pj])
        carrier = np.full(j_count, -1, dtype=np.int64)
        for j in range(j_count):
            carrier[j] = j if j in self.canonical_of else (carrier[parents[j]] if parents[j] >= 0 else -1)
        self.carrier = carrier

    def is_ancestor(self, a: int, j: int) -> bool:
        """True if joint ``a`` is a (strict) ancestor of joint ``j`` in the skeleton."""
        p = self.skeleton.parents[j]
        while p >= 0:
            if p == a:
                return True
            p = self.skeleton.parents[p]
        return False

    @cached_property
    def position_order(self) -> tuple[int, ...]:
        """Joints ordered so each comes after its position parent."""
        kids: list[list[int]] = [[] for _ in range(self.skeleton.num_joints)]
        roots = []
        for j, p in enumerate(self.position_parent):
            (kids[p] if p >= 0 else roots).append(j)
        order: list[int] = []
        stack = roots[::-1]
        while stack:
            j = stack.pop()
            order.append(j)
            stack.extend(reversed(kids[j]))
        if len(order) != self.skeleton.num_joints:  # a detached joint above its own canonical parent
            raise ValueError("mapping places a joint below one of its own descendants")
        return tuple(order)

    def positions_of(self, rotations: np.ndarray, root_positions: dict[int, np.ndarray], joints=None) -> dict[int, np.ndarray]:
        """Global positions {joint: (3, F)} of ``joints`` (default all) from global ``rotations``
        (J, 4, F), component-major (see :mod:`.cq`).

        ``root_positions`` gives the (3, F) position of roots (others stay at their reference
        position) and may pin any other joint. Only the joints ``joints`` need are computed.
        """
        need = set(range(self.skeleton.num_joints)) if joints is None else set()
        if joints is not None:
            for j in joints:
                while j >= 0 and j not in need:
                    need.add(int(j))
                    j = self.position_parent[j]
        out: dict[int, np.ndarray] = {}
        for j in self.position_order:
            if j not in need:
                continue
            if j in root_positions:
                out[j] = root_positions[j]
                continue
            p = self.position_parent[j]
            if p < 0:
                out[j] = self.positions[j][:, None]
                continue
            out[j] = out[p] + cq.rotate(rotations[p], self.offsets[j][:, None])
        return out
