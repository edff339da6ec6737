"""The canonical skeleton: SmartBody's joint names with their hierarchy, body groups and a T-pose.

Everything that works on "a humanoid" addresses joints through these names, whatever a file calls
them; a :class:`~infuse.mapping.Mapping` says which joint of a real skeleton each name means. The
table itself is data (``data/canonical_skeleton.toml``): 69 required names (the corpus labelling
set) plus optional extras such as ``l_sternoclavicular`` and the eyelids.

The authored rest is in the core frame (metres, +Y up, +Z forward, +X the character's left), a
T-pose about 1.75 m tall with identity local rest rotations.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

from . import quaternions as quat
from .skeleton import Skeleton

GROUPS = ("torso", "neck", "head", "eye", "arm", "hand", "leg", "foot")
SIDES = ("center", "left", "right")
FINGERS = ("thumb", "index", "middle", "ring", "pinky")


@dataclass(frozen=True)
class CanonicalJoint:
    """One row of the canonical table. ``position`` is the global T-pose position in metres."""

    name: str
    parent: str | None
    group: str
    side: str
    position: tuple[float, float, float]
    extra: bool = False


@lru_cache(maxsize=1)
def canonical_joints() -> tuple[CanonicalJoint, ...]:
    """Every canonical joint (required and extra), parents first, as authored in the table."""
    text = resources.files("infuse").joinpath("data/canonical_skeleton.toml").read_text(encoding="utf-8")
    rows = tomllib.loads(text)["joints"]
    joints = tuple(
        CanonicalJoint(r["name"], r["parent"] or None, r["group"], r["side"], (float(r["position"][0]), float(r["position"][1]), float(r["position"][2])),
                       bool(r.get("extra", False)))
        for r in rows
    )
    seen: set[str] = set()
    for j in joints:  # the table is data a person edits: check it once
        if j.parent is not None and j.parent not in seen:
            raise ValueError(f"canonical table: parent {j.parent!r} of {j.name!r} is not listed before it")
        if j.group not in GROUPS or j.side not in SIDES or j.name in seen:
            raise ValueError(f"canonical table: bad row {j.name!r}")
        seen.add(j.name)
    return joints


@lru_cache(maxsize=1)
def _by_name() -> dict[str, CanonicalJoint]:
    return {j.name: j for j in canonical_joints()}


def canonical_joint(name: str) -> CanonicalJoint:
    """The table row of canonical ``name`` (KeyError if there is none)."""
    return _by_name()[name]


#: The 69 required canonical names, in table order (the set every label file uses).
CANONICAL_NAMES: tuple[str, ...] = tuple(j.name for j in canonical_joints() if not j.extra)
#: Optional extra names, mapped only when a skeleton clearly has them.
EXTRA_NAMES: tuple[str, ...] = tuple(j.name for j in canonical_joints() if j.extra)
#: Every canonical name, required then extra, in table order.
ALL_NAMES: tuple[str, ...] = tuple(j.name for j in canonical_joints())

#: The joints every humanoid body has (used to judge mappers): pelvis, lower and upper torso, neck,
#: head, clavicle to wrist, thigh to ball of the foot.
BODY_NAMES: tuple[str, ...] = ("base", "spine1", "spine3", "spine4", "skullbase") + tuple(
    f"{s}_{j}" for s in ("l", "r")
    for j in ("acromioclavicular", "shoulder", "elbow", "forearm", "wrist", "hip", "knee", "ankle", "forefoot")
)


def is_canonical(name: str) -> bool:
    return name in _by_name()


def mirror_name(name: str) -> str:
    """The canonical name on the other side (``l_wrist`` <-> ``r_wrist``); central names map to themselves."""
    if name.startswith("l_"):
        return "r_" + name[2:]
    if name.startswith("r_"):
        return "l_" + name[2:]
    if name.endswith("_left"):
        return name[:-5] + "_right"
    if name.endswith("_right"):
        return name[:-6] + "_left"
    return name


def names_in_group(group: str, side: str | None = None, extras: bool = False) -> tuple[str, ...]:
    """Canonical names of one body group (optionally one side), in table order."""
    return tuple(j.name for j in canonical_joints()
                 if j.group == group and (side is None or j.side == side) and (extras or not j.extra))


def canonical_skeleton(extras: bool = True) -> Skeleton:
    """The canonical skeleton in its authored T-pose (identity local rest rotations).

    With ``extras=False`` only the 69 required names are kept; a joint whose parent is an extra
    then hangs from its nearest kept ancestor (``l_acromioclavicular`` from ``spine3``).
    """
    rows = [j for j in canonical_joints() if extras or not j.extra]
    kept = {j.name for j in rows}
    index = {j.name: i for i, j in enumerate(rows)}
    parents = []
    for j in rows:
        p = j.parent
        while p is not None and p not in kept:
            p = canonical_joint(p).parent
        parents.append(-1 if p is None else index[p])
    positions = np.array([j.position for j in rows])
    parents_arr = np.array(parents)
    offsets = positions - np.where(parents_arr[:, None] >= 0, positions[np.maximum(parents_arr, 0)], 0.0)
    return Skeleton(tuple(j.name for j in rows), parents_arr, offsets, quat.identity((len(rows),)))
