"""A skeleton prepared for mapping: positions, tree measures and name facts, computed once.

Lengths are metres in the core frame, but nothing here assumes an up axis, a facing or a unit:
the mapper finds the body's own axes from its structure (see :mod:`.body`).
"""
from __future__ import annotations

import math

import numpy as np

from .names import NameInfo, analyse_all, bits


def length(v: np.ndarray) -> float:
    """Euclidean length of one vector (faster than ``np.linalg.norm`` for a 3-vector)."""
    return math.sqrt(float(v @ v))


def lengths(v: np.ndarray) -> np.ndarray:
    """Row lengths of an (N, 3) array."""
    return np.sqrt(np.einsum("ij,ij->i", v, v))


class SkeletonView:
    """Joint positions ``P`` (J, 3) of one pose plus topology and measures of the tree.

    - ``bone[j]``: distance from the parent's position (0 for roots).
    - ``reach[j]``: longest path length (sum of bone lengths) from ``j`` down to a descendant;
      ``far[j]``: that descendant.
    - ``size[j]``: joints in the subtree of ``j`` (itself included).
    - ``scale``: the longest path between two joints of the tree (the body's span), metres;
      ``body_scale``: the same without joints named as controls or props (an IK control far from
      the body does not make its limbs shorter).
    - ``info[j]``: :class:`~.names.NameInfo` of the name.
    """

    def __init__(self, skeleton, positions: np.ndarray):
        self.skeleton = skeleton
        self.names = skeleton.names
        self.parents = np.asarray(skeleton.parents)
        self.n = len(self.names)
        self.children: tuple[tuple[int, ...], ...] = skeleton.children
        self.info: tuple[NameInfo, ...] = analyse_all(tuple(self.names))
        self._facts: dict[tuple, np.ndarray] = {}
        self._role_bits = np.array([i.role_bits for i in self.info], dtype=np.int64)
        self._flag_bits = np.array([i.flag_bits for i in self.info], dtype=np.int64)
        # children a chain may follow: controls, props and secondary bones only when nothing else is
        # there, and then only when they lead somewhere (a lone prop under a hand ends the arm)
        odd = self.flag("control", "prop", "secondary")
        self.followable = tuple((tuple(c for c in kids if not odd[c])
                                 or tuple(c for c in kids if self.children[c])) if kids else kids
                                for kids in self.children)
        #: joints that carry an end site (BVH): a leaf with one is a real joint, not an end marker
        self.has_end_site = np.zeros(self.n, dtype=bool)
        self.has_end_site[np.asarray(skeleton.end_site_parents, dtype=np.int64)] = True
        # joints named as controls or props, and everything below them: not part of the body's size
        off = self.flag("control", "prop").copy()
        for j in range(self.n):
            p = self.parents[j]
            if p >= 0 and off[p]:
                off[j] = True
        self._off_body = off
        self.set_pose(positions)
        # pre/post order for subtree tests
        tin = np.zeros(self.n, dtype=np.int64)
        tout = np.zeros(self.n, dtype=np.int64)
        clock = 0
        stack = [(int(r), False) for r in reversed(skeleton.roots)]
        while stack:
            j, done = stack.pop()
            if done:
                tout[j] = clock
                clock += 1
                continue
            tin[j] = clock
            clock += 1
            stack.append((j, True))
            stack.extend((c, False) for c in reversed(self.children[j]))
        self.tin, self.tout = tin, tout
        size = np.ones(self.n, dtype=np.int64)
        for j in range(self.n - 1, 0, -1):
            p = self.parents[j]
            if p >= 0:
                size[p] += size[j]
        self.size = size

    def set_pose(self, positions: np.ndarray) -> None:
        """Use another pose (J, 3): recomputes every length-based measure."""
        P = np.asarray(positions, dtype=np.float64)
        self.P = P
        par = self.parents
        has_parent = par >= 0
        bone = np.zeros(self.n)
        bone[has_parent] = lengths(P[has_parent] - P[par[has_parent]])
        self.bone = bone
        reach = np.zeros(self.n)
        far = np.arange(self.n)
        best2 = np.zeros(self.n)  # second-longest downward path, for the span
        for j in range(self.n - 1, -1, -1):
            p = par[j]
            if p < 0:
                continue
            cand = reach[j] + bone[j]
            if cand > reach[p]:
                best2[p] = reach[p]
                reach[p] = cand
                far[p] = far[j]
            elif cand > best2[p]:
                best2[p] = cand
        self.reach = reach
        self.far = far
        self.scale = float(max(np.max(reach + best2), 1e-9))
        self.body_scale = self._span(np.where(self._off_body, 0.0, bone)) if self._off_body.any() else self.scale
        self._chains: dict[tuple[int, int], list[int]] = {}

    def _span(self, bone: np.ndarray) -> float:
        """The longest path between two joints of the tree with these bone lengths (J,)."""
        reach = np.zeros(self.n)
        best2 = np.zeros(self.n)
        for j in range(self.n - 1, -1, -1):
            p = self.parents[j]
            if p < 0:
                continue
            cand = reach[j] + bone[j]
            if cand > reach[p]:
                best2[p] = reach[p]
                reach[p] = cand
            elif cand > best2[p]:
                best2[p] = cand
        return float(max(np.max(reach + best2), 1e-9))

    # -- name facts as arrays ------------------------------------------------------------------------
    def role(self, name: str) -> np.ndarray:
        """(J,) bool: the joint's name says body part ``name``."""
        key = ("role", name)
        arr = self._facts.get(key)
        if arr is None:
            arr = self._facts[key] = (self._role_bits & bits((name,))).astype(bool)
        return arr

    def flag(self, *names: str) -> np.ndarray:
        """(J,) bool: the joint's name carries one of the warning flags ``names``."""
        key = ("flag",) + names
        arr = self._facts.get(key)
        if arr is None:
            arr = self._facts[key] = (self._flag_bits & bits(names)).astype(bool)
        return arr

    def digit_counts(self) -> tuple[np.ndarray, np.ndarray]:
        """(J,) number of children that are not end/twist/control markers, and how many of those
        lead somewhere (have children of their own)."""
        key = ("digits",)
        cached = self._facts.get(key)
        if cached is None:
            real = ~self.flag("end", "twist", "control")
            kids = np.zeros(self.n, dtype=np.int64)
            chains = np.zeros(self.n, dtype=np.int64)
            par = self.parents
            sel = (par >= 0) & real
            np.add.at(kids, par[sel], 1)
            np.add.at(chains, par[sel & (self.size >= 2)], 1)
            cached = self._facts[key] = (kids, chains)
        return cached

    # -- topology ------------------------------------------------------------------------------------
    def is_descendant(self, a: int, b: int) -> bool:
        """True when ``a`` is ``b`` or lies in the subtree of ``b``."""
        return bool(self.tin[b] <= self.tin[a] and self.tout[a] <= self.tout[b])

    def ancestors(self, j: int) -> list[int]:
        """``j``'s ancestors, nearest first."""
        out = []
        p = int(self.parents[j])
        while p >= 0:
            out.append(p)
            p = int(self.parents[p])
        return out

    def lca(self, a: int, b: int) -> int:
        """Lowest common ancestor (-1 when in different trees)."""
        while a >= 0 and not self.is_descendant(b, a):
            a = int(self.parents[a])
        return a

    def path_down(self, top: int, bottom: int) -> list[int]:
        """Joints from ``top`` down to ``bottom`` inclusive (``bottom`` must be in ``top``'s subtree)."""
        out = [bottom]
        while out[-1] != top:
            out.append(int(self.parents[out[-1]]))
        return out[::-1]

    def main_chain(self, j: int, limit: int = 16) -> list[int]:
        """From ``j`` follow the child leading to the farthest descendant, at most ``limit`` joints.

        Children whose names mark them as controls, props or secondary bones are passed over when
        another child exists (an IK hand hanging beside the forearm must not pull the chain away).
        """
        key = (j, limit)
        cached = self._chains.get(key)
        if cached is not None:
            return list(cached)
        chain = [j]
        length = self.bone + self.reach
        while len(chain) < limit:
            pool = self.followable[chain[-1]]
            if not pool:
                break
            best = pool[0]
            for c in pool[1:]:
                if length[c] > length[best]:
                    best = c
            chain.append(best)
        self._chains[key] = chain
        return list(chain)

    def subtree(self, j: int) -> np.ndarray:
        """Indices of the subtree of ``j`` (``j`` included)."""
        return np.nonzero((self.tin >= self.tin[j]) & (self.tout <= self.tout[j]))[0]

    def limb_length(self, branch: int, child: int) -> float:
        """Path length from ``branch`` through ``child`` to the farthest joint below it."""
        return float(self.bone[child] + self.reach[child])
