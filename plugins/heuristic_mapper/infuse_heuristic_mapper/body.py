"""The body plan: which pair of mirror-image limbs are the legs, which the arms, and where they meet.

A humanoid has two pairs of limbs. Each pair hangs from one joint (the two subtrees are mirror
images: the same path lengths along their main chains, about the same number of joints), the
legs and the arms lie in different branches, both pairs are mirror images about one middle
plane, and the legs point away from the head. Candidate pairs are scored on symmetry, length,
names, hands at their ends and rest geometry, and the legs/arms combinations are ranked (the
mapper assigns the best one and its close rivals completely and lets one cost decide). Path
lengths do not depend on the pose, so this works on arbitrary rest poses; the geometry tests take
the pose that makes a standing body.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from .view import SkeletonView

LEG_ROLES = frozenset({"thigh", "shin", "foot", "toe", "legpart", "toe_end"})
ARM_ROLES = frozenset({"clavicle", "shoulder", "upperarm", "forearm", "hand", "thumb", "index", "middle", "ring",
                       "pinky", "finger", "palm"})
NON_BODY_FLAGS = ("control", "secondary", "prop", "face", "root")


@dataclass(frozen=True)
class LimbPair:
    """Two mirror-image subtrees ``a`` and ``b`` hanging from joint ``branch``."""

    branch: int
    a: int
    b: int
    length: float  # mean path length from the branch to the far end of each limb, metres
    symmetry: float  # 0..1


@dataclass(frozen=True)
class BodyPlan:
    """The chosen legs and arms (either may be missing) and the score that chose them."""

    legs: LimbPair | None
    arms: LimbPair | None
    score: float
    reason: str


def _chain_profile(view: SkeletonView, branch: int, child: int, depth: int = 6) -> np.ndarray:
    chain = view.main_chain(child, depth)
    return np.cumsum(view.bone[chain])


#: Branches of one joint compared as possible limbs, the longest first (a pelvis has two legs, a spine and
#: perhaps a skirt's or a tail's chains; a chest two arms, a neck and perhaps hair).
MAX_LIMB_BRANCHES = 24


def limb_pairs(view: SkeletonView, min_fraction: float = 0.1) -> list[LimbPair]:
    """Every pair of sibling subtrees that look like mirror-image limbs."""
    out: list[LimbPair] = []
    floor = min_fraction * view.body_scale
    for j in range(view.n):
        kids = [c for c in view.children[j] if view.limb_length(j, c) > floor]
        if len(kids) < 2:
            continue
        if len(kids) > MAX_LIMB_BRANCHES:  # limbs are among a joint's longest branches; pairs grow as the square
            kids = sorted(kids, key=lambda c: -view.limb_length(j, c))[:MAX_LIMB_BRANCHES]
        profiles = {c: _chain_profile(view, j, c) for c in kids}
        for x, y in combinations(kids, 2):
            lx, ly = view.limb_length(j, x), view.limb_length(j, y)
            ratio = min(lx, ly) / max(lx, ly)
            if ratio < 0.25:
                continue
            # compare the chains joint by joint: a prop in one hand lengthens only one limb
            px, py = profiles[x], profiles[y]
            m = min(len(px), len(py))
            err = float(np.abs(px[:m] - py[:m]).sum()) / m / max(px[m - 1], py[m - 1], 1e-9)
            size_ratio = min(view.size[x], view.size[y]) / max(view.size[x], view.size[y])
            symmetry = 0.55 * max(0.0, 1.0 - 3.0 * err) + 0.25 * ratio + 0.2 * size_ratio
            if symmetry < 0.6 or px[m - 1] < floor:
                continue
            out.append(LimbPair(j, x, y, min(lx, ly), symmetry))
    return out


def _role_votes(view: SkeletonView, pair: LimbPair) -> tuple[float, float, float]:
    """Fractions of the pair's first chain joints whose names say leg, arm, or not-body."""
    leg = arm = bad = total = 0
    for root in (pair.a, pair.b):
        chain = view.main_chain(root, 5)
        for k, j in enumerate(chain):
            info = view.info[j]
            total += 1
            leg += bool(info.roles & LEG_ROLES)
            arm += bool(info.roles & ARM_ROLES)
            if k < 2 and info.flagged(*NON_BODY_FLAGS):
                bad += 1
    total = max(total, 1)
    return leg / total, arm / total, bad / 4.0


def legs_top(view: SkeletonView, legs: LimbPair) -> np.ndarray:
    """(3,) where the legs start: the joint they hang from, or the middle of their first joints when
    that joint lies down the legs' way, past half their length (thighs parented to a ground root)."""
    P = view.P
    sockets = 0.5 * (P[legs.a] + P[legs.b])
    down = 0.5 * (P[view.far[legs.a]] + P[view.far[legs.b]]) - sockets
    reach = float(down @ down)
    if reach > 1e-12 and float((P[legs.branch] - sockets) @ down) > 0.5 * reach:
        return sockets
    return P[legs.branch]


def legs_down(view: SkeletonView, legs: LimbPair, up_from: int | None) -> float:
    """Cosine between the legs' direction (from their top, :func:`legs_top`, from the joint they hang
    from or from the middle of their first joints, whichever makes the straighter body: a pelvis
    joint may sit well in front of the hips, short legs may start at pelvis helpers in front of
    it) and the body's up (from there to ``up_from``); about -1 for a standing body, about 0
    for a four-legged one."""
    if up_from is None:
        return -1.0
    P = view.P
    feet = 0.5 * (P[view.far[legs.a]] + P[view.far[legs.b]])
    tops = (legs_top(view, legs), P[legs.branch], 0.5 * (P[legs.a] + P[legs.b]))
    return min(_cos(P[up_from] - top, feet - top) for top in tops)


def _cos(u: np.ndarray, v: np.ndarray) -> float:
    nu = float(np.sqrt(u @ u))
    nv = float(np.sqrt(v @ v))
    if nu < 1e-12 or nv < 1e-12:
        return 1.0
    return float(u @ v) / (nu * nv)


def upper_anchor(view: SkeletonView, legs: LimbPair, arms: LimbPair | None) -> int | None:
    """The joint that stands for "up" from the legs' branch: the arms' branch, else the far end of
    the longest chain (before any lone joint) that is not a leg, an arm or named a control or prop."""
    if arms is not None and arms.branch != legs.branch:
        return arms.branch
    best, best_key = None, (False, 0.0)
    for c in view.children[legs.branch]:
        if c in (legs.a, legs.b) or (arms is not None and c in (arms.a, arms.b)):
            continue
        if view.info[c].flagged(*NON_BODY_FLAGS):
            continue  # an IK target or a prop hanging from the pelvis is not the way up
        key = (bool(view.size[c] >= 2), view.limb_length(legs.branch, c))  # a chain before a lone leaf
        if key > best_key:
            best, best_key = int(view.far[c]), key
    return best


def off_middle(view: SkeletonView, legs: LimbPair, arms: LimbPair) -> float:
    """How far the arms' pair sits from the legs' middle plane, 0 (on it) .. 1 (a leg length away
    or more, measured along the line between the hips). Both pairs of a body are mirror images
    about one plane; the digits of one hand, or two limbs of one side, are not."""
    P = view.P
    a, b = legs.a, legs.b
    # limbs that start at one place (zero-length first joints, digits of one hand): the first joints
    # along their chains that lie apart
    for a, b in zip(view.main_chain(legs.a, 4), view.main_chain(legs.b, 4)):
        if float(np.sum((P[a] - P[b]) ** 2)) > (1e-3 * view.scale) ** 2:
            break
    across = P[a] - P[b]
    width = float(np.sqrt(across @ across))
    if width < 1e-6 * view.scale:
        return 0.0
    offset = abs(float((0.5 * (P[arms.a] + P[arms.b] - P[a] - P[b])) @ across)) / width
    return min(1.0, offset / max(0.5 * legs.length, 1e-9))


def _hands_below(view: SkeletonView) -> np.ndarray:
    """(J,) bool: the joint or one below it has three or more children that are not end, twist or
    control markers (a hand with its digits)."""
    kids, _ = view.digit_counts()
    below = kids >= 3
    parents = view.parents
    for j in range(view.n - 1, -1, -1):
        if below[j] and parents[j] >= 0:
            below[parents[j]] = True
    return below


def _best_per_branch(pairs: list[LimbPair], score: dict, keep: int, per_branch: int = 2) -> list[LimbPair]:
    """The ``keep`` best pairs, at most ``per_branch`` from one joint: many look-alike chains on one
    joint (hair, skirt) must not crowd out the limbs elsewhere."""
    out, count = [], {}
    for p in sorted(pairs, key=lambda p: -score[p]):
        if count.get(p.branch, 0) < per_branch:
            out.append(p)
            count[p.branch] = count.get(p.branch, 0) + 1
            if len(out) == keep:
                break
    return out


def rank_plans(view: SkeletonView, pairs: list[LimbPair], keep: int = 8) -> list[BodyPlan]:
    """Every legs/arms combination of the best candidate pairs (either may be missing), best first;
    empty when there is no limb pair at all.

    Each pair is first scored alone as legs and as arms (symmetry, length, names); the best few of
    each are then combined and the combination scored on how they sit in the tree and in space.
    """
    if not pairs:
        return []
    span = view.scale
    P = view.P
    as_legs, as_arms = {}, {}
    ends = {}
    hands = _hands_below(view)
    for p in pairs:
        leg_v, arm_v, bad = _role_votes(view, p)
        base = 2.0 * p.symmetry + 1.5 * p.length / span - 2.0 * bad
        as_legs[p] = base + 1.5 * (leg_v - arm_v)
        # both limbs end in hands (a joint where three or more digits branch): arms, not hair or cloth
        as_arms[p] = base + 1.5 * (arm_v - leg_v) + 0.6 * bool(hands[p.a] and hands[p.b])
        ends[p] = 0.5 * (P[view.far[p.a]] + P[view.far[p.b]])
    # a leg or an arm has two joints at least (thigh and shin, upper arm and forearm)
    jointed = [p for p in pairs if len(view.main_chain(p.a, 2)) == 2 and len(view.main_chain(p.b, 2)) == 2]
    leg_cands = _best_per_branch(jointed, as_legs, keep) + [None]
    arm_cands = _best_per_branch(jointed, as_arms, keep) + [None]
    plans: list[BodyPlan] = []
    for legs in leg_cands:
        for arms in arm_cands:
            if legs is None and arms is None:
                continue
            score, why = 0.0, []
            if legs is not None and arms is not None:
                if legs == arms or (legs.branch == arms.branch and {legs.a, legs.b} & {arms.a, arms.b}):
                    continue
                if any(view.is_descendant(arms.branch, c) for c in (legs.a, legs.b)):
                    continue
                if any(view.is_descendant(legs.branch, c) for c in (arms.a, arms.b)):
                    continue
                if arms.branch == legs.branch:
                    score -= 1.5
                elif view.is_descendant(legs.branch, arms.branch):
                    score -= 2.0  # legs hanging from below the arms' joint: upside down
                else:
                    sockets = legs_top(view, legs)
                    up = P[arms.branch] - sockets
                    if float(np.sqrt(up @ up)) < 0.08 * legs.length:
                        score -= 1.0
                    score += 0.75 * -_cos(up, ends[legs] - sockets)
                    if float((ends[arms] - ends[legs]) @ up) < 0:
                        score -= 0.5  # hands hang above the feet in every rest a person stands in
                score -= 3.0 * off_middle(view, legs, arms)
            score += as_legs[legs] if legs is not None else -2.5
            score += as_arms[arms] if arms is not None else -2.5
            if legs is None:
                why.append("no legs")
            if arms is None:
                why.append("no arms")
            plans.append(BodyPlan(legs, arms, score, ", ".join(why)))
    plans.sort(key=lambda plan: -plan.score)
    return plans


def extra_limbs(view: SkeletonView, plan: BodyPlan, pairs: list[LimbPair]) -> list[LimbPair]:
    """Further mirror-image pairs of limbs that hang from the legs' or the arms' joint beside them,
    as long as the legs, jointed like them (three joints or more) and standing on the ground with
    them: the legs of a spider. Pairs whose names say they are not body parts (wings, tails, hair,
    props) do not count, nor do chains that end above the ground (a skirt, a coat)."""
    legs, arms = plan.legs, plan.arms
    taken = {legs.a, legs.b, arms.a, arms.b}
    top = legs_top(view, legs)
    up = view.P[arms.branch] - top
    norm = float(np.sqrt(up @ up))
    if norm < 1e-9:
        return []
    height = view.P @ (up / norm)
    ground = float(height.min())
    standing = max(float(top @ (up / norm)) - ground, 1e-9)
    out = []
    for p in pairs:
        if p.branch not in (legs.branch, arms.branch) or {p.a, p.b} & taken or p.length < 0.6 * legs.length:
            continue
        if any(view.info[j].flagged(*NON_BODY_FLAGS) for j in (p.a, p.b)):
            continue
        if 0.5 * (height[view.far[p.a]] + height[view.far[p.b]]) - ground > 0.15 * standing:
            continue
        chains = [view.main_chain(j, 4) for j in (p.a, p.b)]
        if all(sum(view.bone[c] > 0.05 * p.length for c in chain[1:]) >= 2 for chain in chains):
            out.append(p)
    return out

