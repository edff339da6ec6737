"""The humanoid test on joints found by their names: two legs and two arms on a trunk, the legs
pointing away from the head in the body's own frame (a rest pose that is not a standing body is
replaced by the first frame of motion). Names alone accept a flying head whose arms carry
humanoid names; this refuses it, with the reason.

Where the names give no legs or no arms (a convention the dictionaries do not know for that part),
the hierarchy and the rest positions are asked instead (:mod:`.geometry`): a pair of mirror-image
jointed chains that the named joints do not use, hanging below the arms (legs) or from above the
hips (arms), stands in for the missing pair. Only when there is none is the body refused.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
from infuse.mapping import resolve_pose

from .geometry import Limbs, Tree, limb_pairs

#: cos(legs direction, spine direction) above which a body is not standing (about 140 degrees)
STANDING_COS = -0.75
#: each limb needs its first joint and one of the next two on both sides
LIMBS = {"legs": ("hip", ("knee", "ankle")), "arms": ("shoulder", ("elbow", "wrist"))}
#: joints above the hips that stand for "up", the highest first
UPPER = ("skullbase", "spine5", "spine4", "spine3", "spine2", "spine1")
#: canonical parts (after the side) of each limb
LIMB_PARTS = {"legs": frozenset({"hip", "knee", "ankle", "forefoot", "toe"}),
              "arms": frozenset({"acromioclavicular", "sternoclavicular", "shoulder", "elbow", "forearm", "wrist",
                                 "thumb", "index", "middle", "ring", "pinky"})}
#: legs the geometry finds are at least this share of the arms' length (a cartoon frog's 0.5)
MIN_LEGS_OVER_ARMS = 0.3
#: arms reach a hand or at least this share of the body below the shoulders (legs and trunk) past their
#: first joint (a person's arms about 0.35, a stubby robot arm 0.17, a shoulder girdle left without
#: arms 0.05-0.1)
MIN_ARM_REACH_OVER_BODY = 0.12
#: the arms hang from at least this share of the leg length above the hips
MIN_ARMS_ABOVE_HIPS = 0.25
#: words that say a chain is no limb: controls, cloth, hair and breasts (also in Japanese written in Latin
#: letters), face parts, landmarks and sensors
NOT_LIMB_WORDS = frozenset({
    "ctrl", "control", "ik", "fk", "pole", "target", "helper", "mch", "org",
    "skirt", "hair", "sec", "cloth", "cape", "coat", "tail", "ribbon", "wing", "breast", "bust", "sleeve", "mune", "suso",
    "ear", "jaw", "tongue", "lip", "oris", "orbicularis", "special", "eye", "brow", "cheek", "nose", "teeth",
    "acromion", "landmark", "marker", "imu", "sensor", "com",
})


@dataclass
class BodyCheck:
    """The verdict: ``why`` the body is refused (``None``: accepted), the limb pairs the geometry
    found where the names gave none (``"legs"`` / ``"arms"`` -> :class:`~.geometry.Limbs`), and for
    an accepted body the pose it stands in (J, 3) and its up (3,)."""

    why: str | None
    from_geometry: dict[str, Limbs] = field(default_factory=dict)
    positions: np.ndarray | None = None
    up: np.ndarray | None = None


def check_body(skeleton, joints: dict[str, str], pose=None) -> BodyCheck:
    """The humanoid test of the canonical -> joint name map ``joints`` of ``skeleton``. ``pose``:
    optional (J, 3) or (F, J, 3) global positions (or a callable returning them)."""
    index = skeleton.index
    rest = skeleton.rest_global_positions
    named = {kind: _named_limb(joints, index, first, nexts) for kind, (first, nexts) in LIMBS.items()}
    found: dict[str, Limbs] = {}
    missing = [kind for kind, limb in named.items() if limb is None]
    if missing:
        found = _from_geometry(skeleton, rest, joints, named, missing)
        for kind in missing:
            if kind not in found:
                first, nexts = LIMBS[kind]
                count = sum(f"{s}_{first}" in joints and any(f"{s}_{n}" in joints for n in nexts) for s in "lr")
                return BodyCheck(
                    f"its names give it {count} {kind[:-1] if count == 1 else kind} ({first} and "
                    f"{' or '.join(nexts)} joints on both sides wanted) and its hierarchy shows no other pair of "
                    f"mirror-image limbs to be its {kind}: a humanoid has two legs and two arms on a trunk")
    legs = named["legs"] or _ends(found["legs"])
    arms = named["arms"] or _ends(found["arms"])
    upper = [index[joints[n]] for n in UPPER if n in joints][:1] or list(arms[0])
    standing = rest
    cos = _standing_cos(rest, legs, upper)
    if cos > STANDING_COS:
        frames = resolve_pose(pose)
        if frames is not None:
            frames = np.asarray(frames, dtype=np.float64)
            first_frame = frames[0] if frames.ndim == 3 else frames
            if first_frame.shape == (skeleton.num_joints, 3) and np.all(np.isfinite(first_frame)):
                cos_frame = _standing_cos(first_frame, legs, upper)
                if cos_frame < cos:
                    cos, standing = cos_frame, first_frame
    if cos > STANDING_COS:
        angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        return BodyCheck(f"its legs do not point away from its head (they are {angle:.0f} degrees from the "
                         "spine's direction instead of about 180): a four-legged or lying body", found)
    up = standing[upper].mean(axis=0) - standing[legs[0]].mean(axis=0)
    return BodyCheck(None, found, standing, up / max(float(np.linalg.norm(up)), 1e-12))


def refusal(skeleton, joints: dict[str, str], pose=None) -> str | None:
    """Why ``joints`` of ``skeleton`` is not a humanoid body, or ``None`` (see :func:`check_body`)."""
    return check_body(skeleton, joints, pose).why


def _named_limb(joints: dict, index: dict, first: str, nexts: tuple[str, ...]) -> tuple[list[int], list[int]] | None:
    """([first joint per side], [last named joint per side]) of a limb named on both sides, else None."""
    tops, ends = [], []
    for s in "lr":
        present = [n for n in nexts if f"{s}_{n}" in joints]
        if f"{s}_{first}" not in joints or not present:
            return None
        tops.append(index[joints[f"{s}_{first}"]])
        ends.append(index[joints[f"{s}_{present[-1]}"]])
    return tops, ends


def _ends(limbs: Limbs) -> tuple[list[int], list[int]]:
    return [limbs.a[0], limbs.b[0]], [limbs.a[-1], limbs.b[-1]]


def _from_geometry(skeleton, positions: np.ndarray, joints: dict, named: dict, missing: list[str]) -> dict[str, Limbs]:
    """The limb pairs standing in for the ``missing`` kinds (see :func:`_limbs_ok`): legs pointing away
    from the arms' joint, arms hanging from a joint well above the hips, outside the legs and the head."""
    tree = Tree(skeleton, positions)
    # a chain may hold joints named as parts of a missing limb (a named elbow beside an unknown upper arm
    # name), never joints named as something else
    own = frozenset(part for kind in missing for part in LIMB_PARTS[kind])
    used = {skeleton.index[j] for n, j in joints.items() if not (n[:2] in ("l_", "r_") and limb_part(n) in own)}
    outside = [j for limb in named.values() if limb for j in limb[0]]
    if "skullbase" in joints:
        outside.append(skeleton.index[joints["skullbase"]])
    pairs = [p for p in limb_pairs(tree) if not used & set(p.a + p.b)
             and not any(tree.inside(p.branch, t) for t in outside) and not _named_otherwise(skeleton.names, p)]
    P = positions
    if missing == ["legs"]:
        tops, ends = named["arms"]
        arm_tops, arm_ends = P[tops].mean(axis=0), P[ends].mean(axis=0)
        for legs in pairs:
            if _limbs_ok(tree, P, legs, (tops, [legs.branch]), arm_tops, arm_ends):
                return {"legs": legs}
        return {}
    if missing == ["arms"]:
        tops, ends = named["legs"]
        for arms in pairs:
            if _limbs_ok(tree, P, (tops, ends), arms, P[arms.branch], P[arms.a[-1]]):
                return {"arms": arms}
        return {}
    for legs in pairs:  # neither: the longest legs with a pair of arms above them
        for arms in pairs:
            if arms is legs or set(arms.a + arms.b) & set(legs.a + legs.b):
                continue
            if _limbs_ok(tree, P, legs, arms, P[arms.branch], P[arms.a[-1]]):
                return {"legs": legs, "arms": arms}
    return {}


def _limbs_ok(tree: Tree, P: np.ndarray, legs, arms, arm_top: np.ndarray, arm_end: np.ndarray) -> bool:
    """Legs and arms (each a :class:`~.geometry.Limbs` or ([first joints], [last joints]) of named
    limbs) make a body: the legs point away from the arms' top, the arms hang from well above the
    hips, outside the legs, and reach a hand or at least :data:`MIN_ARM_REACH_OVER_BODY` of the legs'
    and trunk's length past their first joint; the legs have three joints at least and are not much shorter
    than the arms."""
    leg_tops, leg_ends = _ends(legs) if isinstance(legs, Limbs) else legs
    hips = P[leg_tops].mean(axis=0)
    down = P[leg_ends].mean(axis=0) - hips
    leg_length = float(np.linalg.norm(down))
    if leg_length < 1e-9 or _cos(arm_top - hips, down) > STANDING_COS:
        return False
    if float((arm_top - hips) @ -down) < MIN_ARMS_ABOVE_HIPS * leg_length ** 2:
        return False
    if isinstance(legs, Limbs) and min(len(legs.a), len(legs.b)) < 3:
        return False  # a leg has a thigh, a shin and a foot or its end
    if isinstance(arms, Limbs):
        if any(tree.inside(arms.branch, t) for t in leg_tops):
            return False
        # a hand: three jointed digits past the arm's first joint (not a shoulder's landmark leaves)
        hands = all(any(sum(tree.next[c] >= 0 for c in tree.children[j]) >= 3 for j in chain[1:])
                    for chain in (arms.a, arms.b))
        reach = min(tree.reach[arms.a[0]], tree.reach[arms.b[0]])
        if not hands and reach < MIN_ARM_REACH_OVER_BODY * (leg_length + float(np.linalg.norm(arm_top - hips))):
            return False
    return leg_length >= MIN_LEGS_OVER_ARMS * float(np.linalg.norm(arm_end - arm_top))


_WORD = re.compile(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])")


def _named_otherwise(names, limbs: Limbs) -> bool:
    """The first joint of either chain, or half its joints, carries a word of :data:`NOT_LIMB_WORDS`."""
    for chain in (limbs.a, limbs.b):
        hits = [bool(NOT_LIMB_WORDS & {w.lower() for w in _WORD.findall(names[j])}) for j in chain]
        if hits[0] or 2 * sum(hits) >= len(hits):
            return True
    return False


def limb_part(canonical: str) -> str:
    """``l_index2`` -> ``index``, ``r_knee`` -> ``knee``."""
    return canonical[2:].rstrip("1234")


def _cos(u: np.ndarray, v: np.ndarray) -> float:
    norms = float(np.linalg.norm(u) * np.linalg.norm(v))
    return float(u @ v) / norms if norms > 1e-12 else 1.0


def _standing_cos(positions: np.ndarray, legs: tuple[list[int], list[int]], upper: list[int]) -> float:
    """Cosine between the legs' direction (their first joints to their last known joints) and up
    (the legs' first joints to ``upper``) for global positions (J, 3)."""
    hips = positions[legs[0]].mean(axis=0)
    return _cos(positions[legs[1]].mean(axis=0) - hips, positions[upper].mean(axis=0) - hips)
