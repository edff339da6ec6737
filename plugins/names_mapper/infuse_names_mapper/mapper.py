"""The ``names`` mapper: canonical joint names from dictionaries of well-known rig conventions.

Each convention (:mod:`.conventions`) is tried against the skeleton's normalized joint names and
the one that names the most canonical joints wins; its torso and neck joints are then numbered by
the labelling rule (chest = spine3, one neck joint = spine4...) using their order in the hierarchy.
A VRM file's own humanoid map (``Asset.humanoid``, given as ``humanoid=``) is used first when present.
The joints found must make two legs and two arms on a trunk, the legs pointing away from the head
(:mod:`.body_check`; where the names give no legs or no arms, the hierarchy and rest positions
are asked for them); otherwise the skeleton is refused with the reason. Side names that say the
opposite of the body's own left (:mod:`.sides`) are swapped.
"""
from __future__ import annotations

import re

from infuse.canonical import ALL_NAMES
from infuse.errors import NotHumanoidError
from infuse.mapping import Mapping

from .body_check import LIMB_PARTS, limb_part, check_body
from .conventions import CONVENTIONS, VRM, VRM0_THUMB
from .sides import MIRRORED_VOTE, mirrored_vote, swapped

NAME = "names"
_SIDES = {
    "l": {"{s}": "l", "{Side}": "Left", "{side}": "left", "{L}": "L", "{l}": "l", "{Lf}": "Lf"},
    "r": {"{s}": "r", "{Side}": "Right", "{side}": "right", "{L}": "R", "{l}": "r", "{Lf}": "Rt"},
}
MIN_NAMES = 6  # fewer canonical joints than this named by any convention: not a rig we know


def normalize(name: str) -> str:
    """Lower case, namespace and separators removed, ``Bip001``/``Bip01`` folded, ``DEF-`` dropped."""
    for sep in (":", "|"):
        if sep in name:
            name = name.rsplit(sep, 1)[1] or name
    low = name.lower()
    if low.startswith(("def-", "def_")):
        low = low[4:]
    low = re.sub(r"[^a-z0-9]", "", low)
    return re.sub(r"^bip0*1", "bip", low)


def _expand(text: str, side: str | None) -> str:
    if side is None:
        return text
    for k, v in _SIDES[side].items():
        text = text.replace(k, v)
    return text


def _entries(key: str, table: dict[str, list[str]]) -> tuple[tuple[str, str], ...]:
    """(canonical key or group, normalized joint name) for every template of convention ``key``,
    both sides expanded (computed once per convention)."""
    cached = _ENTRIES.get(key)
    if cached is None:
        cached = tuple((_expand(k, side), normalize(_expand(name, side)))
                       for k, names in table.items() for side in (("l", "r") if "{" in k else (None,))
                       for name in names)
        _ENTRIES[key] = cached
    return cached


_ENTRIES: dict[str, tuple[tuple[str, str], ...]] = {}


def _hits(name: str, table: dict[str, list[str]], index: dict[str, str]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for key, norm in _entries(name, table):
        joint = index.get(norm)
        if joint is not None and joint not in out.get(key, []):
            out.setdefault(key, []).append(joint)
    return out


def _number(ordered: list[str], slots: tuple[str, ...], rule: str) -> dict[str, str]:
    """Apply the labelling rule to torso or neck joints listed bottom-up."""
    if not ordered:
        return {}
    if rule == "torso":  # chest is always spine3
        if len(ordered) == 1:
            return {"spine3": ordered[0]}
        if len(ordered) == 2:
            return {"spine1": ordered[0], "spine3": ordered[1]}
        return {"spine1": ordered[0], "spine2": ordered[1], "spine3": ordered[-1]}
    if len(ordered) == 1:
        return {"spine4": ordered[0]}
    return {"spine4": ordered[0], "spine5": ordered[-1]}


def _assemble(hits: dict[str, list[str]], skeleton) -> dict[str, str]:
    depth = skeleton.depths
    index = skeleton.index
    joints: dict[str, str] = {}
    for group in ("torso", "neck"):
        found = sorted(hits.get(group, []), key=lambda n: depth[index[n]])
        joints.update(_number(found, (), group))
    for key, names in hits.items():
        if key in ("torso", "neck") or key in joints:
            continue
        joints[key] = names[0]
    return joints


_PREFIX = re.compile(r"^([^_:.\- ]+[_:.\- ])(.+)$")
_SIDE_WORDS = frozenset({"l", "r", "left", "right", "lf", "rt"})


def name_index(names) -> dict[str, str]:
    """Normalized name -> joint name; names also under their tail after a prefix that at least three
    names share (``Character1_LeftUpLeg`` as ``leftupleg``), full names first."""
    index: dict[str, str] = {}
    for n in names:
        index.setdefault(normalize(n), n)
    split = [(m.group(1), m.group(2), n) for n in names if (m := _PREFIX.match(n))]
    counts: dict[str, int] = {}
    for prefix, _, _ in split:
        counts[prefix] = counts.get(prefix, 0) + 1
    for prefix, tail, n in split:
        if counts[prefix] >= 3 and prefix[:-1].lower() not in _SIDE_WORDS:
            index.setdefault(normalize(tail), n)
    return index


def _from_vrm_humanoid(humanoid, skeleton) -> dict[str, str]:
    """Canonical -> joint from a VRM humanoid map (VRM bone name -> node name)."""
    if not isinstance(humanoid, dict):
        return {}
    bones = {normalize(k) for k in humanoid}
    version = "vrm0" if "leftthumbmetacarpal" not in bones and "leftthumbintermediate" in bones else "vrm"
    table = {**VRM, **VRM0_THUMB} if version == "vrm0" else VRM
    by_bone = {}
    for key, norm in _entries(version, table):
        by_bone.setdefault(norm, key)
    hits: dict[str, list[str]] = {}
    for bone, node in humanoid.items():
        key = by_bone.get(normalize(bone))
        if key is not None and isinstance(node, str) and node in skeleton.index:
            hits.setdefault(key, []).append(node)
    return _assemble(hits, skeleton)


def names_map(skeleton, pose=None, meta=None, fixed=None, file=None, humanoid=None, **_options) -> Mapping:
    """Map ``skeleton`` by its joint names (see the module docstring)."""
    index = name_index(skeleton.names)
    joints = _from_vrm_humanoid(humanoid, skeleton)
    source = "the file's VRM humanoid map" if joints else ""
    sources = {n: source for n in joints}
    if len(joints) < MIN_NAMES:
        found = sorted(((conv, _assemble(_hits(conv, table, index), skeleton)) for conv, table in CONVENTIONS.items()),
                       key=lambda item: -len(item[1]))  # stable: the first listed convention wins a tie
        best_name, best = found[0]
        if len(best) < MIN_NAMES:
            raise NotHumanoidError(file, f"no known naming convention names its joints (best: {best_name if best else 'none'}, "
                                         f"{len(best)} names); try --mapper heuristic")
        joints = dict(best)
        sources = {n: f"the {best_name} naming convention" for n in joints}
        # rigs that mix conventions (a hand of one beside a body of another): names the best one
        # leaves out come from the others, never taking a joint twice
        used = set(joints.values())
        for conv, more in found[1:]:
            for key, joint in more.items():
                if key not in joints and joint not in used:
                    joints[key] = joint
                    used.add(joint)
                    sources[key] = f"the {conv} naming convention"
        source = f"the {best_name} naming convention"
    body = check_body(skeleton, joints, pose)
    if body.why is not None:
        raise NotHumanoidError(file, body.why)
    mirrored = mirrored_vote(body.positions, skeleton, joints, body.up) >= MIRRORED_VOTE
    if mirrored:  # names written from the viewer's side: the body's own left decides
        joints, sources = swapped(joints), swapped(sources)
    conf = {n: (0.95 if n in joints else 0.7) for n in ALL_NAMES}
    reasons = {n: (f"{joints[n]!r} in {sources[n]}" if n in joints else f"no joint of that name in {source}")
               for n in ALL_NAMES}
    if mirrored:
        for n in joints:
            if swapped({n: ""}).keys() != {n}:
                conf[n] = 0.85
                reasons[n] += ("; the side names say the opposite of the body (left = up x forward, forward "
                               "where the toes point and the knees bend): the body decides")
    # limbs the names do not give but the geometry shows stay unmapped: a name-based mapper does not
    # guess which joint of an unnamed chain is which; it says where they are
    for kind, limbs in body.from_geometry.items():
        chains = f"{skeleton.names[limbs.a[0]]}, {skeleton.names[limbs.b[0]]}"
        for n in ALL_NAMES:
            if n not in joints and n[:2] in ("l_", "r_") and limb_part(n) in LIMB_PARTS[kind]:
                conf[n] = 0.3
                reasons[n] = (f"no joint of that name in {source}; the hierarchy shows {kind} from {chains} "
                              "(try --mapper heuristic)")
    # Hand-set entries (``fixed``) are applied by infuse.mapping.complete after every mapper.
    return Mapping.build(skeleton, joints, conf, reasons, mapper=NAME,
                         overall_confidence=0.95 if len(joints) >= 20 else 0.6)
