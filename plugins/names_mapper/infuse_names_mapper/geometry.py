"""Limbs the names do not tell: mirror-image pairs of jointed chains read from the hierarchy and
the rest positions, for the humanoid test when a rig's names give no legs or no arms.

A limb pair is two sibling subtrees whose main chains (from the joint that hangs from the body,
always on to the child with the longest path below it) have the same path lengths joint by joint,
each of two joints or more and long against the body's span (the longest path through the tree).
Path lengths do not depend on the pose, so the pairs do not either; directions are taken from the
positions given. Lengths in the skeleton's units (metres for infuse skeletons).
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

#: a limb is at least this share of the body's span long
MIN_LIMB_OVER_SPAN = 0.12
#: the shorter limb of a pair is at least this share of the longer one, joint by joint
MIN_LENGTH_RATIO = 0.8
#: branches of one joint compared as limbs, the longest first
MAX_BRANCHES = 24


@dataclass(frozen=True)
class Limbs:
    """Two mirror-image chains ``a`` and ``b`` (joint indices from the body outwards) hanging from
    joint ``branch``; ``length``: the shorter chain's path length."""

    branch: int
    a: tuple[int, ...]
    b: tuple[int, ...]
    length: float


class Tree:
    """Bone lengths ``bone`` (J,), the longest path below each joint ``reach`` (J,), the child it
    runs through ``next`` (J,) (-1 at leaves) and ``span``, the longest path between two joints."""

    def __init__(self, skeleton, positions: np.ndarray):
        parents = np.asarray(skeleton.parents)
        self.parents = parents
        self.children = skeleton.children
        has = parents >= 0
        bone = np.zeros(len(parents))
        d = positions[has] - positions[parents[has]]
        bone[has] = np.sqrt(np.einsum("ij,ij->i", d, d))
        reach = np.zeros(len(parents))
        second = np.zeros(len(parents))
        nxt = np.full(len(parents), -1, dtype=np.int64)
        for j in range(len(parents) - 1, 0, -1):  # parents come before their children
            p = parents[j]
            if p < 0:
                continue
            cand = reach[j] + bone[j]
            if cand > reach[p]:
                second[p], reach[p], nxt[p] = reach[p], cand, j
            elif cand > second[p]:
                second[p] = cand
        self.bone, self.reach, self.next = bone, reach, nxt
        self.span = float(max(np.max(reach + second), 1e-9))

    def chain(self, j: int, limit: int = 6) -> tuple[int, ...]:
        out = [j]
        while len(out) < limit and self.next[out[-1]] >= 0:
            out.append(int(self.next[out[-1]]))
        return tuple(out)

    def inside(self, j: int, top: int) -> bool:
        """``j`` is ``top`` or below it."""
        while j >= 0:
            if j == top:
                return True
            j = int(self.parents[j])
        return False


def limb_pairs(tree: Tree) -> list[Limbs]:
    """Every pair of mirror-image jointed chains hanging from one joint, the longest first."""
    out = []
    floor = MIN_LIMB_OVER_SPAN * tree.span
    for j, kids in enumerate(tree.children):
        kids = [c for c in kids if tree.bone[c] + tree.reach[c] > floor and tree.next[c] >= 0]
        if len(kids) < 2:
            continue
        kids = sorted(kids, key=lambda c: -(tree.bone[c] + tree.reach[c]))[:MAX_BRANCHES]
        chains = {c: tree.chain(c) for c in kids}
        for x, y in combinations(kids, 2):
            px, py = (np.cumsum(tree.bone[list(chains[c])]) for c in (x, y))
            m = min(len(px), len(py))
            gap = np.abs(px[:m] - py[:m]) - (1.0 - MIN_LENGTH_RATIO) * np.maximum(px[:m], py[:m])
            if float(gap.max()) <= 0.01 * tree.span:
                out.append(Limbs(j, chains[x], chains[y], float(min(px[-1], py[-1]))))
    out.sort(key=lambda p: -p.length)
    return out
