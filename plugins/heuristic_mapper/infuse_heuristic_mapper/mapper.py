"""The heuristic mapper: any humanoid skeleton -> canonical joint names, with confidences and reasons.

How the decision is made (each part is its own module):

1. :mod:`.body` ranks body plans: every combination of a legs pair and an arms pair among the
   best mirror-image limb pairs, scored together (symmetry, lengths, names, how the pairs sit in
   the tree and in space). A rest pose that is not a standing body is replaced by the caller's pose.
2. :mod:`.humanoid` tests the best plan and its close rivals: two legs and two arms (limbs that
   reach a hand or an arm's length) on a trunk, the legs pointing away from the head; a skeleton
   none of them passes is refused with the best plan's reason (:class:`~infuse.errors.NotHumanoidError`).
3. Every plan that passes is assigned completely: :mod:`.limbs` places hip/knee/ankle and
   clavicle/shoulder/elbow/wrist on each limb's chain (both limbs of a pair as one decision), the
   torso, neck and head come from the path between the two limb pairs, :mod:`.hands` matches the
   fingers to the digits, and of the two ways of giving left and right the one the evidence
   (the body's own axes, the side names) costs least (the reasons say when the geometry
   overrules the names).
4. One cost over each complete assignment decides: the plan's score, the cost of placing every
   limb joint, a missing head or torso, what every mapped joint's name says about its slot, and
   the cost of its sides.
5. Confidence: each entry's own margin, capped by how the sides were decided, by what its joint's
   name says, and by the cost margin to the runner-up assignment where that one differs.
"""
from __future__ import annotations

import numpy as np
from infuse.canonical import ALL_NAMES, CANONICAL_NAMES
from infuse.errors import NotHumanoidError
from infuse.mapping import Mapping, resolve_pose

from .body import LimbPair, legs_down, limb_pairs, rank_plans, upper_anchor
from .hands import assign_fingers
from .humanoid import STANDING_COS, refusal
from .limbs import LimbResult, assign_arms, assign_legs, forearm_twist, relocate, settle_coincident
from .view import SkeletonView, length, lengths

NAME = "heuristic"
_NOT_BODY = ("control", "secondary", "prop", "face")


class _Result:
    """Canonical name -> (joint index, confidence, reason), filled step by step."""

    def __init__(self, view: SkeletonView):
        self.view = view
        self.joint: dict[str, int] = {}
        self.conf: dict[str, float] = {}
        self.reason: dict[str, str] = {}

    def put(self, name: str, joint: int | None, conf: float, reason: str) -> None:
        if joint is None or joint < 0:
            self.joint.pop(name, None)
        else:
            self.joint[name] = int(joint)
        self.conf[name] = min(1.0, max(0.0, float(conf)))
        self.reason[name] = reason


def _conf_from_margin(margin: float, base: float = 0.6) -> float:
    return base + (0.98 - base) * (1.0 - np.exp(-max(margin, 0.0) / 1.2))


class _Frames:
    """The caller's poses as (F, J, 3), computed on first use (``pose`` may be a callable)."""

    def __init__(self, pose, joints: int):
        self._pose = pose
        self._joints = joints
        self._value = None
        self._done = pose is None

    def get(self) -> np.ndarray | None:
        if not self._done:
            self._done = True
            arr = resolve_pose(self._pose)
            if arr is not None:
                arr = np.asarray(arr, dtype=np.float64)
                if arr.ndim == 2:
                    arr = arr[None]
                if arr.ndim == 3 and arr.shape[1:] == (self._joints, 3) and np.all(np.isfinite(arr)):
                    self._value = arr
        return self._value


def _plans_for(view: SkeletonView):
    """(the body plans, best first, every mirror-image pair of limbs)."""
    pairs = limb_pairs(view)
    return rank_plans(view, pairs), pairs


def _standing(view: SkeletonView, plan) -> float:
    """legs_down cosine for the plan in the view's current pose (-1 standing, 0 four-legged)."""
    if plan is None or plan.legs is None:
        return -1.0
    return legs_down(view, plan.legs, upper_anchor(view, plan.legs, plan.arms))


def heuristic_map(skeleton, pose=None, meta=None, fixed=None, file=None, **_options) -> Mapping:
    """Map ``skeleton`` to the canonical names (see the module docstring).

    ``pose``: optional (J, 3) or (F, J, 3) global joint positions in metres (core frame) of
    representative poses; used when the rest pose is not a standing body, and to tell the body's
    front from frames of motion. Hand-set entries (``fixed``) are applied by
    :func:`infuse.mapping.complete` after every mapper.
    """
    view = SkeletonView(skeleton, skeleton.rest_global_positions)
    frames = _Frames(pose, view.n)
    plans, pairs = _plans_for(view)
    cos = _standing(view, plans[0] if plans else None)
    used_pose = "rest pose"
    if (not plans or cos > STANDING_COS) and frames.get() is not None:
        view_pose = SkeletonView(skeleton, frames.get()[0])
        plans_pose, pairs_pose = _plans_for(view_pose)
        cos_pose = _standing(view_pose, plans_pose[0] if plans_pose else None)
        if plans_pose and (not plans or cos_pose < cos):
            view, plans, pairs, cos = view_pose, plans_pose, pairs_pose, cos_pose
            used_pose = "first frame (the rest pose is not a standing body)"
    if not plans:
        result = _Result(view)
        if _map_face_only(view, result):
            return _finish(skeleton, result, 0.3)
    top = plans[0] if plans else None
    why = refusal(view, top, pairs, cos)
    # the best plan and its close rivals that pass the humanoid test, each assigned completely; one
    # cost decides. Without any, the best plan's reason refuses the skeleton.
    rivals = [p for p in plans[1:] if p.legs is not None and p.arms is not None
              and p.score >= top.score - PLAN_WINDOW][:MAX_PLANS - 1]
    candidates = ([top] if why is None else []) + [p for p in rivals if refusal(view, p, pairs, _standing(view, p)) is None]
    if not candidates:
        raise NotHumanoidError(file, why)
    assignments = sorted((_assign(view, p, frames, used_pose) for p in candidates), key=lambda a: a.cost)
    best = assignments[0]
    if len(assignments) > 1:
        _cap_by_rival(best, assignments[1])
    overall = np.mean([best.result.conf.get(n, 0.5) for n in CANONICAL_NAMES])
    return _finish(skeleton, best.result, float(overall))


#: How complete assignments of rival body plans are compared: one cost, the lower the better.
PLAN_WINDOW = 2.0     # rival plans scoring at most this much below the best one are assigned too
MAX_PLANS = 3         # ... at most this many plans in all
PLAN_WEIGHT = 3.0     # cost per unit of a plan's score (symmetry, lengths, names, how the pairs sit)
LIMB_WEIGHT = 0.25    # cost per unit of the limb joints' placement cost (:mod:`.limbs`)
NAME_AGREES = -0.3    # cost per mapped joint whose name names its slot
NAME_CONTRARY = 1.0   # cost per mapped joint whose name names another body part
NO_HEAD = 2.0         # cost of an assignment without a head joint
NO_TORSO = 1.0        # ... without a torso joint between the pelvis and the arms


class _Assignment:
    """One complete assignment of canonical names for one body plan, its cost and the cost's parts
    (``plan``, ``limbs``, ``trunk``, ``names``)."""

    def __init__(self, plan, result: _Result, parts: dict[str, float]):
        self.plan = plan
        self.result = result
        self.parts = parts
        self.cost = sum(parts.values())


def _assign(view: SkeletonView, plan, frames, used_pose: str) -> _Assignment:
    """Assign every canonical name for ``plan``; the cost sums the plan's score (hierarchy and
    geometry of the limb pairs), the cost of placing every limb joint (proportions, bends,
    skipped joints, names) and what the names of all mapped joints say about their slots."""
    result = _Result(view)
    limbs, trunk, sides = _map_body(view, plan, result, frames, used_pose)
    names = 0.0
    for name, j in result.joint.items():
        expected = EXPECTED_ROLES.get(name)
        roles = view.info[j].roles
        if expected is not None and roles:
            names += NAME_AGREES if roles & expected else NAME_CONTRARY
    return _Assignment(plan, result, {"plan": -PLAN_WEIGHT * plan.score, "limbs": LIMB_WEIGHT * limbs,
                                      "trunk": trunk, "names": names, "sides": sides})


def _cap_by_rival(best: _Assignment, rival: _Assignment) -> None:
    """Entries the runner-up assignment gives to other joints are as sure as the cost margin
    between the two: a close rival marks them for checking."""
    margin = rival.cost - best.cost
    cap = 0.5 + 0.48 * (1.0 - np.exp(-margin / 1.5))
    for name in set(best.result.conf) | set(rival.result.conf):
        if best.result.joint.get(name) != rival.result.joint.get(name) and name in best.result.conf:
            if cap < best.result.conf[name]:
                best.result.conf[name] = cap
                best.result.reason[name] += f"; a rival body plan costs only {margin:.2f} more (check it)"


#: The body-part roles a joint's name may carry for each canonical name (by its part after the side).
SLOT_ROLES: dict[str, frozenset[str]] = {
    "base": frozenset({"hips"}), "spine1": frozenset({"spine", "chest", "hips"}),
    "spine2": frozenset({"spine", "chest"}), "spine3": frozenset({"spine", "chest"}), "spine4": frozenset({"neck"}),
    "spine5": frozenset({"neck"}), "skullbase": frozenset({"head"}), "eyeball": frozenset({"eye"}),
    "acromioclavicular": frozenset({"clavicle", "shoulder"}), "sternoclavicular": frozenset({"clavicle", "shoulder"}),
    "shoulder": frozenset({"upperarm", "shoulder"}), "elbow": frozenset({"forearm"}),
    "forearm": frozenset({"forearm"}), "wrist": frozenset({"hand"}), "hip": frozenset({"thigh"}),
    "knee": frozenset({"shin", "legpart"}), "ankle": frozenset({"foot"}), "forefoot": frozenset({"toe"}),
    "toe": frozenset({"toe", "toe_end"}),
    **{f: frozenset({f, "finger"}) for f in ("thumb", "index", "middle", "ring", "pinky")},
}
SETTLED = 0.85  # an entry the tree's structure settles: a chain too short for a segment, a leaf foot, one neck joint
NAME_SILENT_CAP = 0.75   # confidence at most, when the joint's name names no body part
NAME_CONTRARY_CAP = 0.6  # ... when it names another one: an entry to check


def _expected_roles(name: str) -> frozenset[str] | None:
    part = name[2:] if name[:2] in ("l_", "r_") else "eyeball" if name.startswith("eyeball") else name
    return SLOT_ROLES.get(part) or SLOT_ROLES.get(part.rstrip("1234"))  # spine1 / thumb1 -> thumb


EXPECTED_ROLES = {n: _expected_roles(n) for n in ALL_NAMES}


def _name_agreement(result: _Result) -> None:
    """Cap each mapped entry's confidence by what its joint's name says: the geometry alone, or
    against the name, is less sure than both together."""
    for name, j in result.joint.items():
        expected = EXPECTED_ROLES.get(name)
        if expected is None:
            continue
        roles = result.view.info[j].roles
        if not roles:
            result.conf[name] = min(result.conf[name], NAME_SILENT_CAP)
        elif not roles & expected:
            result.conf[name] = min(result.conf[name], NAME_CONTRARY_CAP)
            result.reason[name] += "; its name suggests another body part (check it)"


def _finish(skeleton, result: _Result, overall: float) -> Mapping:
    _name_agreement(result)
    names = skeleton.names
    joints = {n: names[j] for n, j in result.joint.items()}
    conf = dict(result.conf)
    reasons = dict(result.reason)
    for n in ALL_NAMES:
        if n not in conf:
            conf[n] = 0.5
            reasons[n] = reasons.get(n) or "no counterpart found"
    return Mapping.build(skeleton, joints, conf, reasons, mapper=NAME, overall_confidence=overall)


# -- face only ------------------------------------------------------------------------------------------
def _map_face_only(view: SkeletonView, result: _Result) -> bool:
    """A skeleton with no limbs but named eyes (a face rig): map the eyes by their names."""
    eyes = _named_eyes(view, range(view.n))
    if not eyes:
        return False
    for side, j in eyes.items():
        result.put(f"eyeball_{side}", j, 0.6, "named eye (a face rig without a body)")
    return True


def _named_eyes(view: SkeletonView, candidates) -> dict[str, int]:
    found: dict[str, int] = {}
    for j in candidates:
        info = view.info[j]
        if info.has("eye") and not info.flagged("face", "control", "end", "helper") and info.side:
            side = "left" if info.side > 0 else "right"
            if side not in found:
                found[side] = int(j)
    return found


# -- body ------------------------------------------------------------------------------------------------
def _map_body(view: SkeletonView, plan, result: _Result, frames, used_pose: str) -> tuple[float, float, float]:
    """Fill ``result`` for ``plan``; returns the costs of placing the limb joints, the trunk and the
    sides."""
    legs: LimbPair = plan.legs
    arms: LimbPair = plan.arms
    up_guess = None
    anchor = upper_anchor(view, legs, arms)
    if anchor is not None:
        up_guess = view.P[anchor] - view.P[legs.branch]
        up_guess = up_guess / max(length(up_guess), 1e-12)
    leg_res = assign_legs(view, legs.branch, [legs.a, legs.b], up_guess)
    arm_res = assign_arms(view, arms.branch, [arms.a, arms.b])
    body_chain: set[int] = set()
    for r in list(leg_res.values()) + list(arm_res.values()):
        settle_coincident(view, r)
        body_chain.update(r.chain)
    # IK-driven feet and hands hang elsewhere
    for r in leg_res.values():
        _relocate_end(view, r, "ankle", "knee", body_chain)
    for r in arm_res.values():
        _relocate_end(view, r, "wrist", "elbow", body_chain)

    # torso, neck and head
    junction = view.lca(legs.branch, arms.branch)
    up = _up_axis(view, junction, legs, arms)
    hips = [r.slots["hip"] for r in leg_res.values()]
    thigh = max(float(np.mean([length(view.P[r.slots["knee"]] - view.P[r.slots["hip"]]) for r in leg_res.values()]
                              or [0.0])), 1e-9)
    base, base_why = _choose_base(view, junction, arms, hips, thigh, up)
    shoulders = [r.slots["shoulder"] for r in arm_res.values()]
    torso, neck, head, chest_why = _torso_neck_head(view, base, arms, up, shoulders)

    if used_pose != "rest pose":
        base_why += f"; geometry from the {used_pose}"
    result.put("base", base, 0.9, base_why)
    _put_torso(result, torso, chest_why)
    _put_neck(result, neck)
    if head >= 0:
        result.put("skullbase", head, 0.85, "head: the joint where the neck ends and the skull begins")
    else:
        result.put("skullbase", None, 0.5, "no head joint above the neck")

    # sides
    side_of, side_why, side_conf, left, side_cost = _sides(view, base, up, legs, arms, leg_res, arm_res, frames)

    for root, r in leg_res.items():
        s = side_of[root]
        _put_leg(view, result, s, r, side_why, side_conf, up, base)
    for root, r in arm_res.items():
        s = side_of[root]
        _put_arm(view, result, s, r, side_why, side_conf)
    # eyes
    if head >= 0:
        _put_eyes(view, result, head, up, left)
    limbs = sum(r.cost for r in leg_res.values()) + sum(r.cost for r in arm_res.values())
    return limbs, NO_HEAD * (head < 0) + NO_TORSO * (not torso), side_cost


def _relocate_end(view: SkeletonView, r: LimbResult, end: str, middle: str, body_chain: set[int]) -> None:
    """A limb chain that ends early (no joint there, or only an end marker) has its hand or foot
    elsewhere in the tree (IK rigs): take the joint found where the limb ends."""
    j = r.slots[end]
    if j >= 0 and not (view.info[j].flagged("end") and not view.children[j]):
        return
    mid = view.P[r.slots[middle]]
    target = view.P[j] if j >= 0 else r.predicted[end]
    seg = length(target - mid)
    # neither the limb's own trunk nor what hangs from its last joint (digits, claws) is the hand
    # or foot found elsewhere
    exclude = body_chain | set(view.ancestors(r.chain[0])) | set(view.subtree(r.slots[middle]).tolist())
    new = relocate(view, target, exclude, max((0.25 if j >= 0 else 1.5) * seg, 1e-6))
    if new >= 0:
        r.slots[end] = new
        r.notes[end] = "IK-driven: found where the limb ends, outside its chain"


def _only_body_child(view: SkeletonView, parent: int, child: int) -> bool:
    for c in view.children[parent]:
        if c == child:
            continue
        if view.info[c].flagged(*_NOT_BODY, "root") or view.limb_length(parent, c) < 0.15 * view.scale:
            continue
        return False
    return True


def _above_ground(view: SkeletonView, junction: int, top: int, hips: list[int], thigh: float, up: np.ndarray) -> int:
    """The first joint from ``junction`` towards ``top`` that is not far below the hip sockets: rigs
    that hang the thighs from a ground root have their pelvis above it on the way to the chest."""
    sockets = float(view.P[hips].mean(axis=0) @ up)
    if float(view.P[junction] @ up) > sockets - thigh:
        return junction
    for j in view.path_down(junction, top):
        if float(view.P[j] @ up) > sockets - 0.5 * thigh:
            return j
    return junction


def _choose_base(view: SkeletonView, junction: int, arms: LimbPair, hips: list[int], thigh: float,
                 up: np.ndarray) -> tuple[int, str]:
    """The pelvis: the joint where legs and torso meet, or its parent when the legs hang from a spine
    joint well above the hip sockets (3ds Max Biped: Pelvis -> Spine -> thighs), or the first joint
    towards the chest when the legs hang from a ground root."""
    if view.is_descendant(arms.branch, junction):
        junction = _above_ground(view, junction, arms.branch, hips, thigh, up)
    info = view.info[junction]
    p = int(view.parents[junction])
    if p < 0 or not _only_body_child(view, p, junction):
        return junction, "pelvis: parents the spine and both legs"
    parent_info = view.info[p]
    if not info.has("hips") and info.roles & {"spine", "chest"} and parent_info.has("hips"):
        return p, "pelvis above the spine joint that carries the legs"
    if not info.has("hips") and not parent_info.flagged("root"):
        sockets = view.P[hips].mean(axis=0)
        h_junction = float((view.P[junction] - sockets) @ up) / thigh
        h_parent = float((view.P[p] - sockets) @ up) / thigh
        if h_junction > 0.4 and -0.2 < h_parent < h_junction - 0.1:
            return p, "pelvis: the legs hang from a spine joint above it"
    return junction, "pelvis: parents the spine and both legs"


def _up_axis(view: SkeletonView, base: int, legs: LimbPair, arms: LimbPair) -> np.ndarray:
    """(3,) the body's up: from the pelvis to the arms' joint, or from the feet to the pelvis when
    both are one joint."""
    P = view.P
    if length(P[arms.branch] - P[base]) > 1e-3 * view.scale:
        up = P[arms.branch] - P[base]
    else:
        up = P[base] - P[[view.far[legs.a], view.far[legs.b]]].mean(axis=0)
    return up / max(length(up), 1e-12)


def _head_branch(view: SkeletonView, top: int, arms: LimbPair, up: np.ndarray) -> list[int]:
    """The chain from ``top`` towards the head (excluding the arms), following neck/head joints."""
    excluded = {arms.a, arms.b}
    chain: list[int] = []
    cur = top
    for _ in range(12):
        kids = [c for c in view.children[cur] if c not in excluded]
        if not kids:
            break
        def score(c: int) -> float:
            info = view.info[c]
            # which way the joint leads: its own bone, or the next ones when it sits at its parent's
            # place (not its farthest descendant: hair may hang from the head down the back)
            far = view.P[view.main_chain(c, 3)[-1] if view.bone[c] < 1e-3 * view.scale else c] - view.P[cur]
            norm = length(far)
            upness = float(np.dot(far, up) / norm) if norm > 1e-9 else 0.0
            s = upness + 0.5 * view.limb_length(cur, c) / view.scale
            s += 1.0 * bool(info.roles & {"neck", "head", "spine", "chest"})
            s -= 2.0 * info.flagged(*_NOT_BODY) + 1.0 * info.flagged("end")
            s -= 1.0 * bool(info.roles & {"eye", "clavicle", "shoulder", "upperarm", "thigh"})
            return s
        nxt = max(kids, key=score)
        if score(nxt) < -1.0:
            break
        chain.append(nxt)
        cur = nxt
        if sum(not view.info[c].flagged("end") for c in view.children[cur]) >= 2:
            break  # the skull: eyes, jaw, face or hair hang from it
    return chain


def _torso_neck_head(view: SkeletonView, base: int, arms: LimbPair, up: np.ndarray, shoulders: list[int]):
    """(torso joints bottom-up, neck joints bottom-up, head joint or -1, reason for the chest)."""
    P = view.P
    if view.is_descendant(arms.branch, base):
        path = view.path_down(base, arms.branch)[1:]
        top = arms.branch
    else:
        path = []
        top = base
    torso = [j for j in path if not view.info[j].flagged("control", "secondary", "prop", "helper")]
    neck_from_top = False
    chest_why = "chest: the joint the arms hang from"
    above = _head_branch(view, top, arms, up)
    if torso and shoulders:
        # the arms may hang from the neck (3ds Max Biped): a joint at shoulder height, named neck or
        # with the head right above it, is the neck
        s_mean = P[shoulders].mean(axis=0)
        t_len = max(float(np.dot(s_mean - P[base], up)), 1e-9)
        height = float(np.dot(P[top] - s_mean, up)) / t_len
        to_next = length(P[above[0]] - P[top]) / t_len if above else 1.0
        info = view.info[top]
        named_neck = info.has("neck") and not info.roles & {"chest", "spine"}
        named_torso = bool(info.roles & {"chest", "spine", "hips"})
        if named_neck or (not named_torso and height > 0.04 and to_next < 0.35 and len(torso) > 1):
            neck_from_top = True
            torso = torso[:-1]
            chest_why = "chest: the last torso joint below the neck that carries the arms"
    chain = ([top] if neck_from_top else []) + above
    head = _pick_head(view, chain, base, up, top, neck_from_top)
    if head < 0:
        return torso, chain if neck_from_top else [], -1, chest_why
    neck = [j for j in chain[:chain.index(head)] if not view.info[j].flagged("control") and not _helper_below_neck(
        view, j, base, shoulders, up)]
    return torso, neck, head, chest_why


def _helper_below_neck(view: SkeletonView, j: int, base: int, shoulders: list[int], up: np.ndarray) -> bool:
    """A zero-length joint at its parent's place, well below the shoulders: a helper at the torso's
    centre, not a neck joint (a zero-length neck joint at the chest's place is one)."""
    if view.bone[j] > 1e-3 * view.scale or not shoulders or view.info[j].has("neck"):
        return False
    top = float(view.P[shoulders].mean(axis=0) @ up)
    return float(view.P[j] @ up) < top - 0.5 * max(top - float(view.P[base] @ up), 1e-9)


def _pick_head(view: SkeletonView, chain: list[int], base: int, up: np.ndarray, top: int, neck_from_top: bool) -> int:
    """The head: a joint named so, else the last joint of the chain above the chest, unless that one
    is only the end of the skull (a leaf without end site whose bone is long next to the neck's)."""
    candidates = chain[1:] if neck_from_top else chain
    if not candidates:
        return -1
    named = [j for j in candidates if view.info[j].has("head") and not view.info[j].flagged("end", "face", "control")]
    if named:
        return named[0]
    P = view.P
    torso_len = max(float(np.dot(P[top] - P[base], up)), 1e-3 * view.scale)
    last = candidates[-1]
    if len(candidates) >= 2 and not view.children[last] and not view.has_end_site[last]:
        prev = view.bone[candidates[-2]]
        if view.info[last].flagged("end") or (view.bone[last] > 0.15 * torso_len and view.bone[last] > 1.5 * prev):
            last = candidates[-2]
    return last


def _put_torso(result: _Result, torso: list[int], chest_why: str) -> None:
    if not torso:
        for n in ("spine1", "spine2", "spine3"):
            result.put(n, None, 0.6, "no torso joint between the pelvis and the neck")
        return
    result.put("spine3", torso[-1], 0.85, chest_why)
    if len(torso) >= 2:
        result.put("spine1", torso[0], 0.85, "lowest torso joint above the pelvis")
    else:
        result.put("spine1", None, 0.7, "a single torso joint is the chest")
    if len(torso) >= 3:
        result.put("spine2", torso[1], 0.85, "second torso joint from the pelvis")
    else:
        result.put("spine2", None, SETTLED, f"{len(torso)} torso joint(s): no middle one")


def _put_neck(result: _Result, neck: list[int]) -> None:
    if not neck:
        result.put("spine4", None, 0.75, "no neck joint between the chest and the head")
        result.put("spine5", None, SETTLED, "no neck joint")
        return
    result.put("spine4", neck[0], 0.85, "lowest neck joint")
    if len(neck) >= 2:
        result.put("spine5", neck[-1], 0.8, "neck joint just below the head")
    else:
        result.put("spine5", None, SETTLED, "a single neck joint is spine4")


#: The side evidence in the assignment's cost: the sides given cost these weights times the votes
#: against them (each -1..1). The geometry outweighs the names from a vote of 0.25 on (names written
#: from the viewer's side are overruled), the names decide when the body does not show its front.
GEO_SIDE = 4.0
NAME_SIDE = 1.0


def _sides(view, base, up, legs, arms, leg_res, arm_res, frames):
    """(root of each limb -> "l"/"r", the reason, the confidence, the body's left (3,), the side
    cost): the sides that cost least given the geometry's and the names' votes."""
    P = view.P
    pairs = [legs, arms]
    lateral = np.zeros(3)
    for p in pairs:
        res = leg_res if p is legs else arm_res
        key = "hip" if p is legs else "shoulder"
        d = P[res[p.a].slots[key]] - P[res[p.b].slots[key]]
        if np.dot(d, lateral) < 0:
            d = -d
        lateral = lateral + d
    lateral = lateral - np.dot(lateral, up) * up
    lateral /= max(length(lateral), 1e-12)
    # reference: lateral points from the first pair's b member to its a member
    ref = pairs[0]
    ref_res = leg_res if ref is legs else arm_res
    ref_key = "hip" if ref is legs else "shoulder"
    if np.dot(P[ref_res[ref.a].slots[ref_key]] - P[ref_res[ref.b].slots[ref_key]], lateral) < 0:
        lateral = -lateral
    forward = np.cross(lateral, up)  # the body's front if the "a" members are on its left
    top = arms.branch
    geo, geo_why = _front_votes(view, forward, up, legs, leg_res, frames if top != base else None, base, top)
    if abs(geo) < 0.3:  # the feet do not show the front: the thumbs do (they point forward in any rest)
        thumbs = _thumb_votes(view, forward, arm_res)
        if abs(geo + thumbs) > abs(geo):
            geo, geo_why = float(np.clip(geo + thumbs, -1, 1)), "left = up x forward, forward from the thumbs"
    names = _name_votes(view, pairs, leg_res, arm_res, legs)
    # the two ways to give the sides, each costed by the evidence against it; the cheaper one is part
    # of the assignment, and its cost enters the assignment's cost
    cost = {a_left: -(GEO_SIDE * geo + NAME_SIDE * names) * (1.0 if a_left else -1.0) for a_left in (True, False)}
    a_left = cost[True] <= cost[False]
    sign = 1.0 if a_left else -1.0
    if geo * sign >= 0.3:
        why, conf = geo_why, 0.75 + 0.2 * min(1.0, abs(geo))
        if names * sign > 0:
            conf = min(0.99, conf + 0.05)
        elif names:
            why += "; the side names say the opposite (mirrored names): the geometry decides"
            conf = min(conf, 0.85)
    elif names * sign > 0:
        why, conf = "left/right from the names (the feet do not show the front)", 0.7
    elif geo * sign > 0.05:
        why, conf = geo_why + " (weak)", 0.55
    else:
        why, conf = "left/right undecidable (no front, no side names): a guess", 0.3
    left = lateral if a_left else -lateral
    side_of = {}
    for p in pairs:
        res = leg_res if p is legs else arm_res
        key = "hip" if p is legs else "shoulder"
        for root in (p.a, p.b):
            side_of[root] = "l" if np.dot(P[res[root].slots[key]] - P[base], left) > 0 else "r"
        if side_of[p.a] == side_of[p.b]:  # both on one side of the pelvis: order them by the axis
            da = np.dot(P[res[p.a].slots[key]], left)
            db = np.dot(P[res[p.b].slots[key]], left)
            side_of[p.a], side_of[p.b] = ("l", "r") if da >= db else ("r", "l")
    return side_of, why, conf, left, cost[a_left]


def _thumb_votes(view: SkeletonView, forward: np.ndarray, arm_res: dict) -> float:
    """+1 when the thumbs lie along ``forward`` from the wrists, -1 against, 0 when no thumb is
    found: palms down (T-pose, A-pose) or facing the thighs, the thumb side of a hand is its front."""
    votes = []
    for r in arm_res.values():
        wrist = r.slots["wrist"]
        if wrist < 0:
            continue
        fingers, _ = assign_fingers(view, list(view.children[wrist]), view.P[wrist])
        thumb = fingers.get("thumb")
        if thumb:
            d = view.P[thumb[-1]] - view.P[wrist]
            votes.append(float(d @ forward) / max(length(d), 1e-12))
    return float(np.mean(votes)) if votes else 0.0


def _front_votes(view, forward, up, legs, leg_res, frames, base, top) -> tuple[float, str]:
    """+1 when the feet point (and the knees bend) along ``forward``, -1 against, ~0 when they do not
    tell. ``forward`` is the front if the pair's "a" members are on the left. With frames of motion
    each frame votes in its own body axes."""
    ra, rb = leg_res[legs.a], leg_res[legs.b]
    feet = []
    for r in (ra, rb):
        ankle = r.slots["ankle"]
        if ankle < 0:
            continue
        tip = view.main_chain(ankle, 3)[-1]
        if tip != ankle:
            feet.append((ankle, tip))
    knees = [(r.slots["hip"], r.slots["knee"], r.slots["ankle"]) for r in (ra, rb) if r.slots["ankle"] >= 0]
    toe_votes, knee_votes = [], []
    for F in (view.P[None], "frames"):
        if isinstance(F, str):
            # the pose at hand is clear enough: no need to compute frames of motion
            if frames is None or (toe_votes and abs(np.mean(toe_votes)) >= 0.5):
                break
            F = frames.get()
            if F is None:
                break
            u = F[:, top] - F[:, base]
            lat = F[:, ra.slots["hip"]] - F[:, rb.slots["hip"]]
            fwd = np.cross(lat, u)
            fwd /= np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-12)
        else:
            fwd = forward[None]
        for ankle, tip in feet:
            v = F[:, tip] - F[:, ankle]
            n = lengths(v)
            ok = n > 1e-9
            toe_votes.extend((np.einsum("ij,ij->i", v[ok], fwd[ok]) / n[ok]).tolist())
        for h, k, a in knees:
            mid = 0.5 * (F[:, h] + F[:, a])
            off = np.einsum("ij,ij->i", F[:, k] - mid, fwd)
            thigh = lengths(F[:, k] - F[:, h])
            knee_votes.extend(np.clip(off / np.maximum(thigh, 1e-9) * 5.0, -1, 1).tolist())
    toe = float(np.mean(toe_votes)) if toe_votes else 0.0
    knee = float(np.mean(knee_votes)) if knee_votes else 0.0
    if abs(toe) >= 0.3 or not knee_votes:
        return toe, "left = up x forward, forward from the toes"
    return float(np.clip(toe + 0.5 * knee, -1, 1)), "left = up x forward, forward from the toes and knees"


def _name_votes(view, pairs, leg_res, arm_res, legs) -> float:
    """-1..1: the share of the side names on the limbs' first joints that put the "a" members on the
    left, less the share that put them on the right (0 when no name tells a side)."""
    total = count = 0
    for p in pairs:
        res = leg_res if p is legs else arm_res
        for root, sign in ((p.a, 1), (p.b, -1)):
            for j in res[root].chain[:4]:
                side = view.info[j].side
                total += sign * side
                count += side != 0
    return total / count if count else 0.0


def _put_leg(view, result, s, r: LimbResult, side_why, side_conf, up, base) -> None:
    m = r.margins
    result.put(f"{s}_hip", r.slots["hip"], min(side_conf, _conf_from_margin(m.get("hip", 0))),
               f"thigh: first long bone of the leg; {side_why}")
    result.put(f"{s}_knee", r.slots["knee"], min(side_conf, _conf_from_margin(m.get("knee", 0))),
               "shin: the leg bone after the knee")
    ankle = r.slots["ankle"]
    note = r.notes.get("ankle", "")
    result.put(f"{s}_ankle", ankle, min(side_conf, _conf_from_margin(m.get("ankle", 0))),
               "foot: where the shin ends" + (f" ({note})" if note else ""))
    if ankle < 0:
        result.put(f"{s}_forefoot", None, 0.5, "no foot joint")
        result.put(f"{s}_toe", None, 0.5, "no foot joint")
        return
    toes = [c for c in view.children[ankle]
            if not view.info[c].flagged("control", "prop", "heel", "secondary", "helper")]
    forefoot = -1
    if toes:
        if len(toes) >= 3:  # one chain per toe: the big toe is the one nearest the body's middle plane
            forefoot = _big_toe(view, toes, base, up)
        else:  # the longer; of two alike, the one named a toe rather than a digit of another name
            step = 0.01 * view.scale
            forefoot = max(toes, key=lambda c: (round(view.limb_length(ankle, c) / step), view.info[c].has("toe"),
                                                not view.info[c].roles & {"pinky", "ring", "middle", "index"}))
    if forefoot >= 0 and view.info[forefoot].flagged("end") and not view.children[forefoot]:
        result.put(f"{s}_forefoot", None, SETTLED, "the only joint past the ankle is the toe tip")
        result.put(f"{s}_toe", forefoot, SETTLED, "toe end: the tip of the foot")
        return
    if forefoot >= 0:
        result.put(f"{s}_forefoot", forefoot, 0.8, "ball of the foot: the joint after the ankle")
        nxt = [c for c in view.children[forefoot] if not view.info[c].flagged("control", "prop")]
        if nxt:
            toe = max(nxt, key=lambda c: view.limb_length(forefoot, c))
            result.put(f"{s}_toe", toe, 0.8, "toe end: the joint after the ball of the foot")
        else:
            result.put(f"{s}_toe", None, SETTLED, "the ball of the foot is a leaf")
    else:
        result.put(f"{s}_forefoot", None, SETTLED, "the foot joint is a leaf")
        result.put(f"{s}_toe", None, SETTLED, "the foot joint is a leaf")


def _big_toe(view, toes, base, up) -> int:
    """Of several toe chains, the one nearest the body's middle plane (the big toe)."""
    P = view.P
    ref = P[base]
    def lateral_distance(c):
        v = P[c] - ref
        v = v - np.dot(v, up) * up
        return length(v)
    # the big toe is the most medial one; the pelvis lies on the middle plane
    return min(toes, key=lateral_distance)


def _put_arm(view, result, s, r: LimbResult, side_why, side_conf) -> None:
    m = r.margins
    clav = r.slots["clavicle"]
    if clav >= 0:
        result.put(f"{s}_acromioclavicular", clav, min(side_conf, _conf_from_margin(m.get("clavicle", 0))),
                   f"clavicle: short bone from the chest to the shoulder; {side_why}")
        i = r.chain.index(clav) if clav in r.chain else 0
        if i > 0 and not view.info[r.chain[i - 1]].flagged("helper") and view.bone[clav] > 1e-3 * view.scale:
            result.put(f"{s}_sternoclavicular", r.chain[i - 1], 0.6,
                       "sternal end of the clavicle: the joint before the acromioclavicular one")
    else:
        result.put(f"{s}_acromioclavicular", None, min(NAME_SILENT_CAP, _conf_from_margin(m.get("clavicle", 0))),
                   "no clavicle: the arm starts at the shoulder")
    result.put(f"{s}_shoulder", r.slots["shoulder"], min(side_conf, _conf_from_margin(m.get("shoulder", 0))),
               f"upper arm; {side_why}")
    result.put(f"{s}_elbow", r.slots["elbow"], min(side_conf, _conf_from_margin(m.get("elbow", 0))),
               "forearm: the arm bone after the elbow")
    wrist = r.slots["wrist"]
    hand_roots: list[int] = []
    if wrist >= 0:
        siblings = _coincident_siblings(view, wrist)
        if siblings:
            hand_roots = [wrist] + siblings
            result.put(f"{s}_wrist", None, 0.6, "no single hand joint: palm bones start at the wrist")
            wrist_pos = view.P[wrist]
        else:
            note = r.notes.get("wrist", "")
            result.put(f"{s}_wrist", wrist, min(side_conf, _conf_from_margin(m.get("wrist", 0))),
                       "hand: where the forearm ends" + (f" ({note})" if note else ""))
            hand_roots = list(view.children[wrist])
            wrist_pos = view.P[wrist]
    else:
        result.put(f"{s}_wrist", None, 0.5, "no hand joint at the end of the forearm")
        wrist_pos = None
    twist = forearm_twist(view, r) if wrist >= 0 else -1
    if twist >= 0 and twist not in hand_roots:
        result.put(f"{s}_forearm", twist, 0.75, "forearm twist: first joint after the elbow")
    else:
        result.put(f"{s}_forearm", None, 0.75, "no twist joint between elbow and hand")
    if wrist_pos is None or not hand_roots:
        for finger in ("thumb", "index", "middle", "ring", "pinky"):
            for k in range(4):
                result.put(f"{s}_{finger}{k + 1}", None, SETTLED, "no hand joint with digits: no fingers")
        return
    fingers, why = assign_fingers(view, hand_roots, wrist_pos)
    order = {"index": "next to the thumb", "middle": "second from the thumb", "ring": "third from the thumb",
             "pinky": "fourth from the thumb"}
    # a thumb told by its name or number orders the fingers surely; one told by its angle alone may not be
    sure = 0.9 if why.startswith(("named", "lowest-numbered", "fingers named", "a thumb and")) else 0.7
    unmapped = (min(SETTLED, sure) if fingers else SETTLED if why.startswith("a thumb and a single finger")
                else 0.4 if why.startswith("no thumb can be told") else 0.6)
    for finger in ("thumb", "index", "middle", "ring", "pinky"):
        chain = fingers.get(finger, [])
        for k in range(4):
            name = f"{s}_{finger}{k + 1}"
            if k < len(chain):
                where = why if finger == "thumb" else f"the finger {order[finger]} across the palm"
                result.put(name, chain[k], sure, f"{finger} segment {k + 1}: {where}")
            else:
                result.put(name, None, unmapped, why if not fingers else f"the {finger} has {len(chain)} joint(s)")


def _coincident_siblings(view: SkeletonView, j: int) -> list[int]:
    """Siblings of ``j`` at the same place that also lead somewhere (palm bones side by side)."""
    p = int(view.parents[j])
    if p < 0:
        return []
    tol = 0.01 * view.scale
    return [c for c in view.children[p] if c != j and view.size[c] >= 2
            and length(view.P[c] - view.P[j]) < max(tol, 0.2 * length(view.P[j] - view.P[p]))
            and not view.info[c].flagged(*_NOT_BODY)]


def _put_eyes(view, result, head, up, left) -> None:
    """Eyes: named ones below the head; else, in a head with few joints, a mirror-image pair of
    small joints in front of and above the head joint."""
    eyes = _named_eyes(view, view.subtree(head))
    why = "named eye below the head"
    if len(eyes) == 2 and float((view.P[eyes["left"]] - view.P[eyes["right"]]) @ left) < 0:
        eyes = {"left": eyes["right"], "right": eyes["left"]}
        why = "named eye below the head; its side name says the opposite: the geometry decides"
    if not eyes:
        eyes = _eye_pair(view, head, up, left)
        why = "mirror-image pair in front of the head (eyes)"
    for side in ("left", "right"):
        if side in eyes:
            result.put(f"eyeball_{side}", eyes[side], 0.8 if why.startswith("named") else 0.55, why)
        else:
            result.put(f"eyeball_{side}", None, 0.6, "no eye joint below the head")
    for j in view.subtree(head):  # eyelid joints, an extra: by name only
        info = view.info[int(j)]
        if "eyelid" in info.tokens or ("lid" in info.tokens and "eye" in info.roles):
            level = "upper" if "upper" in info.tokens else "lower" if "lower" in info.tokens else None
            if level and info.side:
                name = f"{level}_eyelid_{'left' if info.side > 0 else 'right'}"
                if name not in result.joint:
                    result.put(name, int(j), 0.7, "named eyelid below the head")


def _eye_pair(view, head, up, left) -> dict[str, int]:
    P = view.P
    inside = [int(j) for j in view.subtree(head) if j != head and view.size[j] <= 2
              and not view.info[j].flagged("face", "end", "secondary", "control", "prop")
              and not (len(view.children[j]) == 1 and view.bone[view.children[j][0]] < 1e-4 * view.scale)]
    if not inside or len(inside) > 8:  # a face rig: too many look-alike pairs to tell the eyes by shape
        return {}
    forward = np.cross(left, up)
    neck_len = max(length(P[head] - P[int(view.parents[head])]), 1e-3 * view.scale)
    best, best_score = None, np.inf
    for i, a in enumerate(inside):
        for b in inside[i + 1:]:
            d = P[a] - P[b]
            sep = length(d)
            if sep < 1e-9:
                continue
            across = abs(float(d @ left)) / sep
            mid = 0.5 * (P[a] + P[b]) - P[head]
            if across < 0.85 or abs(float(mid @ left)) > 0.2 * sep:
                continue
            if float(mid @ forward) <= 0 or float(mid @ up) <= 0:
                continue
            score = (1 - across) + abs(float(mid @ left)) / sep + 0.1 * sep / neck_len
            if score < best_score:
                best, best_score = (a, b), score
    if best is None:
        return {}
    a, b = best
    return {"left": a, "right": b} if float((P[a] - P[b]) @ left) > 0 else {"left": b, "right": a}
