"""Foot contacts: when a foot rests on the ground, found from its speed and height.

The start of the foot-contact component: these flags feed the planted positions and pinning goals
of :mod:`infuse.footing`, which the leg IK of :mod:`infuse.runtime.limb_ik` enforces.

Thresholds are normalized by the leg length (thigh + shin, metres), so one setting fits a child, an
adult and a giant robot, and speeds are per second, so it fits any frame rate. The ground is the
level of the lowest foot joint while a foot is planted (a joint centre, not a mesh sole), +Y up.

Each foot has up to two contact points: the ankle (heel side) and the ball (``forefoot``, else
``toe``). A point lands when it moves slower than ``speed`` leg lengths per second and sits less than
``height`` leg lengths above its own planted height, and stays down until it moves faster or rises
``release`` times that high (hysteresis: a point hovering at the height does not flicker); runs
shorter than ``min_duration`` seconds are dropped and gaps shorter than that are filled. On noisy
mocap (:func:`position_noise`) the paths are first low-passed over a window set in seconds and the
speed thresholds kept above the noise that remains (:func:`smoothed`); clean motion is not touched.
:func:`contact_phases` then tells the heel (ankle) from the ball of each planted foot.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from collections.abc import Mapping as NameTable
from typing import TYPE_CHECKING, Union

import numpy as np

from .errors import UnusableInputError
from .kinematics import end_site_positions, motion_fk
from .motion import Motion
from .skeleton import Skeleton

if TYPE_CHECKING:
    from .mapping import Mapping

#: A canonical mapping: a :class:`~infuse.mapping.Mapping`, or canonical name -> joint name or index.
MappingLike = Union["Mapping", NameTable[str, str | int]]
SIDES = (("left", "l_"), ("right", "r_"))
#: Factor by which a planted point's height threshold widens before it lifts off (:func:`detect`). The
#: speed threshold does not widen: feet held into their lift-off measured more skate once retargeted
#: (a speed factor of 1.1 or 1.25 left 6% or 32% more on the retargeting benchmark's pairs).
RELEASE = 1.25
#: How far (leg lengths) the ball may sit above its planted height and still be down: about 8 mm on
#: an adult (:func:`contact_phases`).
DOWN_TOLERANCE = 0.01
#: How far (leg lengths) the ankle may rise above its planted height, the ball down, before the heel
#: counts as off: about 2.5 mm on an adult, a heel rise of about 1 degree, so the foot starts to
#: pivot about its ball as soon as the heel starts to rise (:func:`contact_phases`).
RISE_TOLERANCE = 0.003
#: Speed (leg lengths per second) below which a point lands, by default (:func:`detect`).
LANDING_SPEED = 0.5
#: Share of the speed threshold by which position noise may move a point's measured speed before
#: :func:`detect` low-passes the positions (:func:`smoothed`).
NOISE_SPEED = 0.1
#: The widest window (seconds) over which :func:`detect` low-passes noisy positions.
MAX_SMOOTHING_S = 0.3
#: A point lands below, and lifts off above, these multiples of the speed that the noise left after
#: low-passing gives a point at rest, when that exceeds the speed threshold (:func:`detect`): noise
#: that moves a planted foot faster than a foot landing must not break its contact.
NOISE_LAND = 4.0
NOISE_LIFT = 6.0


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


def joint_index(skeleton: Skeleton, mapping: MappingLike) -> dict[str, int]:
    """Canonical name -> joint index from a :class:`~infuse.mapping.Mapping` or a dict whose values
    are joint names or indices."""
    items = mapping.items() if isinstance(mapping, NameTable) else mapping.mapped().items()
    out: dict[str, int] = {}
    for k, v in items:
        if isinstance(v, (int, np.integer)):
            out[k] = int(v)
        elif v in skeleton.index:
            out[k] = skeleton.index[v]
    return out


def feet(skeleton: Skeleton, mapping: MappingLike, file: str | Path | None = None) -> tuple[Foot, Foot]:
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


def leg_length(skeleton: Skeleton, pair: tuple[Foot, Foot], positions: np.ndarray | None = None,
               file: str | Path | None = None) -> float:
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


def lowest_points(skeleton: Skeleton, pair: tuple[Foot, Foot], global_rotations: np.ndarray,
                  global_positions: np.ndarray) -> np.ndarray:
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


def hysteresis(enter: np.ndarray, stay: np.ndarray) -> np.ndarray:
    """(F, P) flags that turn on in a frame where ``enter`` (F, P) holds and stay on, frame after
    frame, for as long as ``stay`` (F, P) holds (``enter`` implies ``stay``)."""
    stay = np.asarray(stay, dtype=bool) | enter
    frames = np.arange(len(stay))[:, None]
    broken = np.maximum.accumulate(np.where(stay, -1, frames), axis=0)  # the last frame ``stay`` failed
    entered = np.maximum.accumulate(np.where(enter, frames, -1), axis=0)  # the last frame ``enter`` held
    return stay & (entered > broken)


def position_noise(positions: np.ndarray) -> float:
    """Frame-to-frame position noise (metres, standard deviation along each axis) of points moving
    through ``positions`` (F, P, 3).

    The k-th difference of a smooth path is nearly zero, while noise of standard deviation s per
    axis and frame gives one of s x sqrt(C(2k, k)) per axis, whose length has its 5th percentile at
    0.585 times that. The 5th percentile over every point and frame (the feet at rest, where nothing
    else moves them) of the second and of the fourth difference each give an estimate, the smaller
    one is taken: the second difference overstates it where feet accelerate steadily, the fourth
    where every stance is shorter than its 5 frames (a run at a low frame rate). 0 below 5 frames.
    """
    if len(positions) < 5:
        return 0.0
    estimates = [np.percentile(np.linalg.norm(np.diff(positions, n=k, axis=0), axis=-1), 5.0) / (0.585 * np.sqrt(c))
                 for k, c in ((2, 6.0), (4, 70.0))]
    return float(min(estimates))


def _slope_noise(half: np.ndarray) -> np.ndarray:
    """Noise of a velocity measured over ``half`` frames to either side, per unit of position noise
    and frame rate: a local linear slope's sqrt(3 / (h (h + 1) (2h + 1))), one frame's difference
    sqrt(2) at a clip's ends (``half`` 0)."""
    h = np.maximum(half, 1).astype(np.float64)
    out: np.ndarray = np.where(half > 0, np.sqrt(3.0 / (h * (h + 1) * (2 * h + 1))), np.sqrt(2.0))
    return out


def smoothing_frames(noise: float, fps: float, tolerance_m_s: float) -> int:
    """Frames to either side of the fewest (at least 1, at most :data:`MAX_SMOOTHING_S` seconds in all)
    over which a local fit keeps position noise of ``noise`` metres (:func:`position_noise`) from moving
    a velocity measured at ``fps`` by more than ``tolerance_m_s`` along each axis; 1 for clean motion."""
    widest = max(int(MAX_SMOOTHING_S * fps / 2.0), 1)
    half = np.arange(1, widest + 1)
    enough = noise * fps * _slope_noise(half) <= tolerance_m_s
    return int(half[np.argmax(enough)] if enough.any() else widest)


def smoothed(positions: np.ndarray, fps: float, tolerance_m_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (F, P, 3) metres and velocities (F, P, 3) m/s low-passed just enough that the noise
    of ``positions`` (:func:`position_noise`) moves a velocity by at most ``tolerance_m_s`` along
    each axis, and the speed (F,) m/s that the noise left gives a point at rest (the mean length of
    its noisy velocity).

    A local quadratic fit over the fewest frames to either side that does it, at most
    :data:`MAX_SMOOTHING_S` seconds, the window narrowing towards the clip's ends so that a foot
    landing in its first frames is seen moving (the first and last frame of a noisy clip take their
    neighbour's velocity); clean motion keeps its positions and central differences.
    """
    pos = np.asarray(positions, dtype=np.float64)
    frames = len(pos)
    noise = position_noise(pos)
    h = smoothing_frames(noise, fps, tolerance_m_s)
    t = np.arange(frames)
    reach = np.minimum(np.minimum(t, frames - 1 - t), h)  # (F,) frames to either side
    velocity = np.gradient(pos, axis=0) * fps
    out = pos.copy()
    for m in range(2, h + 1):
        at = np.nonzero(reach == m)[0]
        if not at.size:
            continue
        k = np.arange(-m, m + 1)
        window = pos[at[:, None] + k]  # (n, 2m + 1, P, 3)
        # least-squares quadratic through the window: its value and slope at the middle frame
        value = (3.0 * (3 * m * m + 3 * m - 1) - 15.0 * k * k) / ((2 * m - 1) * (2 * m + 1) * (2 * m + 3))
        out[at] = np.einsum("k,nkpc->npc", value, window)
        velocity[at] = np.einsum("k,nkpc->npc", k / float(k @ k), window) * fps
    if h > 1 and frames > 2:  # a noisy clip's end frames: one frame's difference tells nothing
        velocity[[0, -1]] = velocity[[1, -2]]
        reach[[0, -1]] = 1
    return out, velocity, np.sqrt(3.0) * noise * fps * _slope_noise(reach)


def detect(
    positions: np.ndarray,
    fps: float,
    leg: float,
    ground: float,
    *,
    speed: float = LANDING_SPEED,
    height: float = 0.06,
    release: float = RELEASE,
    min_duration: float = 0.05,
) -> np.ndarray:
    """(F, P) contact flags of points moving through ``positions`` (F, P, 3) metres.

    A point lands when its speed is below ``speed`` x ``leg`` per second and its height above its
    own planted height (its 5th-percentile height, at least ``ground``) is below ``height`` x
    ``leg``, and stays planted until its speed exceeds that or its height exceeds ``release`` (>= 1)
    times that. Runs shorter than ``min_duration`` seconds are dropped, gaps shorter are filled.
    """
    pos = np.asarray(positions, dtype=np.float64)
    if len(pos) < 2:
        return np.ones(pos.shape[:2], dtype=bool)
    pos, vel, at_rest = smoothed(pos, fps, NOISE_SPEED * speed * leg)
    sp = np.linalg.norm(vel, axis=-1)
    y = pos[..., 1]
    planted = np.maximum(np.percentile(y, 5.0, axis=0), ground)
    rise = y - planted
    loose = max(float(release), 1.0)
    slow = sp < np.maximum(speed * leg, NOISE_LAND * at_rest)[:, None]
    still = sp < np.maximum(speed * leg, NOISE_LIFT * at_rest)[:, None]
    flags = hysteresis(slow & (rise < height * leg), still & (rise < loose * height * leg))
    return clean_runs(flags, max(1, int(round(min_duration * fps))))


def foot_contacts(motion: Motion, mapping: MappingLike, fk: tuple[np.ndarray, np.ndarray] | None = None,
                  **thresholds: float) -> FootContacts:
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


def foot_frames(heel: np.ndarray, ball: np.ndarray) -> np.ndarray:
    """(F, 3, 3) orthonormal frames of a foot from its heel (ankle) and ball joints (F, 3) metres:
    rows forward (heel to ball), side (forward x up, horizontal) and up (side x forward), so a foot
    pitching about its side axis or turning about the vertical carries its frame exactly (a roll
    about its own length, which two points cannot show, is not followed). The cross products are
    written out (up is +y): numpy's are slow on the few rows of a live block."""
    forward = np.asarray(ball, dtype=np.float64) - heel
    forward /= np.maximum(np.sqrt((forward * forward).sum(axis=-1, keepdims=True)), 1e-12)
    fx, fy, fz = forward[..., 0], forward[..., 1], forward[..., 2]
    across = np.maximum(np.sqrt(fz * fz + fx * fx), 1e-12)
    sx, sz = -fz / across, fx / across
    out = np.empty(forward.shape[:-1] + (3, 3))
    out[..., 0, :] = forward
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = sx, 0.0, sz
    out[..., 2, 0], out[..., 2, 1], out[..., 2, 2] = -(sz * fy), sz * fx - sx * fz, sx * fy
    return out


def sole_positions(found: FootContacts, positions: np.ndarray, tolerance: float = DOWN_TOLERANCE) -> np.ndarray:
    """(F, P, 3) the points of the sole that the contact joints stand for, metres, carried by the foot.

    ``positions`` (F, P, 3): the contact joints, columns as ``found.points``. The sole is taken at
    the level of the ball joint, about which the foot rolls at heel off: the ball stands for itself,
    the ankle for the point of the sole under the heel. That point lies straight below the ankle at
    the ball's height in the foot's flat pose (the frames where both joints are planted and lowest,
    their summed height within ``tolerance`` leg lengths of its least); its offset from the ankle,
    in the foot's frame (:func:`foot_frames`, the median over the flat frames), is carried by that
    frame in every frame. A rigid foot rolling about its ball or its heel leaves that point still
    while the ankle swings along an arc above it; a foot sliding moves it as far as the joints. A
    foot with only its ankle keeps the joint, whose horizontal path is that of the ground below it.
    """
    pos = np.asarray(positions, dtype=np.float64)
    out = pos.copy()
    if not len(pos):
        return out
    for k in (0, 1):
        cols = np.nonzero(found.foot_of_point == k)[0]
        if len(cols) < 2:
            continue
        ankle, ball = pos[:, cols[0]], pos[:, cols[1]]
        frames = foot_frames(ankle, ball)
        both = found.flags[:, cols[:2]].all(axis=1)
        height = ankle[:, 1] + ball[:, 1]
        candidates = both if both.any() else np.ones(len(pos), dtype=bool)
        flat = candidates & (height <= height[candidates].min() + tolerance * found.leg_length)
        drop = np.zeros((int(flat.sum()), 3))
        drop[:, 1] = ball[flat, 1] - ankle[flat, 1]
        offset = np.median(np.einsum("fij,fj->fi", frames[flat], drop), axis=0)
        out[:, cols[0]] = ankle + offset @ frames
    return out


def contact_phases(found: FootContacts, positions: np.ndarray, tolerance: float = DOWN_TOLERANCE,
                   rise: float = RISE_TOLERANCE) -> np.ndarray:
    """(F, 2, 2) flags of each foot (left, right) having its heel (ankle) and its ball down.

    ``found``: the clip's :class:`FootContacts`; ``positions`` (F, J, 3) metres. A foot's ball is
    down while the foot is planted and the ball sits within ``tolerance`` leg lengths of its planted
    height (its lower quartile while the foot is planted: the ball is down for most of a stance);
    the heel is down while the foot is planted, except when the ankle has risen more than ``rise``
    leg lengths with the ball down, or after the ball was down in that stance (heel off, the push
    off on the toes, or a landing on the ball). During the heel rocker (toes up after heel strike)
    only the heel is down. A foot without a ball point has its heel down whenever it is planted.
    """
    planted = found.foot_flags()
    out = np.zeros(planted.shape + (2,), dtype=bool)
    eps = tolerance * found.leg_length
    for k in (0, 1):
        pts = found.points[found.foot_of_point == k]
        ankle = positions[:, pts[0], 1]
        raised = ankle - np.percentile(ankle[planted[:, k]] if planted[:, k].any() else ankle, 5.0) > rise * found.leg_length
        if len(pts) > 1:
            y = positions[:, pts[1], 1]
            ball = planted[:, k] & (y - np.percentile(y[planted[:, k]] if planted[:, k].any() else y, 25.0) <= eps)
        else:
            ball = np.zeros(len(planted), dtype=bool)
        frames = np.arange(len(ball))
        stance_start = np.maximum.accumulate(np.where(planted[:, k] & ~np.roll(planted[:, k], 1), frames, 0))
        ball_seen = np.maximum.accumulate(np.where(ball, frames, -1)) >= stance_start
        out[:, k, 0] = planted[:, k] & ~(ball_seen & raised)
        out[:, k, 1] = ball
    return out


def phase_contacts(found: FootContacts, positions: np.ndarray, tolerance: float = DOWN_TOLERANCE,
                   rise: float = RISE_TOLERANCE) -> FootContacts:
    """``found`` with each point's flags narrowed to when it is on the ground: the ankle while the
    heel is down, the ball while the ball is down (see :func:`contact_phases`), e.g. for
    :func:`infuse.metrics.foot_skate`."""
    phases = contact_phases(found, positions, tolerance, rise)
    flags = np.zeros_like(found.flags)
    for k in (0, 1):
        cols = np.nonzero(found.foot_of_point == k)[0]
        for n, col in enumerate(cols[:2]):
            flags[:, col] = phases[:, k, n]
    return replace(found, flags=flags)
