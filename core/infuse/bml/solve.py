"""The constraint solver: local times (seconds from the block start) for every sync point of a block.

Equalities (sync attributes, ``<synchronize>``) join sync points into groups with fixed offsets
(union-find with potentials). Groups fixed by absolute times are resolved first; from there each
behaviour's timing model places its other points, which resolves more groups (rigid behaviours such as
speech go first, since they cannot adapt). A group nothing fixes is placed as early as possible: no
behaviour in it starts before the block, and ``<after>``/``<before>`` constraints on already placed
points are met. Whatever cannot be met is dropped with a reason; a dropped ``<required>`` item fails
the block.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import Callable

from .model import IMPOSSIBLE_TO_SCHEDULE, Block, Issue
from .sync import SyncRef, TimingError

ANCHOR = ("", "start")  # the block start, local time 0
TOLERANCE_S = 1e-6


class _Drop(Exception):
    def __init__(self, kind: str, key, reason: str):
        super().__init__(reason)
        self.kind, self.key, self.reason = kind, key, reason


class _RefError(Exception):
    pass


class _Resolved(dict):
    """Group root -> local time, remembering the order roots were added (``added``) and handing each
    new one out once (:meth:`take_new`)."""

    def __init__(self):
        super().__init__()
        self.added: list = []
        self._handed = 0

    def __setitem__(self, root, time):
        if root not in self:
            self.added.append(root)
        super().__setitem__(root, time)

    def take_new(self) -> list:
        new = self.added[self._handed:]
        self._handed = len(self.added)
        return new


class _Groups:
    """Union-find with potentials: ``t(node) = t(root) + potential(node)``."""

    def __init__(self):
        self.parent: dict = {}
        self.potential: dict = {}

    def __contains__(self, node) -> bool:
        return node in self.parent

    def find(self, node):
        if node not in self.parent:
            self.parent[node], self.potential[node] = node, 0.0
        path = []
        while self.parent[node] != node:
            path.append(node)
            node = self.parent[node]
        root, total = node, 0.0
        for n in reversed(path):  # compress, accumulating potentials from the root down
            total += self.potential[n]
            self.parent[n], self.potential[n] = root, total
        return root

    def root_and_potential(self, node):
        root = self.find(node)
        return root, (0.0 if node == root else self.potential[node])

    def join(self, a, b, delta: float) -> bool:
        """Require ``t(a) = t(b) + delta``; False if that contradicts what is already joined."""
        ra, pa = self.root_and_potential(a)
        rb, pb = self.root_and_potential(b)
        if ra == rb:
            return abs(pa - (pb + delta)) <= TOLERANCE_S
        self.parent[ra], self.potential[ra] = rb, pb + delta - pa
        return True


@dataclass
class Solution:
    """Local sync times per behaviour, what was dropped and why, and whether the block failed."""

    times: dict = field(default_factory=dict)
    issues: list = field(default_factory=list)
    dropped: dict = field(default_factory=dict)
    failed: str | None = None


class BlockSolver:
    """Solves one block. ``plans``: behaviour id -> :class:`~infuse.bml.behaviours.BehaviourPlan` for the
    behaviours that can be realized; ``unavailable``: behaviour id -> why it cannot; ``external(ref)`` -> the
    local time of a sync point in another block, or None."""

    def __init__(self, block: Block, plans: dict, unavailable: dict, external: Callable[[SyncRef], float | None],
                 allow_negative_start: bool):
        self.block = block
        self.plans = plans
        self.unavailable = dict(unavailable)
        self.external = external
        self.allow_negative = allow_negative_start
        self.order = {b.id: i for i, b in enumerate(block.behaviours)}
        self.dropped_constraints: dict[int, str] = {}

    # -- building -------------------------------------------------------------------------------------------
    def _node(self, ref: SyncRef):
        """(node, offset) for a sync reference, or _RefError."""
        if ref.is_absolute:
            return ANCHOR, ref.time
        if ref.block is not None and ref.block != self.block.id:
            value = self.external(ref)
            if value is None:
                raise _RefError(f"{ref.text!r} names no scheduled behaviour sync point in block {ref.block!r}")
            return ANCHOR, value
        if ref.behaviour in self.unavailable:
            raise _RefError(f"{ref.text!r} refers to {ref.behaviour!r}, which is not realized ({self.unavailable[ref.behaviour]})")
        plan = self.plans.get(ref.behaviour)
        if plan is None:
            raise _RefError(f"{ref.text!r} refers to {ref.behaviour!r}, and there is no such behaviour in block {self.block.id!r}")
        sync = plan.timing.resolve(ref.sync, ref.iteration)
        if sync is None:
            raise _RefError(f"{ref.text!r}: {ref.behaviour!r} has no sync point {ref.point!r}")
        return (ref.behaviour, sync), ref.offset

    def _build(self):
        groups, inequalities, linked = _Groups(), [], {b: set() for b in self.plans}
        groups.find(ANCHOR)
        for b in self.block.behaviours:
            if b.id not in self.plans:
                continue
            timing, own = self.plans[b.id].timing, self.plans[b.id].own_sync_attributes
            for attr, ref in b.sync_refs.items():
                if attr in own:
                    continue
                sync = timing.resolve(attr)
                if sync is None:
                    raise _Drop("behaviour", b.id, f"has no sync point {attr!r} (its {attr} attribute cannot be honoured)")
                try:
                    node, offset = self._node(ref)
                except _RefError as exc:
                    raise _Drop("behaviour", b.id, f"{attr}: {exc}") from None
                if node[0] == b.id and node[1] == sync:
                    if abs(offset) > TOLERANCE_S:
                        raise _Drop("behaviour", b.id, f"{attr}={ref.text!r} refers to itself with an offset")
                    continue
                linked[b.id].add(sync)
                if node != ANCHOR:
                    linked[node[0]].add(node[1])
                if not groups.join((b.id, sync), node, offset):
                    raise _Drop("behaviour", b.id, f"{attr}={ref.text!r} contradicts the other constraints on it")
        for index, c in enumerate(self.block.constraints):
            if index in self.dropped_constraints:
                continue
            if c.error:
                raise _Drop("constraint", index, c.error)
            try:
                entries = [self._node(r) for r in c.syncs]
                ref = self._node(c.ref) if c.ref is not None else None
            except _RefError as exc:
                raise _Drop("constraint", index, str(exc)) from None
            if c.kind == "synchronize":
                entries = entries + ([ref] if ref else [])
                for node, _ in entries:
                    if node != ANCHOR:
                        linked[node[0]].add(node[1])
                for node, offset in entries[1:]:
                    if not groups.join(node, entries[0][0], entries[0][1] - offset):
                        raise _Drop("constraint", index, "cannot be met together with the other constraints")
            elif c.kind == "before":
                inequalities.extend((index, e, ref) for e in entries)
            else:
                inequalities.extend((index, ref, e) for e in entries)
        return groups, inequalities, linked

    # -- placing --------------------------------------------------------------------------------------------
    def _place(self, b: str, state, tentative: bool) -> None:
        groups, resolved, placed, linked = state
        timing = self.plans[b].timing
        while True:
            known = {}
            for s in linked[b]:
                root, pot = groups.root_and_potential((b, s))
                if root in resolved:
                    known[s] = resolved[root] + pot
            try:
                times = timing.place(known, allow_negative_start=self.allow_negative or tentative)
            except TimingError as exc:
                raise _Drop("behaviour", b, f"cannot be scheduled: {exc}") from None
            open_syncs = [s for s in timing.sync_ids if s in linked[b] and groups.find((b, s)) not in resolved]
            if not open_syncs:
                placed[b] = times
                return
            root, pot = groups.root_and_potential((b, open_syncs[0]))
            resolved[root] = times[open_syncs[0]] - pot

    def _node_time(self, node, placed):
        if node == ANCHOR:
            return 0.0
        times = placed.get(node[0])
        return None if times is None else times[node[1]]

    def _place_all(self, groups, inequalities):
        """Place every behaviour: next the one with the best priority (all its linked points known,
        not stretchable, most points known, document order) among those tied to a known point, else
        the next free cluster as early as it may go. A heap keeps the priorities, updated as points
        become known, so each step costs a logarithm rather than a pass over the pending behaviours."""
        resolved = _Resolved()
        resolved[groups.find(ANCHOR)] = -groups.root_and_potential(ANCHOR)[1]
        placed: dict = {}
        state = (groups, resolved, placed, self.linked)
        pending = dict.fromkeys(sorted(self.plans, key=self.order.get))
        roots = {b: {groups.find((b, s)) for s in self.linked[b]} for b in pending}
        users: dict = {}
        for b, own in roots.items():
            for root in own:
                users.setdefault(root, []).append(b)
        known = dict.fromkeys(pending, 0)
        later: dict = {}  # behaviour -> the inequalities whose late point is one of its own
        for _, early, late in inequalities:
            if late[0] != ANCHOR:
                later.setdefault(late[0][0], []).append((early, late))
        heap: list = []

        def priority(b):
            n = known[b]
            return (n < len(roots[b]), self.plans[b].timing.stretchable, -n, self.order[b])

        def next_ready():
            for root in resolved.take_new():
                for b in users.get(root, ()):
                    if b in pending:
                        known[b] += 1
                        heapq.heappush(heap, (priority(b), b))
            while heap:
                key, b = heapq.heappop(heap)
                if b in pending and key == priority(b):
                    return b
            return None

        while pending:
            b = next_ready()
            if b is not None:
                self._place(b, state, tentative=False)
                del pending[b]
                continue
            # Nothing is tied to a placed point: place the next free cluster as early as it may go.
            seed = self._seed(pending, later, placed)
            first_root = len(resolved.added)
            members = [seed]
            self._place(seed, state, tentative=True)
            del pending[seed]
            while (b := next_ready()) is not None:
                self._place(b, state, tentative=True)
                del pending[b]
                members.append(b)
            cluster = set(members)
            shift = max(-min(placed[m][self.plans[m].timing.sync_ids[0]] for m in members), 0.0)
            for m in members:
                for (early, early_off), (late, late_off) in later.get(m, ()):
                    if early == ANCHOR or (early[0] in placed and early[0] not in cluster):
                        needed = self._node_time(early, placed) + early_off - (placed[late[0]][late[1]] + late_off)
                        shift = max(shift, needed)
            for m in members:
                placed[m] = {s: t + shift for s, t in placed[m].items()}
            for root in resolved.added[first_root:]:
                resolved[root] += shift
        return placed

    def _seed(self, pending, later, placed):
        def blocked(b):
            return any(early != ANCHOR and early[0] not in placed and early[0] != b for (early, _eo), _late in later.get(b, ()))
        return next((b for b in pending if not blocked(b)), next(iter(pending)))

    # -- driver ---------------------------------------------------------------------------------------------
    def solve(self) -> Solution:
        solution = Solution()
        required = {b.id for b in self.block.behaviours if b.required}
        for _ in range(len(self.block.behaviours) + len(self.block.constraints) + 2):
            try:
                groups, inequalities, self.linked = self._build()
                placed = self._place_all(groups, inequalities)
            except _Drop as drop:
                if drop.kind == "behaviour":
                    self.plans = {k: v for k, v in self.plans.items() if k != drop.key}
                    self.unavailable[drop.key] = "its timing cannot be met"
                    solution.dropped[drop.key] = drop.reason
                    where = f"{self.block.id}:{drop.key}"
                    dropped = self.block.behaviour(drop.key)
                    line = dropped.line if dropped is not None else None
                    is_required = drop.key in required
                else:
                    self.dropped_constraints[drop.key] = drop.reason
                    c = self.block.constraints[drop.key]
                    where, line, is_required = f"{self.block.id}:{c.id}" if c.id else self.block.id, c.line, c.required
                    drop.reason = f"<{c.kind}> constraint dropped: {drop.reason}"
                solution.issues.append(Issue(where, IMPOSSIBLE_TO_SCHEDULE, drop.reason, line))
                if is_required:
                    solution.failed = f"a required item cannot be realized: {drop.reason}"
                    return solution
                continue
            for index, early, late in inequalities:
                te, tl = self._node_time(early[0], placed), self._node_time(late[0], placed)
                if te is not None and tl is not None and tl + late[1] < te + early[1] - TOLERANCE_S:
                    c = self.block.constraints[index]
                    reason = (f"<{c.kind}> constraint not met: {self._label(late)} at {tl + late[1]:.3f} s comes before "
                              f"{self._label(early)} at {te + early[1]:.3f} s")
                    solution.issues.append(Issue(f"{self.block.id}:{c.id}" if c.id else self.block.id,
                                                 IMPOSSIBLE_TO_SCHEDULE, reason, c.line))
                    if c.required:
                        solution.failed = f"a required constraint cannot be met: {reason}"
                        return solution
            solution.times = placed
            return solution
        solution.failed = "the constraints could not be resolved"
        return solution

    @staticmethod
    def _label(entry) -> str:
        (node, offset) = entry
        base = "block start" if node == ANCHOR else f"{node[0]}:{node[1]}"
        return base + (f"{offset:+g}" if offset else "")
