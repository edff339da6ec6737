"""Generated variants of a real locomotion motion set, for testing pack import and build on sets nobody prepared.

A :class:`MotionSet` holds takes (name -> :class:`~infuse.Motion`) on one skeleton read from BVH (whose
rest rotations are identity) and the unit and up axis it is written in; :func:`write_set` writes it as a
folder of BVH files, which ``infuse pack import bvh`` then reads as a new user's set. Variants of a set
(:data:`VARIANTS`, each a function of the set and a random generator):

- ``fps_24`` / ``fps_50`` / ``fps_120``: every take resampled to that frame rate (rotations slerped,
  translations interpolated linearly);
- ``metres`` / ``z_up``: written in another unit (metres, or centimetres for a set in metres) or with
  +Z up (the figure lying along Z in the file, as 3ds Max and MotionBuilder write it);
- ``renamed``: joints renamed into the Mixamo convention, namespace prefix included (``mixamorig:Hips``);
  joints the mapping leaves out, or the convention does not name, behind the same prefix;
- ``a_pose``: the rest pose's arms turned about the shoulders in the frontal plane to 45 degrees below
  the horizontal; the motion re-expressed so that every joint moves as before (only the file's offsets
  and channel values change);
- ``facing_curving``: every take turned to start facing anywhere (uniform in -180..180 degrees) and
  to curve, its heading drifting steadily by up to 20 degrees either way over the take (the body
  turned frame by frame about its pelvis, the pelvis's path following its turned velocity);
- ``trimmed``: each take cut at both ends by 0.3 to 0.7 s (not whole gait cycles), at most
  :data:`TRIM_SHARE` of the take at each end (a one-stride loop loses part of its stride);
- ``jitter``: every joint's rotation on every frame turned by a random rotation of about 1 degree
  (root-mean-square angle), as marker noise does;
- ``two_speeds``: only the slowest and the fastest of the takes that walk forward;
- ``no_runs``: takes whose pelvis travels faster than :data:`RUN_M_S` left out;
- ``mirrored``: every take mirrored left for right (the left joints moving as the right ones did,
  mirrored through the body's middle plane), names kept (a take named as walking left walks right);
- ``cadences``: each take played faster or slower (factors 0.85 to 1.15 spread over the takes), so the
  takes step at different cadences than the set's;
- ``fps_25``: every take resampled to 25 fps (PAL video's rate);
- ``t_pose_start``: each take begins with :data:`T_POSE_S` of the skeleton's rest pose (a T-pose, as
  capture sessions calibrate with), standing where the take starts, then cuts to the take;
- ``one_speed``: of the takes that walk forward, only the one nearest :data:`ONE_SPEED_M_S`; every take
  that does anything else kept.

Times are seconds, distances metres, angles degrees; the core frame is +Y up, +Z forward, +X left.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

import infuse
from infuse import Asset, Motion, Skeleton
from infuse import quaternions as quat
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from skeleton_variants import CONVENTIONS, _convention_name

#: Takes whose pelvis travels faster than this (m/s) are runs.
RUN_M_S = 2.0
#: Heading drift over a take is at most this (degrees).
MAX_DRIFT_DEG = 20.0
#: Rotation noise per joint and frame, root-mean-square angle (degrees).
JITTER_DEG = 1.0
#: Seconds cut from each end of a take, from .. to.
TRIM_S = (0.3, 0.7)
#: At most this share of a take is cut at each end.
TRIM_SHARE = 0.1
#: Playback speed factors of the ``cadences`` variant, spread over the takes.
CADENCE_FACTORS = (0.85, 1.15)
#: Seconds of rest pose before each take of the ``t_pose_start`` variant.
T_POSE_S = 0.5
#: The walking speed (m/s) whose nearest forward take the ``one_speed`` variant keeps.
ONE_SPEED_M_S = 1.3
SIX_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
_UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class MotionSet:
    """Takes on one skeleton (identity rest rotations once written), written in ``units`` with ``up_axis``."""

    name: str
    skeleton: Skeleton
    takes: dict
    units: str = "cm"
    up_axis: str = "Y"


def read_set(files, name: str) -> MotionSet:
    """A set of BVH takes (paths) sharing one hierarchy; the skeleton is the first file's."""
    assets = [infuse.load(f) for f in files]
    skeleton = assets[0].skeleton
    takes = {Path(f).stem: next(iter(a.motions.values())).replace(name=Path(f).stem, skeleton=skeleton)
             for f, a in zip(files, assets)}
    return MotionSet(name, skeleton, takes, assets[0].source_units, assets[0].source_up_axis)


def write_set(motion_set: MotionSet, folder) -> Path:
    """Write every take as ``folder/<take>.bvh`` (six channels on every joint, the set's unit and up axis)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    channels = {n: SIX_CHANNELS for n in motion_set.skeleton.names}
    for take, motion in motion_set.takes.items():
        asset = Asset(path=None, format="bvh", skeleton=motion_set.skeleton, motions={take: motion},
                      source_units=motion_set.units, source_up_axis=motion_set.up_axis, meta={"channels": channels})
        infuse.save(asset, folder / f"{take}.bvh", format="bvh")
    return folder


def _mapping(motion_set: MotionSet) -> dict:
    """Canonical name -> joint index of the set's skeleton."""
    index = motion_set.skeleton.index
    return {k: index[v] for k, v in map_skeleton(motion_set.skeleton).joints.items() if v is not None}


def _each(motion_set: MotionSet, name: str, change) -> MotionSet:
    return replace(motion_set, name=name, takes={k: change(m) for k, m in motion_set.takes.items()})


def sample(motion: Motion, source_frames: np.ndarray, fps: float) -> Motion:
    """``motion`` sampled at fractional frame indices ``source_frames`` (N,), played at ``fps``."""
    f = np.clip(source_frames, 0.0, motion.num_frames - 1)
    lo = np.floor(f).astype(int)
    hi = np.minimum(lo + 1, motion.num_frames - 1)
    t = f - lo
    rot = quat.slerp(motion.local_rotations[lo], motion.local_rotations[hi], t[:, None])
    trans = motion.local_translations()
    lerp = trans[lo] + (trans[hi] - trans[lo]) * t[:, None, None]
    return motion.replace(fps=fps, local_rotations=rot, root_translations=lerp[:, 0],
                          joint_translations=lerp if motion.joint_translations is not None else None)


def resampled(motion_set: MotionSet, fps: float) -> MotionSet:
    def change(m: Motion) -> Motion:
        return sample(m, np.arange(0.0, m.duration + 1e-9, 1.0 / fps) * m.fps, fps)
    return _each(motion_set, f"fps_{fps:g}", change)


def other_unit(motion_set: MotionSet) -> MotionSet:
    return replace(motion_set, name="metres", units="m" if motion_set.units != "m" else "cm")


def z_up(motion_set: MotionSet) -> MotionSet:
    return replace(motion_set, name="z_up", up_axis="Z")


def renamed(motion_set: MotionSet) -> MotionSet:
    """Mapped joints named as Mixamo names them; the others behind Mixamo's namespace."""
    sk = motion_set.skeleton
    canonical = {j: k for k, j in _mapping(motion_set).items()}

    def name(j: int, original: str) -> str:
        try:
            return _convention_name(CONVENTIONS["mixamo"], canonical[j])
        except KeyError:  # unmapped, or a joint the convention has no name for (an eyelid)
            return f"mixamorig:{original}"
    names = tuple(name(j, n) for j, n in enumerate(sk.names))
    skeleton = Skeleton(names, sk.parents, sk.rest_translations, sk.rest_rotations, sk.end_site_parents, sk.end_site_offsets)
    return replace(motion_set, name="renamed", skeleton=skeleton,
                   takes={k: m.replace(skeleton=skeleton) for k, m in motion_set.takes.items()})


def a_pose(motion_set: MotionSet, elevation_deg: float = -45.0) -> MotionSet:
    """Each upper arm's rest turned about the body's forward axis until its shoulder-to-hand line is
    ``elevation_deg`` above the horizontal; motions keep their local rotations, so every joint moves as
    before and only the rest (hence the file's offsets and channels) changes."""
    sk, m = motion_set.skeleton, _mapping(motion_set)
    pos, rest = sk.rest_global_positions, sk.rest_global_rotations
    left = pos[m["l_shoulder"]] - pos[m["r_shoulder"]]
    left = left - (left @ _UP) * _UP
    left /= np.linalg.norm(left)
    forward = np.cross(left, _UP)
    local = sk.rest_rotations.copy()
    for side, outward in (("l", left), ("r", -left)):
        shoulder = m[f"{side}_shoulder"]
        d = pos[m.get(f"{side}_wrist", m[f"{side}_elbow"])] - pos[shoulder]
        turn = np.radians(elevation_deg) - np.arctan2(d @ _UP, d @ outward)
        world = quat.from_axis_angle(forward, turn if side == "l" else -turn)
        parent = rest[sk.parents[shoulder]]
        local[shoulder] = quat.multiply(quat.multiply(quat.conjugate(parent), quat.multiply(world, parent)), local[shoulder])
    skeleton = sk.with_rest(rest_rotations=local)
    return replace(motion_set, name="a_pose", skeleton=skeleton,
                   takes={k: t.replace(skeleton=skeleton) for k, t in motion_set.takes.items()})


def _turned_about_pelvis(motion: Motion, pelvis: int, yaw: np.ndarray) -> Motion:
    """The body turned about +Y by ``yaw`` (F,) radians on each frame about its pelvis, the pelvis's ground
    path following its velocity turned by the same angle (heights kept). Everything hangs from joint 0."""
    _, g_pos = motion_fk(motion)
    ground = g_pos[:, pelvis] * [1.0, 0.0, 1.0]
    turn = quat.from_axis_angle(_UP, yaw)
    step = quat.rotate(turn[1:], np.diff(ground, axis=0))
    path = np.concatenate((ground[:1], ground[0] + np.cumsum(step, axis=0)))
    root = motion.root_translations
    rotations = motion.local_rotations.copy()
    rotations[:, 0] = quat.multiply(turn, rotations[:, 0])
    return motion.replace(local_rotations=rotations, root_translations=path + quat.rotate(turn, root - ground))


def facing_curving(motion_set: MotionSet, rng: np.random.Generator) -> MotionSet:
    pelvis = _mapping(motion_set)["base"]

    def change(m: Motion) -> Motion:
        start = rng.uniform(-np.pi, np.pi)
        drift = np.radians(rng.uniform(-MAX_DRIFT_DEG, MAX_DRIFT_DEG))
        return _turned_about_pelvis(m, pelvis, start + drift * np.linspace(0.0, 1.0, m.num_frames))
    return _each(motion_set, "facing_curving", change)


def trimmed(motion_set: MotionSet, rng: np.random.Generator) -> MotionSet:
    def change(m: Motion) -> Motion:
        cut = np.round(np.minimum(rng.uniform(*TRIM_S, size=2), TRIM_SHARE * m.duration) * m.fps).astype(int)
        return sample(m, np.arange(cut[0], m.num_frames - cut[1], dtype=np.float64), m.fps)
    return _each(motion_set, "trimmed", change)


def jitter(motion_set: MotionSet, rng: np.random.Generator) -> MotionSet:
    def change(m: Motion) -> Motion:
        noise = quat.from_rotvec(rng.normal(0.0, np.radians(JITTER_DEG) / np.sqrt(3.0), m.local_rotations.shape[:2] + (3,)))
        return m.replace(local_rotations=quat.multiply(m.local_rotations, noise))
    return _each(motion_set, "jitter", change)


def take_velocities(motion_set: MotionSet) -> dict:
    """Take -> (along, across) its first facing, m/s: the pelvis's net ground travel over the take."""
    m = _mapping(motion_set)
    out = {}
    for take, motion in motion_set.takes.items():
        _, g_pos = motion_fk(motion)
        travel = (g_pos[-1, m["base"]] - g_pos[0, m["base"]]) / motion.duration
        left = g_pos[0, m["l_hip"]] - g_pos[0, m["r_hip"]]
        forward = np.cross(left, _UP)
        forward /= np.linalg.norm(forward)
        out[take] = (float(travel @ forward), float(np.linalg.norm(travel - (travel @ forward) * forward - travel[1] * _UP)))
    return out


def two_speeds(motion_set: MotionSet) -> MotionSet:
    """The slowest and fastest forward takes (travel within 30 degrees of the facing) only."""
    velocity = take_velocities(motion_set)
    ahead = sorted((v[0], k) for k, v in velocity.items() if v[0] > 0.0 and v[1] < 0.58 * v[0])
    keep = {ahead[0][1], ahead[-1][1]}
    return replace(motion_set, name="two_speeds", takes={k: m for k, m in motion_set.takes.items() if k in keep})


def no_runs(motion_set: MotionSet) -> MotionSet:
    velocity = take_velocities(motion_set)
    return replace(motion_set, name="no_runs",
                   takes={k: m for k, m in motion_set.takes.items() if np.hypot(*velocity[k]) <= RUN_M_S})


def mirrored(motion_set: MotionSet) -> MotionSet:
    """Left and right swapped through the plane x = 0 of the core frame (rest rotations must be identity,
    as a set read from BVH or SmartBody has them)."""
    if not np.allclose(np.abs(motion_set.skeleton.rest_rotations[:, 3]), 1.0):
        raise ValueError(f"{motion_set.name}: mirroring needs identity rest rotations")
    m = _mapping(motion_set)
    partner = np.arange(motion_set.skeleton.num_joints)
    for k, j in m.items():
        if k.startswith("l_") and f"r_{k[2:]}" in m:
            partner[j], partner[m[f"r_{k[2:]}"]] = m[f"r_{k[2:]}"], j
    flip = np.array([-1.0, 1.0, 1.0])
    flip_q = np.array([1.0, -1.0, -1.0, 1.0])

    def change(t: Motion) -> Motion:
        trans = t.local_translations()[:, partner] * flip
        return t.replace(local_rotations=t.local_rotations[:, partner] * flip_q, root_translations=trans[:, 0],
                         joint_translations=trans if t.joint_translations is not None else None)
    sk = motion_set.skeleton
    skeleton = sk.with_rest(rest_translations=sk.rest_translations[partner] * flip)
    takes = {k: change(t.replace(skeleton=skeleton)) for k, t in motion_set.takes.items()}
    return replace(motion_set, name="mirrored", skeleton=skeleton, takes=takes)


def cadences(motion_set: MotionSet) -> MotionSet:
    factors = np.linspace(*CADENCE_FACTORS, len(motion_set.takes))
    order = np.argsort(np.arange(len(factors)) * 7 % len(factors))  # spread: neighbours differ

    def played(m: Motion, factor: float) -> Motion:
        return sample(m, np.arange(0.0, m.duration * m.fps / factor + 1e-9) * factor, m.fps)
    takes = {k: played(m, float(f)) for (k, m), f in zip(motion_set.takes.items(), factors[order])}
    return replace(motion_set, name="cadences", takes=takes)


def t_pose_start(motion_set: MotionSet) -> MotionSet:
    """Each take preceded by :data:`T_POSE_S` of the rest pose (every joint at its rest rotation, the root
    where the take's first frame has it, its height the rest pose's)."""
    sk = motion_set.skeleton

    def change(m: Motion) -> Motion:
        n = int(round(T_POSE_S * m.fps))
        rest = np.repeat(sk.rest_rotations[None], n, axis=0)
        root = np.repeat(m.root_translations[:1], n, axis=0)
        root[:, 1] = sk.rest_translations[0, 1]
        trans = None
        if m.joint_translations is not None:
            trans = np.concatenate((np.repeat(sk.rest_translations[None], n, axis=0), m.joint_translations))
            trans[:n, 0] = root
        return m.replace(local_rotations=np.concatenate((rest, m.local_rotations)),
                         root_translations=np.concatenate((root, m.root_translations)), joint_translations=trans)
    return _each(motion_set, "t_pose_start", change)


def one_speed(motion_set: MotionSet) -> MotionSet:
    """Of the forward takes (travel within 30 degrees of the facing), only the one nearest
    :data:`ONE_SPEED_M_S`; the other takes kept."""
    velocity = take_velocities(motion_set)
    ahead = [k for k, v in velocity.items() if v[0] > 0.3 and v[1] < 0.58 * v[0]]
    keep = min(ahead, key=lambda k: abs(velocity[k][0] - ONE_SPEED_M_S))
    return replace(motion_set, name="one_speed",
                   takes={k: m for k, m in motion_set.takes.items() if k == keep or k not in ahead})


#: Variant name -> function of (set, random generator) -> set.
VARIANTS = {
    "fps_24": lambda s, rng: resampled(s, 24.0),
    "fps_50": lambda s, rng: resampled(s, 50.0),
    "fps_120": lambda s, rng: resampled(s, 120.0),
    "metres": lambda s, rng: other_unit(s),
    "z_up": lambda s, rng: z_up(s),
    "renamed": lambda s, rng: renamed(s),
    "a_pose": lambda s, rng: a_pose(s),
    "facing_curving": facing_curving,
    "trimmed": trimmed,
    "jitter": jitter,
    "two_speeds": lambda s, rng: two_speeds(s),
    "no_runs": lambda s, rng: no_runs(s),
    "mirrored": lambda s, rng: mirrored(s),
    "cadences": lambda s, rng: cadences(s),
    "fps_25": lambda s, rng: resampled(s, 25.0),
    "t_pose_start": lambda s, rng: t_pose_start(s),
    "one_speed": lambda s, rng: one_speed(s),
}


def variant(motion_set: MotionSet, name: str, seed: int = 0) -> MotionSet:
    """The variant ``name`` of :data:`VARIANTS` (random choices from ``seed``)."""
    return VARIANTS[name](motion_set, np.random.default_rng(seed))
