"""The humanoid test: is a body plan (legs and arms, :mod:`.body`) two legs and two arms on a trunk?

A plan is refused, with the reason, when it lacks a pair of limbs (a snake, a fish, a flying head
with arms), when the limbs taken as legs or arms are named as other things (wings, tails, hair,
cloth, face parts, or the other kind of limb: the arms of a legless body taken as its legs), when
the legs and the arms are not joined by a trunk (the path between them runs through other limbs:
the digits of two hands), when the legs do not point away from the head (a quadruped, a lying
body), when the front limbs stand on the ground like legs under a trunk that is not upright, or
when more limbs as long as the legs stand beside them (a spider, an insect), or when the limbs
taken as arms are no arms: what is left of a shoulder girdle (two clavicle joints, a clavicle and
its landmark) reaches too short a way past its first joint, and a chain whose every joint is
named as a clavicle, a control, a landmark or cloth is no arm either.
Every measure is taken in the body's own frame and relative to its own size.
"""
from __future__ import annotations

import numpy as np

from .body import ARM_ROLES, LEG_ROLES, BodyPlan, LimbPair, extra_limbs, legs_top
from .view import SkeletonView, length

#: cos(legs direction, spine direction) above which a body is not standing (about 140 degrees)
STANDING_COS = -0.75
#: shoulders at least this many times as high above the ground as the hips: an upright trunk whose
#: long arms may hang to the ground (a person's are about 1.6 times as high, a quadruped's about as high)
UPRIGHT_SHOULDERS = 1.35
#: the path between the legs' and the arms' joints at most this many times as long as the longer
#: limb (a person's trunk is shorter than a leg; the arms and shoulders between two hands are not)
TRUNK_OVER_LIMB = 3.0
#: an arm reaches at least this share of the body below the shoulders (the legs' length plus the
#: trunk's path between the legs' and the arms' joints) past its first joint: a person's upper arm
#: and forearm about 0.35, short cartoon arms 0.16, a stubby robot arm without a forearm joint 0.17;
#: what is left of a shoulder girdle when the arms are gone 0.05-0.1
ARM_REACH_OVER_BODY = 0.12
#: flags that say a joint is no arm joint (a control, a landmark or helper, cloth or hair)
NOT_ARM_FLAGS = ("control", "helper", "secondary", "prop")


def refusal(view: SkeletonView, plan: BodyPlan | None, pairs: list[LimbPair], standing_cos: float) -> str | None:
    """Why ``plan`` is not a humanoid body, or ``None`` when it is one. ``standing_cos``: the cosine
    between the legs' direction and the spine's (:func:`.body.legs_down`)."""
    if plan is None:
        return (f"no pair of mirror-image limbs among its {view.n} joints"
                + (" (a single chain)" if all(len(c) <= 1 for c in view.children) else ""))
    if plan.legs is None or plan.arms is None:
        one = "arms" if plan.legs is None else "legs"
        return (f"only one pair of mirror-image limbs (taken as {one}) among its {view.n} joints: "
                "a humanoid has two legs and two arms on a trunk")
    for pair, kind in ((plan.legs, "legs"), (plan.arms, "arms")):
        what, named = _named_otherwise(view, pair, LEG_ROLES if kind == "legs" else ARM_ROLES)
        if named:
            return (f"the limbs taken as its {kind} are named as {what} ({', '.join(named)}): "
                    "not two legs and two arms on a trunk")
    trunk = _trunk_ratio(view, plan)
    if trunk > TRUNK_OVER_LIMB:
        return (f"the limbs taken as its legs and arms are joined by a path {trunk:.0f} times as long as they "
                "are, through other limbs: no trunk with two legs and two arms")
    no_arm = _no_arms(view, plan)
    if no_arm:
        return no_arm
    if standing_cos > STANDING_COS:
        angle = np.degrees(np.arccos(np.clip(standing_cos, -1, 1)))
        return (f"its legs do not point away from its head (they are {angle:.0f} degrees from the spine's "
                "direction instead of about 180): a four-legged or lying body")
    if hands_on_ground(view, plan):
        return "its front limbs reach the ground like its legs under a trunk that is not upright: a four-legged body"
    extra = extra_limbs(view, plan, pairs)
    if extra:
        limbs = len({j for p in extra for j in (p.a, p.b)})
        return (f"{limbs} more limbs as long as its legs hang beside its legs or arms: a many-legged body "
                "(a humanoid has two legs and two arms)")
    return None


def _named_otherwise(view: SkeletonView, pair: LimbPair, own: frozenset[str]) -> tuple[str, list[str]]:
    """(what they are named as, names) of the pair's first joints when their names say the limbs
    are something else: first joints named as wings, tails, hair, cloth or face parts, or chains
    whose names name other body parts and never a part of this kind of limb; ("", []) otherwise."""
    for flag, what in (("secondary", "wings, tails, hair or cloth"), ("face", "parts of the face")):
        flagged = [view.names[j] for j in (pair.a, pair.b) if view.info[j].flagged(flag)]
        if flagged:
            return what, flagged
    chains = [view.main_chain(j, 4) for j in (pair.a, pair.b)]
    joints = [j for chain in chains for j in chain]
    if any(view.info[j].roles & own for j in joints):
        return "", []
    other = [view.names[j] for j in joints if view.info[j].roles - own - {"hips"}]
    return ("other body parts", other[:4]) if len(other) >= 2 else ("", [])


def _no_arms(view: SkeletonView, plan: BodyPlan) -> str | None:
    """Why the limbs taken as arms are no arms, or ``None``. An arm reaches a hand-like end: either
    a hand where digits branch, or a reach past its first joint of an upper arm at least (relative
    to the legs and the trunk: a shoulder girdle left without its arms reaches a few centimetres);
    and a chain whose every joint is named as a clavicle, a control, a landmark or cloth is no arm."""
    arms, legs = plan.arms, plan.legs
    hands = _hands_at_ends(view, arms)
    trunk = _trunk_ratio(view, plan) * max(legs.length, arms.length)
    reach = min(view.reach[arms.a], view.reach[arms.b]) / max(legs.length + trunk, 1e-9)
    if not hands and reach < ARM_REACH_OVER_BODY:
        return (f"the limbs taken as its arms ({view.names[arms.a]}, {view.names[arms.b]}) reach only {reach:.2f} "
                "of its legs' and trunk's length past their first joint, with no hand: a shoulder girdle "
                "without arms (a humanoid has two legs and two arms on a trunk)")
    for root in (arms.a, arms.b):
        chain = [j for j in view.main_chain(root, 6) if not view.info[j].flagged("end")]
        infos = [view.info[j] for j in chain]
        # every joint named, none as a part of an arm past the shoulder girdle
        if infos and all(i.flagged(*NOT_ARM_FLAGS) or i.roles == frozenset({"clavicle"}) for i in infos):
            named = ", ".join(view.names[j] for j in chain[:3])
            return (f"the limb taken as an arm from {view.names[root]} is named as a shoulder girdle, a control, a "
                    f"landmark or cloth all along and never as an upper arm, forearm or hand ({named}): no arm "
                    "(a humanoid has two legs and two arms on a trunk)")
    return None


def _hands_at_ends(view: SkeletonView, arms: LimbPair) -> bool:
    """Both limbs of the pair branch into three or more jointed digits (chains, not the landmark or
    sensor leaves a shoulder may carry) past their first joint."""
    _, digits = view.digit_counts()
    return all(any(digits[j] >= 3 for j in view.main_chain(root, 8)[1:]) for root in (arms.a, arms.b))


def _trunk_ratio(view: SkeletonView, plan: BodyPlan) -> float:
    """Path length between the legs' and the arms' joints over the longer limb's length."""
    legs, arms = plan.legs, plan.arms
    top = view.lca(legs.branch, arms.branch)
    if top < 0:
        return np.inf
    path = view.path_down(top, legs.branch)[1:] + view.path_down(top, arms.branch)[1:]
    return float(view.bone[path].sum()) / max(legs.length, arms.length, 1e-9)


def hands_on_ground(view: SkeletonView, plan: BodyPlan) -> bool:
    """True when the arms' far ends are as low as the ground the legs stand on and the arms hold the
    trunk up about as high as the legs do (a quadruped's front legs); the long arms of an upright
    body hanging down (a cartoon frog, a gorilla) do not count. The ground is the lowest joint
    outside the arms: an IK-driven foot may hang elsewhere."""
    legs, arms = plan.legs, plan.arms
    sockets = legs_top(view, legs)
    up = view.P[arms.branch] - sockets
    norm = length(up)
    if norm < 1e-9:
        return False
    up /= norm
    height = view.P @ up
    outside = np.ones(view.n, dtype=bool)
    outside[view.subtree(arms.a)] = False
    outside[view.subtree(arms.b)] = False
    ground = float(height[outside].min())
    hands = height[[view.far[arms.a], view.far[arms.b]]]
    leg_height = float(sockets @ up) - ground
    shoulder_height = float(height[[arms.a, arms.b]].mean()) - ground
    return (leg_height > 0 and float(hands.mean()) - ground < 0.08 * leg_height
            and shoulder_height < UPRIGHT_SHOULDERS * leg_height)
