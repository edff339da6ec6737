"""Foot contacts: when a foot rests on the ground, found from its speed and height.

Thresholds are normalized by the leg length (thigh + shin, metres), so one setting fits a child, an
adult and a giant robot, and speeds are per second, so it fits any frame rate. The ground is the
level of the lowest foot joint while a foot is planted (a joint centre, not a mesh sole), +Y up.

Each foot has up to two contact points: the ankle (heel side) and the ball (``forefoot``, else
``toe``). A point is in contact while it moves slower than ``speed`` leg lengths per second and sits
less than ``height`` leg lengths above its own planted height; runs shorter than ``min_duration``
seconds are dropped and gaps shorter than that are filled.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import UnusableInputError
from .kinematics import end_site_positions, motion_fk
from .motion import Motion
from .skeleton import Skeleton

SIDES = (("left", "l_"), ("right", "r_"))


@dataclass(frozen=True)
class Foot:
    """One foot of a skeleton: its contact joints and every joint and end site below the ankle.

    ``hip``, ``knee``, ``ankle``: joint indices; ``ball``: the forefoot (else toe) joint or ``None``;
    ``joints``/``end_sites``: the ankle and its descendants, the candidates for the lowest point.
    """

    side: str
    hip: int
    knee: int
    ankle: int
    ball: int | None
    joints: tuple[int, ...]
    end_sites: tuple[int, ...]

    @property
    def points(self) -> tuple[int, ...]:
        """The contact joints: ankle, then ball when there is one."""
        return (self.ankle,) if self.ball is None else (self.ankle, self.ball)


def _descendants(skeleton: Skeleton, joint: int) -> list[int]:
    inside = np.zeros(skeleton.num_joints, dtype=bool)
    inside[joint] = True
    for j in range(joint + 1, skeleton.num_joints):  # parents precede children
        p = skeleton.parents[j]
        inside[j] = p >= 0 and inside[p]
    return [int(j) for j in np.nonzero(inside)[0]]


def joint_index(skeleton: Skeleton, mapping) -> dict[str, int]:
    """Canonical name -> joint index from a :class:`~infuse.mapping.Mapping` or a dict whose values
    are joint names or indices."""
    items = mapping.mapped().items() if hasattr(mapping, "mapped") else mapping.items()
    out = {}
    for k, v in items:
        if isinstance(v, (int, np.integer)):
            out[k] = int(v)
        elif v in skeleton.index:
            out[k] = skeleton.index[v]
    return out


def feet(skeleton: Skeleton, mapping, file=None) -> tuple[Foot, Foot]:
    """The left and right :class:`Foot` of ``skeleton`` from a canonical mapping (see :func:`joint_index`).

    Raises :class:`UnusableInputError` when a hip, knee or ankle is not mapped.
    """
    index = joint_index(skeleton, mapping)
    out = []
    for side, prefix in SIDES:
        missing = [n for n in ("hip", "knee", "ankle") if prefix + n not in index]
        if missing:
            raise UnusableInputError(file, f"no {side} leg: {', '.join(prefix + n for n in missing)} not mapped")
        ankle = index[prefix + "ankle"]
        ball = index.get(prefix + "forefoot", index.get(prefix + "toe"))
        joints = _descendants(skeleton, ankle)
        if ball is not None and ball not in joints:
            joints.append(ball)  # a rig whose foot bones hang elsewhere (IK-driven feet)
        sites = tuple(int(e) for e in np.nonzero(np.isin(skeleton.end_site_parents, joints))[0])
        out.append(Foot(side, index[prefix + "hip"], index[prefix + "knee"], ankle, ball, tuple(joints), sites))
    return out[0], out[1]


def leg_length(skeleton: Skeleton, pair: tuple[Foot, Foot], positions: np.ndarray | None = None, file=None) -> float:
    """Mean thigh + shin length of the two legs in metres (joint distances, so any rest pose will do).

    ``positions`` (J, 3) defaults to the rest pose. Raises :class:`UnusableInputError` for a leg of
    (nearly) zero length.
    """
    pos = skeleton.rest_global_positions if positions is None else np.asarray(positions, dtype=np.float64)
    lengths = [np.linalg.norm(pos[f.knee] - pos[f.hip]) + np.linalg.norm(pos[f.ankle] - pos[f.knee]) for f in pair]
    scale = max(skeleton.height(), 1e-9)
    if not all(np.isfinite(lengths)) or min(lengths) < 1e-3 * scale or min(lengths) < 1e-6:
        raise UnusableInputError(file, f"zero-length leg (thigh + shin = {min(lengths):.3g} m)")
    return float(np.mean(lengths))


def lowest_points(skeleton: Skeleton, pair, global_rotations: np.ndarray, global_positions: np.ndarray) -> np.ndarray:
    """(F, 2) height (Y, metres) of the lowest joint or end site of each foot, left then right."""
    ends = end_site_positions(skeleton, global_rotations, global_positions) if len(skeleton.end_site_parents) else None
    out = []
    for foot in pair:
        h = global_positions[:, list(foot.joints), 1]
        if ends is not None and foot.end_sites:
            h = np.concatenate((h, ends[:, list(foot.end_sites), 1]), axis=1)
        out.append(h.min(axis=1))
    return np.stack(out, axis=1)


def _runs(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start, end (exclusive) and column of every run of True down the columns of (F, P) ``flags``."""
    f, p = flags.shape
    padded = np.zeros((f + 2, p), dtype=np.int8)
    padded[1:-1] = flags
    d = np.diff(padded, axis=0)
    starts = np.argwhere(d.T == 1)  # (column, frame), column-major so runs come out per column in order
    ends = np.argwhere(d.T == -1)
    return starts[:, 1], ends[:, 1], starts[:, 0]


def clean_runs(flags: np.ndarray, min_frames: int) -> np.ndarray:
    """Fill gaps shorter than ``min_frames`` between runs of True, then drop runs shorter than it."""
    flags = np.array(flags, dtype=bool)
    if min_frames <= 1:
        return flags
    gaps = ~flags
    s, e, c = _runs(gaps)
    inner = (s > 0) & (e < len(flags)) & (e - s < min_frames)
    for a, b, col in zip(s[inner], e[inner], c[inner]):
        flags[a:b, col] = True
    s, e, c = _runs(flags)
    for a, b, col in zip(s, e, c):
        if b - a < min_frames:
            flags[a:b, col] = False
    return flags


def contact_runs(flags: np.ndarray) -> list[tuple[int, int, int]]:
    """Every run of True in (F, P) ``flags`` as (point, first frame, end frame exclusive)."""
    s, e, c = _runs(np.asarray(flags, dtype=bool))
    return [(int(col), int(a), int(b)) for a, b, col in zip(s, e, c)]


def estimate_ground(lowest: np.ndarray) -> float:
    """Ground height from (F, 2) lowest foot heights: where the lower foot sits most of the time.

    In walking one foot is down in every frame; in running the flight phases are a minority, so a
    low percentile of the per-frame lower foot is the ground.
    """
    low = np.min(lowest, axis=1)
    return float(np.percentile(low, 10.0))


@dataclass(frozen=True)
class FootContacts:
    """Contact flags of a clip's foot points.

    - ``points``: (P,) joint indices (left ankle, left ball, right ankle, right ball; a foot without
      a ball has only its ankle); ``foot_of_point``: (P,) 0 for left, 1 for right.
    - ``flags``: (F, P) True while the point is planted.
    - ``ground``: metres (Y); ``leg_length``: metres; ``lowest``: (F, 2) lowest point per foot.
    """

    points: np.ndarray
    foot_of_point: np.ndarray
    flags: np.ndarray
    ground: float
    leg_length: float
    lowest: np.ndarray

    def foot_flags(self) -> np.ndarray:
        """(F, 2) True while any point of the foot is planted."""
        out = np.zeros((len(self.flags), 2), dtype=bool)
        for k in (0, 1):
            out[:, k] = self.flags[:, self.foot_of_point == k].any(axis=1)
        return out

    def by_joint(self, skeleton: Skeleton) -> dict[str, np.ndarray]:
        """{joint name: (F,) flags}, e.g. for :class:`infuse.render.Figure` ``contacts``."""
        return {skeleton.names[j]: self.flags[:, k] for k, j in enumerate(self.points)}


def detect(
    positions: np.ndarray,
    fps: float,
    leg: float,
    ground: float,
    *,
    speed: float = 0.5,
    height: float = 0.06,
    min_duration: float = 0.05,
) -> np.ndarray:
    """(F, P) contact flags of points moving through ``positions`` (F, P, 3) metres.

    A point is planted while its speed is below ``speed`` x ``leg`` per second and its height above
    its own planted height (its 5th-percentile height, at least ``ground``) is below ``height`` x
    ``leg``. Runs shorter than ``min_duration`` seconds are dropped, gaps shorter are filled.
    """
    pos = np.asarray(positions, dtype=np.float64)
    if len(pos) < 2:
        return np.ones(pos.shape[:2], dtype=bool)
    vel = np.gradient(pos, axis=0) * fps
    sp = np.linalg.norm(vel, axis=-1)
    y = pos[..., 1]
    planted = np.maximum(np.percentile(y, 5.0, axis=0), ground)
    flags = (sp < speed * leg) & (y - planted < height * leg)
    return clean_runs(flags, max(1, int(round(min_duration * fps))))


def foot_contacts(motion: Motion, mapping, fk=None, **thresholds) -> FootContacts:
    """Contacts of both feet of ``motion`` (see :func:`detect` for ``thresholds``).

    ``mapping`` names the legs (canonical ``l_hip``... ``r_toe``); ``fk`` optionally passes
    precomputed ``(global_rotations, global_positions)``.
    """
    sk = motion.skeleton
    pair = feet(sk, mapping)
    g_rot, g_pos = motion_fk(motion) if fk is None else fk
    leg = leg_length(sk, pair)
    lowest = lowest_points(sk, pair, g_rot, g_pos)
    ground = estimate_ground(lowest)
    points = np.array([j for f in pair for j in f.points], dtype=np.int64)
    foot_of = np.array([k for k, f in enumerate(pair) for _ in f.points], dtype=np.int64)
    flags = detect(g_pos[:, points], motion.fps, leg, ground, **thresholds)
    return FootContacts(points, foot_of, flags, ground, leg, lowest)
