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

from .view import SkeletonView, length, lengths

UPPER_OVER_FORE = 1.0    # upper arm / forearm length between joints (rigs range 0.6 .. 1.6)
THIGH_OVER_SHIN = 1.05   # thigh / shin length
VIRTUAL_COST = 2.2       # picking a predicted (missing) hand or foot instead of a chain joint
EARLY_END_COST = 0.6     # ... while digits or claws follow on the forearm itself


@lru_cache(maxsize=64)
def _combos(m: int, k: int, lead: int = 3) -> np.ndarray:
    """(N, k) increasing index tuples into a chain of m points; the last slot may also take the
    virtual index m (the limb ends early: no hand or foot joint, or only digits or claws past the
    slot before it, see :data:`EARLY_END_COST`). The second slot sits within the first ``lead + 1``
    chain joints (a limb starts with at most a few helpers)."""
    rows = list(combinations(range(m), k))
    if m >= k - 1:
        rows += [c + (m,) for c in combinations(range(m), k - 1)]
    rows = [r for r in rows if k < 2 or r[1] <= lead]
    return np.array(rows, dtype=np.int64).reshape(-1, k)


def _proportion_cost(x: np.ndarray) -> np.ndarray:
    """Cost of a length ratio ``x`` standard deviations from a person's: quadratic near it, linear
    past one deviation, so that cartoon proportions stay possible when the rest of the evidence
    agrees."""
    a = np.abs(x)
    return np.where(a < 1.0, a * a, 2.0 * a - 1.0)


def _early_end_cost(view: SkeletonView, chains: list[list[int]], last: np.ndarray, virtual: np.ndarray) -> np.ndarray:
    """(B, N) cost of a predicted end while chain joints follow the slot before it (index ``last``):
    cheap when digits or claws branch from that joint (a hand without a wrist joint), otherwise
    the chain goes on and the end should be on it."""
    kids, _ = view.digit_counts()
    idx = np.array(chains)
    m = idx.shape[1]
    branching = kids[idx[:, np.clip(last, 0, m - 1)]] >= 2
    early = virtual & (last < m - 1)
    return np.where(early, np.where(branching, EARLY_END_COST, 3.0 * VIRTUAL_COST), 0.0)


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
    """(B, N) sum of skip[:, lo+1 .. hi-1] per combination (a cumulative sum; ``skip`` is (B, m+1))."""
    cs = np.concatenate((np.zeros((len(skip), 1)), np.cumsum(skip, axis=1)), axis=1)
    return np.where(hi > lo + 1, cs[:, np.maximum(hi, lo + 1)] - cs[:, np.minimum(lo + 1, hi)], 0.0)


def _prefix_costs(view: SkeletonView, chains: list[list[int]], anchor: np.ndarray, scale: float, other: float) -> np.ndarray:
    """(B, m+1) cost of leaving all chain joints before index i unmapped (helpers are cheap)."""
    idx = np.array(chains)
    d = view.P[idx] - anchor
    cheap = (np.einsum("bij,bij->bi", d, d) < (1e-3 * scale) ** 2) | view.flag("helper")[idx]
    steps = np.where(cheap, 0.15, other)
    return np.concatenate((np.zeros((len(chains), 1)), np.cumsum(steps, axis=1)), axis=1)


def _leg_prefix_costs(view: SkeletonView, chain: list[int], anchor: np.ndarray, scale: float, up) -> np.ndarray:
    """Like :func:`_prefix_costs` for a leg: a joint whose bone to the next runs sideways (a pelvis
    bone from the hips' centre to the hip socket) is cheap to leave out; one whose bone goes down
    costs more the longer that bone is next to the whole chain (a thigh is not a pelvis helper)."""
    P = view.P[chain]
    near = np.einsum("ij,ij->i", P - anchor, P - anchor) < (1e-3 * scale) ** 2
    sideways = np.zeros(len(chain), dtype=bool)
    seg_len = np.zeros(len(chain))
    if len(chain) > 1:
        seg = P[1:] - P[:-1]
        seg_len[:-1] = np.sqrt(np.einsum("ij,ij->i", seg, seg))
        if up is not None:
            sideways[:-1] = (seg_len[:-1] < 1e-3 * scale) | (-(seg @ up) < 0.5 * seg_len[:-1])
    share = seg_len / max(float(seg_len.sum()), 1e-9)
    cheap = near | sideways | view.flag("helper")[np.array(chain)]
    steps = np.where(cheap, 0.3, 0.9 + 2.0 * share)
    return np.concatenate(([0.0], np.cumsum(steps)))


def _mirror_offsets(view: SkeletonView, chains: list[list[int]], anchor: np.ndarray) -> list[np.ndarray]:
    """Per chain point, half the distance to the same point of the mirror chain: how far the point
    lies from the body's middle plane. Past the shorter chain, the distance to the anchor."""
    out = []
    for i, chain in enumerate(chains):
        other = chains[1 - i] if len(chains) == 2 else None
        P = view.P[chain]
        off = lengths(P - anchor)
        if other is not None:
            m = min(len(chain), len(other))
            off[:m] = 0.5 * lengths(P[:m] - view.P[other[:m]])
        out.append(np.concatenate((off, [off[-1]])))
    return out


def _stack(view: SkeletonView, chains: list[list[int]], fn) -> np.ndarray:
    """(B, m+1) per-chain vectors from ``fn(view, chain)``."""
    return np.stack([fn(chain) for chain in chains])


def _batches(chains: list[list[int]]) -> list[list[int]]:
    """Indices of chains scored together: mirror chains of one length share every numpy call, and
    their summed cost gives left and right the same answer."""
    if len(chains) == 2 and len(chains[0]) == len(chains[1]):
        return [[0, 1]]
    return [[i] for i in range(len(chains))]


def _strongest_bend(P: np.ndarray) -> np.ndarray:
    """(B,) index of the largest bend (> 25 degrees) inside each chain of P (B, m, 3), or -1."""
    if P.shape[1] < 3:
        return np.full(len(P), -1)
    a = P[:, 1:-1] - P[:, :-2]
    b = P[:, 2:] - P[:, 1:-1]
    na = np.sqrt(np.einsum("bij,bij->bi", a, a))
    nb = np.sqrt(np.einsum("bij,bij->bi", b, b))
    ok = (na > 1e-9) & (nb > 1e-9)
    cos = np.where(ok, np.einsum("bij,bij->bi", a, b) / np.where(ok, na * nb, 1.0), 1.0)
    i = np.argmin(cos, axis=1)
    strong = cos[np.arange(len(P)), i] < np.cos(np.radians(25))
    return np.where(strong, i + 1, -1)


def _slot_paths(view: SkeletonView, chain: list[int], combos: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """(N, k) path length from the limb's branch to each slot's joint along the chain (NaN: slot
    empty); a predicted end lies its predicted distance past the slot before it. Path lengths do not
    depend on the pose."""
    m = len(chain)
    path = np.cumsum(view.bone[chain])
    idx = np.clip(combos, 0, m - 1)
    out = np.where(combos >= 0, path[idx], np.nan)
    virtual = combos[:, -1] == m
    if np.any(virtual) and combos.shape[1] >= 2:
        prev = np.clip(combos[:, -2], 0, m - 1)
        extra = lengths(predicted - view.P[np.array(chain)[prev]])
        out[:, -1] = np.where(virtual, path[prev] + extra, out[:, -1])
    return out


def _agree(view: SkeletonView, chains: list[list[int]], found: list, weight: float = 3.0) -> None:
    """Two mirror limbs whose chains differ in length (a prop or a claw on one hand) are scored
    separately; make them one decision: the pair of placements with the least summed cost, where
    each slot's path length from the branch differing between the two sides costs ``weight`` per
    limb length, and a slot filled on one side only costs ``weight / 3``. Adds that cost to each
    side's costs (in place), against the other side's chosen placement."""
    (ga, ca, Ca, Pa), (gb, cb, Cb, Pb) = found
    pa = _slot_paths(view, chains[ga[0]], ca, Pa[0])
    pb = _slot_paths(view, chains[gb[0]], cb, Pb[0])
    scale = max(float(np.nanmax(pa)), float(np.nanmax(pb)), 1e-9)
    keep = 40
    ia = np.argsort(Ca[0])[:keep]
    ib = np.argsort(Cb[0])[:keep]

    def mismatch(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        both = ~np.isnan(x) & ~np.isnan(y)
        diff = np.where(both, np.abs(np.nan_to_num(x) - np.nan_to_num(y)), 0.0).sum(axis=-1) / scale
        return diff + (np.isnan(x) != np.isnan(y)).sum(axis=-1) / 3.0

    total = Ca[0][ia][:, None] + Cb[0][ib][None, :] + weight * mismatch(pa[ia][:, None, :], pb[ib][None, :, :])
    i, j = np.unravel_index(int(np.argmin(total)), total.shape)
    Ca[0] += weight * mismatch(pa, pb[ib[j]][None, :])
    Cb[0] += weight * mismatch(pb, pa[ia[i]][None, :])


def _results(chains, group, combos, cost, predicted, slot_names, end_slot) -> list[LimbResult]:
    total = cost.sum(axis=0)
    best = int(np.argmin(total))
    margins = _margins(combos, total / len(group), best, slot_names)
    out = []
    for b, i in enumerate(group):
        chain = chains[i]
        m = len(chain)
        slots = {name: (chain[int(x)] if 0 <= int(x) < m else -1) for name, x in zip(slot_names, combos[best])}
        r = LimbResult(slots, chain, float(cost[b, best]), margins)
        if int(combos[best, -1]) == m:
            r.predicted[end_slot] = predicted[b, best]
        out.append(r)
    return out


def assign_legs(view: SkeletonView, branch: int, roots: list[int], up: np.ndarray | None) -> dict[int, LimbResult]:
    """Hip (thigh), knee (shin) and ankle (foot) joints on each leg chain starting at ``roots``."""
    anchor = view.P[branch]
    scale = view.scale
    chains = [view.main_chain(r, 9) for r in roots]
    out: dict[int, LimbResult] = {}
    found = []
    for group in _batches(chains):
        cs = [chains[i] for i in group]
        m = len(cs[0])
        P = view.P[np.array(cs)]  # (B, m, 3)
        combos = _combos(m, 3, 4)
        h, k, a = combos.T
        virtual = a == m
        Ph, Pk = P[:, h], P[:, k]
        Pa = np.where(virtual[None, :, None], Pk + (Pk - Ph) / THIGH_OVER_SHIN, P[:, np.minimum(a, m - 1)])
        thigh_v, shin_v = Pk - Ph, Pa - Pk
        thigh = np.sqrt(np.einsum("bnk,bnk->bn", thigh_v, thigh_v))
        shin = np.sqrt(np.einsum("bnk,bnk->bn", shin_v, shin_v))
        ok = (thigh > 1e-6) & (shin > 1e-6)
        ratio = np.where(ok, thigh / np.where(ok, shin, 1.0), 1.0)
        cost = np.where(ok, _proportion_cost((np.log(ratio) - np.log(THIGH_OVER_SHIN)) / 0.4), 1e6)
        if up is not None:  # thigh and shin point away from the head
            for seg, seg_len in ((thigh_v, thigh), (shin_v, shin)):
                down = -(seg @ up) / np.maximum(seg_len, 1e-9)
                cost += 6.0 * np.maximum(0.0, 0.5 - down) + 2.0 * np.maximum(0.0, 0.8 - down)
        cost += _stack(view, cs, lambda c: _leg_prefix_costs(view, c, anchor, scale, up))[:, h]
        skip = _stack(view, cs, lambda c: _skip_costs(view, c, scale))
        cost += _between(skip, h, k) + _between(skip, k, a)
        # the foot past the ankle is short: its farthest chain joint (a heel may loop back) is near
        diff = P[:, :, None, :] - P[:, None, :, :]
        dist = np.sqrt(np.einsum("bijk,bijk->bij", diff, diff))
        upper_tri = np.triu(np.ones((m, m), dtype=bool), 1)
        extent = np.concatenate((np.where(upper_tri, dist, 0.0).max(axis=2), np.zeros((len(cs), 1))), axis=1)
        rem = np.where(virtual, 0.0, extent[:, a])
        cost += np.where(rem > 0.9 * shin, ((rem / np.maximum(shin, 1e-9) - 0.9) / 0.25) ** 2, 0.0)
        start = np.sqrt(np.einsum("bnk,bnk->bn", Ph - anchor, Ph - anchor))
        cost += 0.6 * (start < 0.02 * thigh)  # a joint at the pelvis is a helper, not the thigh
        strongest = _strongest_bend(P)[:, None]
        inside = (h < strongest) & (np.minimum(a, m) > strongest) & (strongest > 0)
        cost += 1.0 * (inside & (k != strongest))
        cost += VIRTUAL_COST * virtual + _early_end_cost(view, cs, k, virtual)
        cost += _stack(view, cs, lambda c: _role_cost(view, c, {"thigh": 0.8, "shin": -0.8, "foot": -1.0, "toe": -1.0},
                                                      {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.8}))[:, h]
        cost += _stack(view, cs, lambda c: _role_cost(view, c, {"shin": 0.8, "legpart": 0.4, "thigh": -0.8,
                                                                "foot": -0.8, "toe": -1.0},
                                                      {"twist": 1.0, "end": 0.8, "control": 0.6, "helper": 0.6}))[:, k]
        cost += _stack(view, cs, lambda c: _role_cost(view, c, {"foot": 0.8, "thigh": -1.0, "shin": -0.8},
                                                      {"twist": 0.8, "end": 0.6, "control": 0.3, "heel": 0.6}))[:, a]
        found.append((group, combos, cost, Pa))
    if len(found) == 2:
        _agree(view, chains, found)
    for group, combos, cost, Pa in found:
        for i, r in zip(group, _results(chains, group, combos, cost, Pa, ("hip", "knee", "ankle"), "ankle")):
            out[roots[i]] = r
    return out


def assign_arms(view: SkeletonView, branch: int, roots: list[int]) -> dict[int, LimbResult]:
    """Clavicle, shoulder (upper arm), elbow (forearm) and wrist (hand) joints on each arm chain."""
    anchor = view.P[branch]
    scale = view.scale
    chains = [view.main_chain(r, 10) for r in roots]
    all_offsets = _mirror_offsets(view, chains, anchor)
    out: dict[int, LimbResult] = {}
    found = []
    for group in _batches(chains):
        cs = [chains[i] for i in group]
        m = len(cs[0])
        P = view.P[np.array(cs)]  # (B, m, 3)
        offset = np.stack([all_offsets[i] for i in group])
        with_c = _combos(m, 4, 3)
        without = _combos(m, 3, 4)
        combos = np.concatenate((with_c, np.concatenate((np.full((len(without), 1), -1), without), axis=1)))
        c, s, e, w = combos.T
        has_c = c >= 0
        c0 = np.maximum(c, 0)
        virtual = w == m
        Ps, Pe = P[:, s], P[:, e]
        Pw = np.where(virtual[None, :, None], Pe + (Pe - Ps) / UPPER_OVER_FORE, P[:, np.minimum(w, m - 1)])

        def norm(v):
            return np.sqrt(np.einsum("bnk,bnk->bn", v, v))
        upper = norm(Pe - Ps)
        fore = norm(Pw - Pe)
        ok = (upper > 1e-6) & (fore > 1e-6)
        ratio = np.where(ok, upper / np.where(ok, fore, 1.0), 1.0)
        cost = np.where(ok, _proportion_cost((np.log(ratio) - np.log(UPPER_OVER_FORE)) / 0.45), 1e6)
        clav = norm(Ps - P[:, c0])
        log_c = np.log(np.maximum(np.where(has_c, clav / np.maximum(upper, 1e-9), 0.5), 1e-3))
        cost += np.where(has_c, (np.maximum(0.0, np.log(0.15) - log_c) / 0.5) ** 2
                         + (np.maximum(0.0, log_c - np.log(1.6)) / 0.5) ** 2, 0.0)
        # the upper arm starts well away from the middle plane, a clavicle near it
        rel_s = offset[:, s] / np.maximum(upper, 1e-9)
        rel_c = offset[:, c0] / np.maximum(upper, 1e-9)
        cost += 4.0 * np.maximum(0.0, 0.45 - rel_s)
        cost += 3.0 * has_c * np.maximum(0.0, rel_c - 0.75)
        cost += _prefix_costs(view, cs, anchor, scale, 0.6)[:, np.where(has_c, c, s)]
        skip = _stack(view, cs, lambda ch: _skip_costs(view, ch, scale))
        cost += np.where(has_c, _between(skip, c, s) + 0.5 * (s > c + 1), 0.0)
        cost += _between(skip, s, e) + _between(skip, e, w)
        # the wrist: a short bone after it, fingers below it, no whole arm segment past it
        after = np.where((w + 1 < m) & ~virtual, norm(P[:, np.minimum(w + 1, m - 1)] - Pw), 0.0)
        cost += 2.0 * (after > 0.7 * fore)
        many, first_branch = _hand_structure(view, cs)
        cost -= 0.6 * (~virtual & many[:, np.minimum(w, m)])
        # the hand is where the fingers branch: a wrist past a branching joint is a finger
        fb = first_branch[:, None]
        palm_less = _starts_together(view, cs)[:, np.minimum(w, m - 1)] & (w == fb + 1)
        cost += 1.5 * ((e <= fb) & (w > fb) & (w < m) & ~palm_less)
        reach = view.reach[np.array(cs)]
        rem = np.where(virtual, 0.0, reach[:, np.minimum(w, m - 1)])
        cost += 0.6 * (rem > 1.6 * fore)
        strongest = _strongest_bend(P)[:, None]
        inside = (s < strongest) & (np.minimum(w, m) > strongest) & (strongest > 0)
        cost += 1.0 * (inside & (e != strongest))
        cost += VIRTUAL_COST * virtual + _early_end_cost(view, cs, e, virtual)
        cost += np.where(has_c, _stack(view, cs, lambda ch: _role_cost(
            view, ch, {"clavicle": 0.8, "shoulder": 0.4, "upperarm": -0.8, "forearm": -1.0, "hand": -1.0},
            {"twist": 1.0, "end": 1.0, "control": 0.6}))[:, c0], 0.0)
        cost += _stack(view, cs, lambda ch: _role_cost(view, ch, {"upperarm": 0.8, "shoulder": 0.3, "forearm": -0.8,
                                                                  "hand": -1.0},
                                                       {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.8}))[:, s]
        clav_named = np.concatenate((view.role("clavicle")[np.array(cs)], np.zeros((len(cs), 1), dtype=bool)), axis=1)
        cost += 0.6 * (~has_c & clav_named[:, s])
        cost += _stack(view, cs, lambda ch: _role_cost(view, ch, {"forearm": 0.8, "upperarm": -0.8, "clavicle": -1.0,
                                                                  "hand": -0.8},
                                                       {"twist": 1.0, "end": 1.0, "control": 0.6, "helper": 0.6}))[:, e]
        cost += _stack(view, cs, lambda ch: _role_cost(view, ch, {"hand": 0.8, "upperarm": -1.0, "clavicle": -1.0,
                                                                  "forearm": -0.5},
                                                       {"twist": 0.8, "end": 0.6, "control": 0.3, "prop": 1.0,
                                                        "metacarpal": 0.8}))[:, w]
        found.append((group, combos, cost, Pw))
    if len(found) == 2:
        _agree(view, chains, found)
    for group, combos, cost, Pw in found:
        for i, r in zip(group, _results(chains, group, combos, cost, Pw, ("clavicle", "shoulder", "elbow", "wrist"),
                                        "wrist")):
            out[roots[i]] = r
    return out


def _starts_together(view: SkeletonView, chains: list[list[int]]) -> np.ndarray:
    """(B, m) the chain joint has a sibling at its own place that leads somewhere: digits that all
    start at the end of the forearm (a hand without a hand joint)."""
    idx = np.array(chains)
    out = np.zeros(idx.shape, dtype=bool)
    for b, chain in enumerate(chains):
        for i, j in enumerate(chain):
            p = int(view.parents[j])
            if p < 0 or len(view.children[p]) < 2:
                continue
            tol = 0.05 * max(view.bone[j], 1e-9)
            out[b, i] = any(c != j and view.size[c] >= 2 and length(view.P[c] - view.P[j]) < tol
                            for c in view.children[p])
    return out


def _hand_structure(view: SkeletonView, chains: list[list[int]]) -> tuple[np.ndarray, np.ndarray]:
    """(B, m+1) "has two or more children" and (B,) index of the first joint where digits branch
    (three children, or two that lead somewhere), m when none."""
    kids, leading = view.digit_counts()
    idx = np.array(chains)
    many = np.concatenate((kids[idx] >= 2, np.zeros((len(chains), 1), dtype=bool)), axis=1)
    branching = (kids[idx] >= 3) | (leading[idx] >= 2)
    first = np.where(branching.any(axis=1), branching.argmax(axis=1), idx.shape[1])
    return many, first


def settle_coincident(view: SkeletonView, result: LimbResult) -> None:
    """Several joints at one place along a chain (a twist joint at the elbow, a helper above a
    joint): the slot goes to the one that branches (parents the next segments), else the last one,
    whose bone is the segment that follows; joints named twist, roll or helper only when all are."""
    chain = result.chain
    tol = 1e-3 * view.scale
    taken = {j for j in result.slots.values() if j >= 0}
    for slot, j in list(result.slots.items()):
        if j < 0 or j not in chain:
            continue
        i = chain.index(j)
        lo = i
        while lo > 0 and length(view.P[chain[lo - 1]] - view.P[chain[i]]) < tol:
            lo -= 1
        hi = i
        while hi + 1 < len(chain) and length(view.P[chain[hi + 1]] - view.P[chain[i]]) < tol:
            hi += 1
        if lo == hi:
            continue
        run = [c for c in chain[lo:hi + 1] if c == j or c not in taken]
        # a joint named twist, roll or helper never carries a limb slot over a plain one at its place
        run = [c for c in run if not view.info[c].flagged("twist", "helper")] or run
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
            off = length(view.P[c] - E - t * axis) / np.sqrt(length2)
            if 0.05 < t < 0.98 and off < 0.2 and not view.info[c].flagged("control", "prop", "end", "helper"):
                return c
    return -1


def relocate(view: SkeletonView, target: np.ndarray, exclude: set[int], tolerance: float) -> int:
    """The joint (not in ``exclude``) nearest ``target`` within ``tolerance`` that looks like a hand
    or foot (has children, is named so), or -1."""
    d = lengths(view.P - target)
    best, best_score = -1, np.inf
    for j in np.nonzero(d < tolerance)[0]:
        j = int(j)
        info = view.info[j]
        odd = info.flagged("control", "prop", "secondary", "face")
        if j in exclude or (odd and not view.children[j]):
            continue  # a bare IK target or pole, prop or cloth bone is never a hand or foot
        score = d[j] / tolerance
        score -= 0.5 * (len(view.children[j]) > 0)
        score -= 0.6 * bool(info.roles & {"hand", "foot"})
        score += 0.8 * odd + 0.3 * info.flagged("end")
        score += 0.8 * bool(info.roles & {"thumb", "index", "middle", "ring", "pinky", "finger", "toe"})
        if score < best_score:
            best, best_score = j, score
    return best
