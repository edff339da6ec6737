"""Motion quality figures: foot skate, bone-direction agreement, popping, ground contact and root speed.

Every function takes global joint positions (F, J, 3) in metres (core frame, +Y up) and, where it
compares two clips, the canonical mappings that say which joints correspond. Frames correspond one
to one (a retargeted clip keeps its source's frame count and rate).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import quaternions as quat
from .canonical import BODY_NAMES, canonical_joint
from .contacts import FootContacts, sole_positions


def horizontal_path(points: np.ndarray) -> float:
    """Length in metres of the horizontal (XZ) path through (F, 3) ``points``."""
    d = np.diff(np.asarray(points, dtype=np.float64)[:, [0, 2]], axis=0)
    return float(np.linalg.norm(d, axis=-1).sum())


#: Height (leg lengths) above a contact point's planted height at which its travel stops counting as
#: skate: 2.5 cm on a leg of about 0.85 m, the threshold of Zhang et al. 2018.
SKATE_LIFT = 0.03


@dataclass(frozen=True)
class Skate:
    """Horizontal travel of the feet while planted: ``travel`` metres over ``distance`` metres walked
    by the root; ``per_metre`` is centimetres of skate per metre walked (NaN if it did not travel)."""

    travel: float
    distance: float

    @property
    def per_metre(self) -> float:
        return 100.0 * self.travel / self.distance if self.distance > 1e-6 else float("nan")


def skate_weight(height: np.ndarray, threshold: float) -> np.ndarray:
    """Share of a planted point's horizontal travel that counts as skate at ``height`` above its
    planted height: ``2 - 2^(h / H)`` clipped to [0, 1] (Zhang et al. 2018, *Mode-adaptive neural
    networks for quadruped motion control*), 1 on the ground, 0 from ``threshold`` H up."""
    h = np.maximum(np.asarray(height, dtype=np.float64), 0.0) / max(threshold, 1e-12)
    return np.clip(2.0 - np.exp2(h), 0.0, 1.0)


def foot_skate(positions: np.ndarray, contacts: FootContacts, root: int, points: np.ndarray | None = None,
               lift: float = SKATE_LIFT, steps: np.ndarray | None = None) -> Skate:
    """Foot skate of a clip whose contact flags are ``contacts`` (found on this clip or its source).

    The travel counted is that of the sole, not of the joints: each contact joint (ankle, ball)
    stands for the point of the sole below it, carried rigidly by the foot
    (:func:`infuse.contacts.sole_positions`), so a foot rolling over its ball or heel, whose ankle
    swings forward along an arc above a still sole, counts nothing, and a foot sliding, twisting
    or sliding while it rolls counts the sole's travel. For each foot and each pair of consecutive
    frames in which some of its points are planted, the foot travels the mean horizontal distance
    those sole points move, each weighted by :func:`skate_weight` of its height above its planted
    height (its 5th-percentile height while planted), with H = ``lift`` x the leg length: a point
    sliding on the ground counts fully, a point lifting off less the higher it is, and not at all
    from H up. ``lift=inf`` counts every planted frame fully. ``points`` (P,) gives the joints of
    ``positions`` (F, J, 3) metres that play the contact points (default ``contacts.points``: the
    same skeleton); ``root`` is the joint whose horizontal path is the distance walked. ``steps``
    (F - 1,) bool, optional: count only the travel from frame f to f + 1 where ``steps[f]`` holds,
    the planted heights still those of the whole clip (so the travels of steps split into parts
    add up to the whole's); the distance walked stays the whole clip's.
    """
    pos = np.asarray(positions, dtype=np.float64)
    pts = contacts.points if points is None else np.asarray(points)
    p = sole_positions(contacts, pos[:, pts])
    step = np.linalg.norm(np.diff(p[..., [0, 2]], axis=0), axis=-1)  # (F-1, P)
    held = contacts.flags[1:] & contacts.flags[:-1]
    if steps is not None:
        held = held & np.asarray(steps, dtype=bool)[:, None]
    y = p[..., 1]
    ever = contacts.flags.any(axis=0)  # a point never planted: its heights over the whole clip
    planted = np.nanpercentile(np.where(contacts.flags | ~ever, y, np.nan), 5.0, axis=0)
    rise = 0.5 * (y[1:] + y[:-1]) - planted
    weight = skate_weight(rise, lift * contacts.leg_length) if np.isfinite(lift) else np.ones_like(step)
    travel = 0.0
    for k in (0, 1):
        cols = contacts.foot_of_point == k
        n = held[:, cols].sum(axis=1)
        moved = (step[:, cols] * weight[:, cols] * held[:, cols]).sum(axis=1)
        travel += float(np.sum(np.where(n > 0, moved / np.maximum(n, 1), 0.0)))
    return Skate(travel, horizontal_path(pos[:, root]))


#: Pairs of joints whose connecting line stands for a branching joint's orientation (pelvis, chest).
ACROSS = (("r_hip", "l_hip"), ("r_shoulder", "l_shoulder"))


def canonical_bones(source_index: dict[str, int], target_index: dict[str, int], names=BODY_NAMES) -> list[tuple[str, str]]:
    """(start, end) canonical pairs mapped on both sides, within ``names``, whose direction should agree.

    Each mapped joint with a single mapped canonical child gives the bone to it (a joint missing
    between them is skipped over). Bones leaving a branching joint (pelvis to hip, chest to neck or
    clavicle) are fixed by how each rig is built, not by the motion, so instead the hip-to-hip and
    shoulder-to-shoulder lines stand for the pelvis and chest orientation.
    """
    common = [n for n in names if n in source_index and n in target_index]
    kept = set(common)
    children: dict[str, list[str]] = {n: [] for n in common}
    for child in common:
        parent = canonical_joint(child).parent
        while parent is not None and parent not in kept:
            parent = canonical_joint(parent).parent
        if parent is not None:
            children[parent].append(child)
    bones = [(p, kids[0]) for p, kids in children.items() if len(kids) == 1]
    bones += [(a, b) for a, b in ACROSS if a in kept and b in kept]
    return bones


@dataclass(frozen=True)
class BoneAgreement:
    """Angles in degrees between corresponding bones of two clips: ``per_bone`` {"a->b": mean over
    frames}, ``mean`` over bones and frames, ``worst`` the largest per-frame angle."""

    per_bone: dict[str, float]
    mean: float
    worst: float


def bone_directions(source_positions: np.ndarray, source_index: dict[str, int], output_positions: np.ndarray,
                    output_index: dict[str, int], names=BODY_NAMES) -> BoneAgreement:
    """Mean angle between corresponding canonical bones (see :func:`canonical_bones`) of two clips.

    ``*_index``: canonical name -> joint index of each clip's skeleton (``Mapping.indices``).
    """
    bones = canonical_bones(source_index, output_index, names)
    if not bones:
        return BoneAgreement({}, float("nan"), float("nan"))
    a = np.array([[source_index[p], source_index[c]] for p, c in bones])
    b = np.array([[output_index[p], output_index[c]] for p, c in bones])
    u = source_positions[:, a[:, 1]] - source_positions[:, a[:, 0]]
    v = output_positions[:, b[:, 1]] - output_positions[:, b[:, 0]]
    nu = np.linalg.norm(u, axis=-1)
    nv = np.linalg.norm(v, axis=-1)
    cos = np.sum(u * v, axis=-1) / np.maximum(nu * nv, 1e-12)
    ang = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    ang = np.where((nu > 1e-6) & (nv > 1e-6), ang, 0.0)  # zero-length bones have no direction
    per_bone = {f"{p}->{c}": float(m) for (p, c), m in zip(bones, ang.mean(axis=0))}
    return BoneAgreement(per_bone, float(ang.mean()), float(ang.max()))


@dataclass(frozen=True)
class GroundContact:
    """How the feet meet the ground, centimetres: ``penetration`` mean depth of the lower foot point
    below the ground over all frames (``max_penetration`` the deepest), ``float`` mean height of a
    planted foot's lowest point above the ground."""

    penetration: float
    max_penetration: float
    float: float


def ground_contact(lowest: np.ndarray, foot_flags: np.ndarray, ground: float) -> GroundContact:
    """Penetration and float from (F, 2) lowest foot heights and (F, 2) planted flags, metres in."""
    below = np.maximum(ground - np.asarray(lowest), 0.0)
    above = np.maximum(np.asarray(lowest) - ground, 0.0)
    planted = np.asarray(foot_flags, dtype=bool)
    fl = float(above[planted].mean()) if planted.any() else 0.0
    return GroundContact(100.0 * float(below.mean()), 100.0 * float(below.max()), 100.0 * fl)


def mean_speed(points: np.ndarray, fps: float) -> float:
    """Mean horizontal speed, metres per second, along (F, 3) ``points`` (path length over duration)."""
    n = len(points)
    return horizontal_path(points) * fps / (n - 1) if n > 1 else 0.0


def largest_turns(global_rotations: np.ndarray) -> np.ndarray:
    """(J,) the largest turn of each joint's global orientation between consecutive frames, degrees,
    from (F, J, 4) global rotations (x, y, z, w); zeros for a clip of one frame."""
    g = np.asarray(global_rotations, dtype=np.float64)
    if len(g) < 2:
        return np.zeros(g.shape[1])
    return np.degrees(quat.angle_between(g[:-1], g[1:]).max(axis=0))


#: The popping bound: a joint may turn in one frame at most ``POP_FACTOR`` x the source's largest
#: turn of that joint, plus ``POP_MARGIN_DEG`` degrees.
POP_FACTOR = 1.5
POP_MARGIN_DEG = 10.0


def pop_limit(source_deg):
    """The largest per-frame turn (degrees) allowed for a joint whose source turns at most ``source_deg``."""
    return POP_FACTOR * np.asarray(source_deg) + POP_MARGIN_DEG


@dataclass(frozen=True)
class Popping:
    """Largest per-frame turns of corresponding joints, degrees: ``per_joint`` {canonical name:
    (source, output)}; ``worst`` the joint whose output turn exceeds its :func:`pop_limit` by the
    most (or comes closest to it), ``excess`` by how many degrees (negative: within the bound)."""

    per_joint: dict[str, tuple[float, float]]
    worst: str
    excess: float

    @property
    def ok(self) -> bool:
        """Every joint within :func:`pop_limit`."""
        return self.excess <= 0.0

    def turns(self, name: str | None = None) -> tuple[float, float]:
        """(source, output) largest turn of joint ``name`` (default: the worst joint)."""
        return self.per_joint[self.worst if name is None else name]


def popping(source_rotations: np.ndarray, source_index: dict[str, int], output_rotations: np.ndarray,
            output_index: dict[str, int], names=None) -> Popping:
    """Popping of a clip against its source: each joint's largest change of global orientation
    between frames (:func:`largest_turns`), output against source, over the canonical ``names``
    (default: every name both ``*_index`` map, canonical name -> joint index).

    ``*_rotations``: (F, J, 4) global rotations of each clip; the frame rates should agree (a joint
    turning at a given speed turns by the same angle per frame).
    """
    names = [n for n in (source_index if names is None else names) if n in source_index and n in output_index]
    if not names:
        return Popping({}, "", float("-inf"))
    src = largest_turns(np.asarray(source_rotations)[:, [source_index[n] for n in names]])
    out = largest_turns(np.asarray(output_rotations)[:, [output_index[n] for n in names]])
    excess = out - pop_limit(src)
    k = int(np.argmax(excess))
    per_joint = {n: (float(a), float(b)) for n, a, b in zip(names, src, out)}
    return Popping(per_joint, names[k], float(excess[k]))
