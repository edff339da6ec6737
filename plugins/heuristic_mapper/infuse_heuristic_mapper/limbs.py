"""Which joints of a limb's chain are the canonical leg and arm joints.

A limb's main chain (from the joint that hangs from the body to its farthest descendant) holds the
canonical joints plus whatever a rig adds: pelvis helpers, clavicle helpers, twist joints, palm or
grip joints, fingers and props. Every way of picking the canonical joints in chain order is scored
at once (numpy over all index combinations) from:

- proportions: thigh/shin and upper arm/forearm lengths, a short foot and hand, a clavicle that
  starts near the body's middle plane while the upper arm starts well away from it (the distance
  between the mirror-image chains measures that);
- shape: legs point away from the head, a bend in the chain marks the knee or elbow;
- structure: a wrist parents fingers, skipped joints cost unless they are helpers or twists;
- names: role words (thigh, forearm, hand...) lower the cost, twist/end/helper/control raise it.

Both limbs of a pair are scored together so that left and right get the same answer when their
chains have the same shape. A limb whose hand or foot is driven by IK ends early: a virtual end
point is predicted from the bone lengths, and a real joint there is looked for elsewhere.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from itertools import combinations

import numpy as np

from .view import SkeletonView

UPPER_OVER_FORE = 1.0    # upper arm / forearm length between joints (rigs range 0.6 .. 1.6)
THIGH_OVER_SHIN = 1.05   # thigh / shin length
VIRTUAL_COST = 2.2       # picking a predicted (missing) hand or foot instead of a chain joint


@lru_cache(maxsize=64)
def _combos(m: int, k: int) -> np.ndarray:
    """(N, k) increasing index tuples into a chain of m points; the last slot may also take the
    virtual index m, but only right after the last chain joint (the limb ends early)."""
    rows = list(combinations(range(m), k))
    if m >= k - 1:
        rows += [c + (m,) for c in combinations(range(m), k - 1) if c[-1] == m - 1]
    return np.array(rows, dtype=np.int64).reshape(-1, k)


def _bend(P: np.ndarray) -> np.ndarray:
    """(m,) turning angle in radians at each chain point (0 at the ends)."""
    out = np.zeros(len(P))
    if len(P) < 3:
        return out
    a = P[1:-1] - P[:-2]
    b = P[2:] - P[1:-1]
    na = np.linalg.norm(a, axis=1)
    nb = np.linalg.norm(b, axis=1)
    ok = (na > 1e-9) & (nb > 1e-9)
    cos = np.ones(len(a))
    cos[ok] = np.einsum("ij,ij->i", a[ok], b[ok]) / (na[ok] * nb[ok])
    out[1:-1] = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def _role_cost(view: SkeletonView, chain: list[int], good: dict[str, float], bad_flags: dict[str, float]) -> np.ndarray:
    """(m+1,) name cost of putting each chain joint in one slot (last entry: the virtual point).

    ``good``: role -> bonus (negative: the name says another slot). A role every chain joint has
    (``hand.L``, ``hand.L.001``, ``hand.L.002``) tells nothing and is ignored.
    """
    out = np.zeros(len(chain) + 1)
    infos = [view.info[j] for j in chain]
    common = frozenset.intersection(*(i.roles for i in infos)) if len(infos) >= 3 else frozenset()
    for i, info in enumerate(infos):
        roles = info.roles - common if common else info.roles
        if roles:
            pos = neg = 0.0
            for r in roles:
                w = good.get(r, 0.0)
                if w > pos:
                    pos = w
                elif w < neg:
                    neg = w
            out[i] -= pos if pos else neg
        if info.flags:
            for f in info.flags:
                out[i] += bad_flags.get(f, 0.0)
    return out


@dataclass
class LimbResult:
    """Chain joints chosen for each slot (joint index, or -1: none), the cost of the choice and, per
    slot, how much more the best alternative for that slot costs (its margin)."""

    slots: dict[str, int]
    chain: list[int]
    cost: float
    margins: dict[str, float] = field(default_factory=dict)
    notes: dict[str, str] = field(default_factory=dict)
    predicted: dict[str, np.ndarray] = field(default_factory=dict)  # slot -> predicted position when virtual


def _margins(combos: np.ndarray, cost: np.ndarray, best: int, names: tuple[str, ...]) -> dict[str, float]:
    out = {}
    for col, name in enumerate(names):
        other = combos[:, col] != combos[best, col]
        out[name] = float(np.min(cost[other]) - cost[best]) if np.any(other) else 5.0
    return out


def _skip_costs(view: SkeletonView, chain: list[int], scale: float) -> np.ndarray:
    """(m+1,) cost of leaving each chain joint unmapped between two slots (twists are cheap)."""
    out = np.full(len(chain) + 1, 0.45)
    for i, j in enumerate(chain):
        info = view.info[j]
        if info.flagged("twist"):
            out[i] = 0.05
        elif info.flagged("helper") or view.bone[j] < 1e-3 * scale:
            out[i] = 0.1
        elif info.roles:
            out[i] = 0.8  # a named body part is rarely a twist joint
    out[-1] = 0.0
    return out


def _between(skip: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Sum of skip[lo+1 .. hi-1] for each row (vectorized with a cumulative sum)."""
    cs = np.concatenate(([0.0], np.cumsum(skip)))
    return np.where(hi > lo + 1, cs[np.maximum(hi, lo + 1)] - cs[np.minimum(lo + 1, hi)], 0.0)


def _prefix_costs(view: SkeletonView, chain: list[int], anchor: np.ndarray, scale: float, other: float) -> np.ndarray:
    """(m+1,) cost of leaving all chain joints before index i unmapped."""
    near = np.einsum("ij,ij->i", view.P[chain] - anchor, view.P[chain] - anchor) < (1e-3 * scale) ** 2
    steps = [0.15 if (near[i] or view.info[j].flagged("helper")) else other for i, j in enumerate(chain)]
    return np.concatenate(([0.0], np.cumsum(steps)))


def _leg_prefix_costs(view: SkeletonView, chain: list[int], anchor: np.ndarray, scale: float, up) -> np.ndarray:
    """Like :func:`_prefix_costs` for a leg: a joint whose bone to the next runs sideways (a pelvis
    bone from the hips' centre to the hip socket) is cheap to leave out."""
    P = view.P[chain]
    near = np.einsum("ij,ij->i", P - anchor, P - anchor) < (1e-3 * scale) ** 2
    sideways = np.zeros(len(chain), dtype=bool)
    if up is not None and len(chain) > 1:
        seg = P[1:] - P[:-1]
        n = np.sqrt(np.einsum("ij,ij->i", seg, seg))
        sideways[:-1] = (n < 1e-3 * scale) | (-(seg @ up) < 0.5 * n)
    steps = [0.3 if (near[i] or sideways[i] or view.info[j].flagged("helper")) else 0.9 for i, j in enumerate(chain)]
    return np.concatenate(([0.0], np.cumsum(steps)))


def _mirror_offsets(view: SkeletonView, chains: list[list[int]], anchor: np.ndarray) -> list[np.ndarray]:
    """Per chain point, half the distance to the same point of the mirror chain: how far the point
    lies from the body's middle plane. Past the shorter chain, the distance to the anchor."""
    out = []
    for i, chain in enumerate(chains):
        other = chains[1 - i] if len(chains) == 2 else None
        P = view.P[chain]
        off = np.linalg.norm(P - anchor, axis=1)
        if other is not None:
            m = min(len(chain), len(other))
            off[:m] = 0.5 * np.linalg.norm(P[:m] - view.P[other[:m]], axis=1)
        out.append(np.concatenate((off, [off[-1]])))
    return out


def _pick(view, chains, costs, combos_list, names):
    """Best combo per chain; chains of the same length share one combo (summed costs)."""
    if len(chains) == 2 and len(chains[0]) == len(chains[1]):
        total = costs[0] + costs[1]
        best = int(np.argmin(total))
        return [(best, _margins(combos_list[0], total / 2, best, names))] * 2
    out = []
    for c, cost in zip(combos_list, costs):
        best = int(np.argmin(cost))
        out.append((best, _margins(c, cost, best, names)))
    return out


def assign_legs(view: SkeletonView, branch: int, roots: list[int], up: np.ndarray | None) -> dict[int, LimbResult]:
    """Hip (thigh), knee (shin) and ankle (foot) joints on each leg chain starting at ``roots``."""
    anchor = view.P[branch]
    scale = view.scale
    chains = [view.main_chain(r, 12) for r in roots]
    costs, combos_list, predicted = [], [], []
    for chain in chains:
        m = len(chain)
        P = view.P[chain]
        combos = _combos(m, 3)
        h, k, a = combos.T
        Ph, Pk = P[h], P[k]
        virtual = a == m
        Pa = np.where(virtual[:, None], Pk + (Pk - Ph) / THIGH_OVER_SHIN, P[np.minimum(a, m - 1)])
        thigh = np.linalg.norm(Pk - Ph, axis=1)
        shin = np.linalg.norm(Pa - Pk, axis=1)
        ok = (thigh > 1e-6) & (shin > 1e-6)
        ratio = np.where(ok, thigh / np.where(ok, shin, 1.0), 1.0)
        cost = np.where(ok, ((np.log(ratio) - np.log(THIGH_OVER_SHIN)) / 0.35) ** 2, 1e6)
        if up is not None:  # thigh and shin point away from the head
            for seg, length in ((Pk - Ph, thigh), (Pa - Pk, shin)):
                down = -(seg @ up) / np.maximum(length, 1e-9)
                cost += np.where(down < 0.5, 6.0 * (0.5 - down), 0.0)
        cost += _leg_prefix_costs(view, chain, anchor, scale, up)[h]
        skip = _skip_costs(view, chain, scale)
        cost += _between(skip, h, k) + _between(skip, k, a)
        # the foot past the ankle is short: its farthest chain joint (a heel may loop back) is near
        diff = P[:, None, :] - P[None, :, :]
        dist = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
        extent = np.array([dist[i, i + 1:].max() if i + 1 < m else 0.0 for i in range(m)] + [0.0])
        rem = np.where(virtual, 0.0, extent[a])
        cost += np.where(rem > 0.9 * shin, ((rem / np.maximum(shin, 1e-9) - 0.9) / 0.25) ** 2, 0.0)
        start = np.linalg.norm(Ph - anchor, axis=1)
        cost += np.where(start < 0.02 * thigh, 0.6, 0.0)  # a joint at the pelvis is a helper, not the thigh
        bend = np.concatenate((_bend(P), [0.0]))
        strongest = max(range(1, m - 1), key=lambda i: bend[i], default=None)
        if strongest is not None and bend[strongest] > np.radians(25):
            inside = (h < strongest) & (np.minimum(a, m) > strongest)
            cost += np.where(inside & (k != strongest), 1.0, 0.0)
        cost += VIRTUAL_COST * virtual
        cost += _role_cost(view, chain, {"thigh": 0.8, "shin": -0.8, "foot": -1.0, "toe": -1.0},
                           {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.8})[h]
        cost += _role_cost(view, chain, {"shin": 0.8, "legpart": 0.4, "thigh": -0.8, "foot": -0.8, "toe": -1.0},
                           {"twist": 1.0, "end": 0.8, "control": 0.6, "helper": 0.6})[k]
        cost += _role_cost(view, chain, {"foot": 0.8, "thigh": -1.0, "shin": -0.8},
                           {"twist": 0.8, "end": 0.6, "control": 0.3, "heel": 0.6})[a]
        costs.append(cost)
        combos_list.append(combos)
        predicted.append(Pa)
    out = {}
    for root, chain, combos, (best, margins), Pa, cost in zip(roots, chains, combos_list,
                                                              _pick(view, chains, costs, combos_list, ("hip", "knee", "ankle")),
                                                              predicted, costs):
        m = len(chain)
        hb, kb, ab = (int(x) for x in combos[best])
        r = LimbResult({"hip": chain[hb], "knee": chain[kb], "ankle": chain[ab] if ab < m else -1}, chain,
                       float(cost[best]), margins)
        if ab == m:
            r.predicted["ankle"] = Pa[best]
        out[root] = r
    return out


def assign_arms(view: SkeletonView, branch: int, roots: list[int]) -> dict[int, LimbResult]:
    """Clavicle, shoulder (upper arm), elbow (forearm) and wrist (hand) joints on each arm chain."""
    anchor = view.P[branch]
    scale = view.scale
    chains = [view.main_chain(r, 14) for r in roots]
    offsets = _mirror_offsets(view, chains, anchor)
    costs, combos_list, predicted = [], [], []
    for chain, offset in zip(chains, offsets):
        m = len(chain)
        P = view.P[chain]
        chain_arr = np.array(chain)
        with_c = _combos(m, 4)
        without = _combos(m, 3)
        combos = np.concatenate((with_c, np.concatenate((np.full((len(without), 1), -1), without), axis=1)))
        c, s, e, w = combos.T
        Ps, Pe = P[s], P[e]
        virtual = w == m
        Pw = np.where(virtual[:, None], Pe + (Pe - Ps) / UPPER_OVER_FORE, P[np.minimum(w, m - 1)])
        upper = np.linalg.norm(Pe - Ps, axis=1)
        fore = np.linalg.norm(Pw - Pe, axis=1)
        ok = (upper > 1e-6) & (fore > 1e-6)
        ratio = np.where(ok, upper / np.where(ok, fore, 1.0), 1.0)
        cost = np.where(ok, ((np.log(ratio) - np.log(UPPER_OVER_FORE)) / 0.4) ** 2, 1e6)
        has_c = c >= 0
        Pc = P[np.maximum(c, 0)]
        clav = np.linalg.norm(Ps - Pc, axis=1)
        clav_ratio = np.where(has_c, clav / np.maximum(upper, 1e-9), 0.5)
        log_c = np.log(np.maximum(clav_ratio, 1e-3))
        cost += np.where(has_c, (np.maximum(0.0, np.log(0.15) - log_c) / 0.5) ** 2
                         + (np.maximum(0.0, log_c - np.log(1.6)) / 0.5) ** 2, 0.0)
        # the upper arm starts well away from the middle plane, a clavicle near it
        rel_s = offset[s] / np.maximum(upper, 1e-9)
        rel_c = offset[np.maximum(c, 0)] / np.maximum(upper, 1e-9)
        cost += np.where(rel_s < 0.45, 4.0 * (0.45 - rel_s), 0.0)
        cost += np.where(has_c & (rel_c > 0.75), 3.0 * (rel_c - 0.75), 0.0)
        first = np.where(has_c, c, s)
        cost += _prefix_costs(view, chain, anchor, scale, 0.6)[first]
        skip = _skip_costs(view, chain, scale)
        cost += np.where(has_c, _between(skip, c, s) + 0.5 * (s > c + 1), 0.0)
        cost += _between(skip, s, e) + _between(skip, e, w)
        # the wrist: a short bone after it, fingers below it, no whole arm segment past it
        nxt = np.minimum(w + 1, m - 1)
        after = np.where((w + 1 < m) & ~virtual, np.linalg.norm(P[nxt] - Pw, axis=1), 0.0)
        cost += np.where(after > 0.7 * fore, 2.0, 0.0)
        kids = [[ch for ch in view.children[j] if not view.info[ch].flagged("end", "twist", "control")] for j in chain]
        branching = np.array([len(k) >= 3 or sum(view.size[ch] >= 2 for ch in k) >= 2 for k in kids] + [False])
        many = np.array([len(k) >= 2 for k in kids] + [False])
        cost -= np.where(~virtual & many[np.minimum(w, m)], 0.6, 0.0)
        # the hand is where the fingers branch: a wrist past a branching joint is a finger
        first_branch = next((i for i in range(m) if branching[i]), m)
        cost += np.where((e < first_branch) & (w > first_branch) & (w < m), 1.5, 0.0)
        rem = np.where(virtual, 0.0, view.reach[chain_arr[np.minimum(w, m - 1)]])
        cost += np.where(rem > 1.6 * fore, 0.6, 0.0)
        bend = np.concatenate((_bend(P), [0.0]))
        strongest = max(range(1, m - 1), key=lambda i: bend[i], default=None)
        if strongest is not None and bend[strongest] > np.radians(25):
            inside = (s < strongest) & (np.minimum(w, m) > strongest)
            cost += np.where(inside & (e != strongest), 1.0, 0.0)
        cost += VIRTUAL_COST * virtual
        cost += np.where(has_c, _role_cost(view, chain, {"clavicle": 0.8, "shoulder": 0.4, "upperarm": -0.8,
                                                         "forearm": -1.0, "hand": -1.0},
                                           {"twist": 1.0, "end": 1.0, "control": 0.6})[np.maximum(c, 0)], 0.0)
        cost += _role_cost(view, chain, {"upperarm": 0.8, "shoulder": 0.3, "forearm": -0.8, "hand": -1.0},
                           {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.8})[s]
        clav_named = np.array([view.info[j].has("clavicle") for j in chain] + [False])
        cost += np.where(~has_c & clav_named[s], 0.6, 0.0)
        cost += _role_cost(view, chain, {"forearm": 0.8, "upperarm": -0.8, "clavicle": -1.0, "hand": -0.8},
                           {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.6})[e]
        cost += _role_cost(view, chain, {"hand": 0.8, "upperarm": -1.0, "clavicle": -1.0, "forearm": -0.5},
                           {"twist": 0.8, "end": 0.6, "control": 0.3, "prop": 1.0, "metacarpal": 0.8})[w]
        costs.append(cost)
        combos_list.append(combos)
        predicted.append(Pw)
    out = {}
    names = ("clavicle", "shoulder", "elbow", "wrist")
    for root, chain, combos, (best, margins), Pw, cost in zip(roots, chains, combos_list,
                                                              _pick(view, chains, costs, combos_list, names),
                                                              predicted, costs):
        m = len(chain)
        cb, sb, eb, wb = (int(x) for x in combos[best])
        r = LimbResult({"clavicle": chain[cb] if cb >= 0 else -1, "shoulder": chain[sb], "elbow": chain[eb],
                        "wrist": chain[wb] if wb < m else -1}, chain, float(cost[best]), margins)
        if wb == m:
            r.predicted["wrist"] = Pw[best]
        out[root] = r
    return out


def settle_coincident(view: SkeletonView, result: LimbResult) -> None:
    """Several joints at one place along a chain (a twist joint at the elbow, a helper above a
    joint): the slot goes to the one that branches (parents the next segments), else the last one,
    whose bone is the segment that follows."""
    chain = result.chain
    tol = 1e-3 * view.scale
    taken = {j for j in result.slots.values() if j >= 0}
    for slot, j in list(result.slots.items()):
        if j < 0 or j not in chain:
            continue
        i = chain.index(j)
        lo = i
        while lo > 0 and float(np.linalg.norm(view.P[chain[lo - 1]] - view.P[chain[i]])) < tol:
            lo -= 1
        hi = i
        while hi + 1 < len(chain) and float(np.linalg.norm(view.P[chain[hi + 1]] - view.P[chain[i]])) < tol:
            hi += 1
        if lo == hi:
            continue
        run = [c for c in chain[lo:hi + 1] if c == j or c not in taken]
        best = max(run, key=lambda c: (len(view.children[c]), chain.index(c)))
        if best != j and not view.info[j].roles - view.info[best].roles:
            taken.discard(j)
            taken.add(best)
            result.slots[slot] = best


def forearm_twist(view: SkeletonView, result: LimbResult) -> int:
    """The first joint after the elbow and before the wrist (in the chain or hanging from it), or -1."""
    chain = result.chain
    e, w = result.slots["elbow"], result.slots["wrist"]
    ie = chain.index(e)
    iw = chain.index(w) if w in chain else len(chain)
    if iw > ie + 1:
        return chain[ie + 1]
    if w < 0:
        return -1
    E, W = view.P[e], view.P[w]
    axis = W - E
    length2 = float(np.dot(axis, axis))
    if length2 < 1e-12:
        return -1
    for j in chain[ie:iw]:
        for c in view.children[j]:
            if c in chain or view.size[c] > 2:
                continue
            t = float(np.dot(view.P[c] - E, axis)) / length2
            off = float(np.linalg.norm(view.P[c] - E - t * axis)) / np.sqrt(length2)
            if 0.05 < t < 0.98 and off < 0.2 and not view.info[c].flagged("control", "prop", "end"):
                return c
    return -1


def relocate(view: SkeletonView, target: np.ndarray, exclude: set[int], tolerance: float) -> int:
    """The joint (not in ``exclude``) nearest ``target`` within ``tolerance`` that looks like a hand
    or foot (has children, is named so), or -1."""
    d = np.linalg.norm(view.P - target, axis=1)
    best, best_score = -1, np.inf
    for j in np.nonzero(d < tolerance)[0]:
        j = int(j)
        if j in exclude:
            continue
        info = view.info[j]
        score = d[j] / tolerance
        score -= 0.5 * (len(view.children[j]) > 0)
        score -= 0.6 * bool(info.roles & {"hand", "foot"})
        score += 0.8 * info.flagged("secondary", "prop", "face", "control") + 0.3 * info.flagged("end")
        score += 0.8 * bool(info.roles & {"thumb", "index", "middle", "ring", "pinky", "finger", "toe"})
        if score < best_score:
            best, best_score = j, score
    return best
