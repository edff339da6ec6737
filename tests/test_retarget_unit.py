"""Retargeting on synthetic skeletons: the maths, any-to-any structure, IK, goals, bad input."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import metrics
from infuse import quaternions as quat
from infuse.canonical import BODY_NAMES
from infuse.contacts import FootContacts, clean_runs, detect
from infuse.errors import UnusableInputError, UsageError
from infuse_retarget import RetargetPlan, retarget, retarget_clip
from infuse_retarget import cq, goals, ik
from infuse_retarget.frames import reorient, to_canonical, unorient
from infuse_retarget.rig import canonical_parent
from retarget_helpers import (a_pose, canonical, from_globals, identity_map, inserted, parts, reframed, removed,
                              renamed, smooth_clip)

RNG = np.random.default_rng(7)


def jm(a):
    """(F, n) -> (n, F) component-major."""
    return np.ascontiguousarray(np.asarray(a).T)


# -- component-major maths -----------------------------------------------------------------------
def test_cq_matches_core_quaternions():
    a = quat.normalize(RNG.normal(size=(50, 4)))
    b = quat.normalize(RNG.normal(size=(50, 4)))
    v = RNG.normal(size=(50, 3))
    assert np.allclose(cq.mul(jm(a), jm(b)).T, quat.multiply(a, b))
    assert np.allclose(cq.mul_inv(jm(a), jm(b)).T, quat.multiply(quat.conjugate(a), b))
    assert np.allclose(cq.rotate(jm(a), jm(v)).T, quat.rotate(a, v))
    u = RNG.normal(size=(50, 3))
    q = cq.between(jm(u), jm(v)).T
    assert np.allclose(quat.rotate(q, u / np.linalg.norm(u, axis=1, keepdims=True)), v / np.linalg.norm(v, axis=1, keepdims=True))
    opposite = cq.between(jm(u), jm(-u)).T
    assert np.allclose(quat.rotate(opposite, u), -u)
    omega = RNG.normal(size=(50, 3))
    assert np.allclose(quat.angle_between(cq.exp(jm(omega)).T, quat.from_rotvec(omega)), 0.0, atol=1e-9)
    assert np.allclose(cq.exp(cq.log(jm(a))).T, quat.canonical_sign(a))


def test_twist_power_takes_a_share_of_the_twist_only():
    axis = np.array([1.0, 0.0, 0.0])
    twist = quat.from_axis_angle(axis, 1.2)
    swing = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.4)
    q = quat.multiply(swing, twist)
    half = cq.twist_power(q[None, :, None], axis[None, :, None], np.array([[0.5]]))[0, :, 0]
    assert np.isclose(quat.angle_between(half, quat.from_axis_angle(axis, 0.6)), 0.0, atol=1e-9)


def test_make_continuous_removes_sign_flips():
    q = quat.normalize(np.cumsum(RNG.normal(scale=0.05, size=(100, 4)), axis=0) + [0, 0, 0, 1])
    flipped = np.where(RNG.random((100, 1)) < 0.4, -q, q)
    out = cq.make_continuous(jm(flipped)[None])[0].T
    assert np.all(np.sum(out[1:] * out[:-1], axis=1) > 0)
    assert np.allclose(quat.angle_between(out, q), 0.0, atol=1e-7)


def test_paper_reorientation_round_trip():
    q, q_init, r_g = (quat.normalize(RNG.normal(size=(20, 4))) for _ in range(3))
    assert np.allclose(quat.angle_between(unorient(reorient(q, q_init, r_g), q_init, r_g), q), 0.0, atol=1e-7)
    # The identity in the canonical frame is the default local rotation.
    assert np.allclose(quat.angle_between(reorient(quat.identity((20,)), q_init, r_g), q_init), 0.0, atol=1e-7)


# -- any-to-any transfer -------------------------------------------------------------------------
def _positions(motion):
    return infuse.motion_fk(motion)[1]


def _same_mapped_positions(src_motion, src_map, out_motion, out_map, names=None, atol=1e-6):
    ps, po = _positions(src_motion), _positions(out_motion)
    names = [n for n in (names or src_map) if n in src_map and n in out_map]
    a = [src_motion.skeleton.index[src_map[n]] for n in names]
    b = [out_motion.skeleton.index[out_map[n]] for n in names]
    err = np.linalg.norm(ps[:, a] - po[:, b], axis=-1)
    assert err.max() < atol, (names[int(np.argmax(err.max(axis=0)))], err.max())


@pytest.fixture(scope="module")
def source():
    sk = canonical()
    return smooth_clip(sk), identity_map(sk)


@pytest.mark.parametrize("variant", ["self", "other local frames", "A-pose", "facing -Z", "renamed"])
def test_same_body_gives_the_same_motion(source, variant):
    """Whatever a target's rest frames, rest pose, facing or names, the same body moves identically."""
    clip, cmap = source
    sk = clip.skeleton
    tmap = identity_map(sk)
    target = {"self": sk, "other local frames": reframed(sk), "A-pose": a_pose(sk),
              "facing -Z": sk.transformed(rotation=quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi))}.get(variant)
    if variant == "renamed":
        target, tmap = renamed(reframed(a_pose(sk), seed=3), "joint")
    out = retarget(clip, cmap, target, tmap, ik="none")
    assert out.skeleton is target and out.num_frames == clip.num_frames
    _same_mapped_positions(clip, cmap, out, tmap)


def test_scaled_body_scales_the_root_path_and_keeps_directions(source):
    clip, cmap = source
    target = clip.skeleton.transformed(scale=0.5)
    plan = RetargetPlan(clip.skeleton, cmap, target, cmap)
    assert plan.scale == pytest.approx(0.5, rel=1e-9)
    out = retarget_clip(plan, clip, ik="none").motion
    ps, po = _positions(clip), _positions(out)
    idx = {n: j for j, n in enumerate(clip.skeleton.names)}
    agreement = metrics.bone_directions(ps, idx, po, idx)
    assert agreement.worst < 1e-5
    travel_s = ps[-1, 0, [0, 2]] - ps[0, 0, [0, 2]]
    travel_o = po[-1, 0, [0, 2]] - po[0, 0, [0, 2]]
    assert np.allclose(travel_o, 0.5 * travel_s, atol=1e-9)


@pytest.mark.parametrize("variant", ["5-joint spine", "twist joints", "missing clavicles", "2-joint spine source"])
def test_extra_and_missing_joints_keep_bone_directions(source, variant):
    clip, cmap = source
    sk = clip.skeleton
    if variant == "5-joint spine":
        target = inserted(inserted(sk, "spine1", "spine2", "spine1b"), "spine2", "spine3", "spine2b", 0.3)
    elif variant == "twist joints":
        target = inserted(inserted(sk, "l_elbow", "l_forearm", "l_elbow_twist"), "l_hip", "l_knee", "l_thigh_twist")
    elif variant == "missing clavicles":
        target = removed(removed(sk, "l_acromioclavicular"), "r_acromioclavicular")
    else:  # the source has fewer joints than the target
        small = removed(removed(sk, "spine2"), "spine5")
        src_map = identity_map(small)
        small_clip = smooth_clip(small, seed=4)
        out = retarget(small_clip, src_map, sk, cmap, ik="none")
        agreement = metrics.bone_directions(_positions(small_clip), {n: small.index[n] for n in small.names},
                                            _positions(out), {n: sk.index[n] for n in sk.names})
        # The target's extra spine joints take a share of the twist about an axis they lie just off.
        assert agreement.worst < 0.5, agreement.per_bone
        return
    tmap = {n: n for n in target.names if n in sk.index}
    out = retarget(clip, cmap, target, tmap, ik="none")
    agreement = metrics.bone_directions(_positions(clip), {n: sk.index[n] for n in sk.names},
                                        _positions(out), {n: target.index[n] for n in tmap})
    limbs = {bone: angle for bone, angle in agreement.per_bone.items() if bone != "r_shoulder->l_shoulder"}
    assert max(limbs.values()) < 1e-5, agreement.per_bone
    if variant == "missing clavicles":  # shoulders fixed to the chest cannot follow a shrug
        assert agreement.per_bone["r_shoulder->l_shoulder"] > 1.0
    else:  # inserted joints lie on their bones: mapped joints land exactly
        _same_mapped_positions(clip, cmap, out, tmap)


def test_twist_joints_share_the_wrist_twist():
    sk = canonical()
    target = inserted(sk, "l_forearm", "l_wrist", "l_forearm_twist", 0.5)
    frames = 10
    rot = np.broadcast_to(sk.rest_rotations, (frames, sk.num_joints, 4)).copy()
    angle = np.linspace(0.0, 1.2, frames)
    rot[:, sk.index["l_wrist"]] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), angle)  # about the forearm
    clip = infuse.Motion(sk, 30.0, rot, np.broadcast_to(sk.rest_translations[0], (frames, 3)))
    out = retarget(clip, identity_map(sk), target, {n: n for n in sk.names}, ik="none")
    g = infuse.motion_fk(out)[0]
    twist = quat.angle_between(g[:, target.index["l_forearm_twist"]], g[:, target.index["l_forearm"]])
    wrist = quat.angle_between(g[:, target.index["l_wrist"]], g[:, target.index["l_forearm"]])
    # The twist joint sits at 1/4 of the forearm-to-wrist chain... of the path from the driver.
    assert np.allclose(wrist, angle, atol=1e-7)
    assert np.all(twist > 0.2 * angle - 1e-9) and np.all(twist < 0.8 * angle + 1e-9)


def test_paper_formula_reproduces_the_plan_on_matching_hierarchies(source):
    """q' = q_init·R_G⁻¹·q·R_G on a canonical-frame clip gives the plan's local rotations."""
    clip, cmap = source
    canonical_clip = to_canonical(clip, cmap)
    target = reframed(a_pose(clip.skeleton), seed=5)
    plan = RetargetPlan(canonical_clip.skeleton, identity_map(canonical_clip.skeleton), target, identity_map(target))
    out = retarget_clip(plan, canonical_clip, ik="none").motion
    t = plan.target
    checked = 0
    for name in plan.common:
        parent = canonical_parent(name, t.index)
        if parent is None or target.parents[t.index[name]] != t.index[parent]:
            continue
        q = canonical_clip.local_rotations[:, canonical_clip.skeleton.index[name]]
        q_init = quat.multiply(quat.conjugate(t.frame[t.index[parent]]), t.frame[t.index[name]])
        expected = reorient(q, q_init, t.frame[t.index[name]])
        assert np.allclose(quat.angle_between(expected, out.local_rotations[:, t.index[name]]), 0.0, atol=1e-6), name
        checked += 1
    assert checked > 60


def test_canonical_clip_keeps_the_motion(source):
    clip, cmap = source
    canonical_clip = to_canonical(clip, cmap)
    assert canonical_clip.skeleton.names[0] == "base" and canonical_clip.num_frames == clip.num_frames
    _same_mapped_positions(clip, cmap, canonical_clip, identity_map(canonical_clip.skeleton))


def test_detached_feet_follow_the_knee(source):
    """A rig whose feet hang from the ground root (IK-driven feet) gets translated feet at the shins' ends."""
    clip, cmap = source
    names, parents, rots, pos = parts(clip.skeleton)
    names.append("ground")
    parents.append(None)
    rots.append(quat.IDENTITY)
    pos.append(np.zeros(3))
    parents[names.index("base")] = "ground"
    for side in "lr":
        parents[names.index(f"{side}_ankle")] = "ground"
    target = from_globals(names, parents, rots, pos)
    out = retarget(clip, cmap, target, identity_map(clip.skeleton), ik="none")
    assert out.joint_translations is not None
    _same_mapped_positions(clip, cmap, out, identity_map(clip.skeleton))


def test_ancestors_of_the_base_hold_their_pose(source):
    clip, cmap = source
    names, parents, rots, pos = parts(clip.skeleton)
    names.append("root")
    parents.append(None)
    rots.append(quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), -np.pi / 2))  # a Z-up armature node
    pos.append(np.zeros(3))
    parents[names.index("base")] = "root"
    target = from_globals(names, parents, rots, pos)
    out = retarget(clip, cmap, target, identity_map(clip.skeleton), ik="none")
    root = target.index["root"]
    assert np.allclose(out.local_rotations[:, root], target.rest_rotations[root])
    _same_mapped_positions(clip, cmap, out, identity_map(clip.skeleton))


# -- the foot's aim at its ball ---------------------------------------------------------------------
def test_aim_turns_the_foot_onto_its_goal_and_keeps_its_roll():
    frames = 30
    pivot = np.zeros((3, frames))
    point = np.tile([[0.0], [-0.05], [0.15]], frames)
    goal = np.tile([[0.05], [-0.1], [0.12]], frames)
    goal = goal / cq.norm(goal) * cq.norm(point)
    turn, moved = ik.aim(pivot, point, goal, np.tile([[0.0], [0.0], [0.0], [1.0]], frames))
    assert np.allclose(moved, goal, atol=1e-5)
    shortest = cq.between(point, goal)
    assert np.allclose(quat.angle_between(turn.T, shortest.T), 0.0, atol=1e-4)


# -- goals -----------------------------------------------------------------------------------------
def test_warp_is_the_papers_recurrence():
    source = RNG.normal(size=(3, 40))
    start = RNG.normal(size=3)
    out = goals.warp(start, source, 1.7)
    recurrence = [start]
    for k in range(1, 40):
        recurrence.append(recurrence[-1] + 1.7 * (source[:, k] - source[:, k - 1]))
    assert np.allclose(out, np.array(recurrence).T)


# -- contacts and metrics --------------------------------------------------------------------------
def test_contacts_from_speed_and_height():
    fps, leg = 30.0, 0.8
    frames = 90
    y = np.where((np.arange(frames) // 30) % 2 == 0, 0.05, 0.3)
    z = np.cumsum(np.where(y > 0.1, 0.05, 0.0))
    points = np.stack((np.zeros(frames), y, z), axis=1)[:, None]
    flags = detect(points, fps, leg, ground=0.05)[:, 0]
    assert flags[3:27].all() and not flags[33:57].any() and flags[63:87].all()
    assert np.array_equal(clean_runs(np.array([[1], [0], [1], [1], [0], [0], [0], [1]], bool), 2)[:, 0],
                          [True, True, True, True, False, False, False, False])


def test_skate_counts_travel_while_planted():
    frames = 11
    pos = np.zeros((frames, 2, 3))
    pos[:, 0, 2] = np.linspace(0.0, 1.0, frames)  # the root walks 1 m
    pos[:, 1, 2] = np.linspace(0.0, 0.1, frames)  # the foot slides 10 cm, planted throughout
    contacts = FootContacts(np.array([1]), np.array([0]), np.ones((frames, 1), bool), 0.0, 1.0, np.zeros((frames, 2)))
    skate = metrics.foot_skate(pos, contacts, root=0)
    assert skate.per_metre == pytest.approx(10.0)


# -- bad input -------------------------------------------------------------------------------------
def test_unmappable_zero_length_and_mismatched_input_are_typed_errors(source):
    clip, cmap = source
    sk = clip.skeleton
    legless = {n: j for n, j in cmap.items() if "knee" not in n}
    with pytest.raises(UnusableInputError, match="lacks l_knee"):
        RetargetPlan(sk, legless, sk, cmap)
    names, parents, rots, pos = parts(sk)
    pos = np.array(pos)
    for side in "lr":
        for n in ("knee", "ankle", "forefoot", "toe"):
            pos[names.index(f"{side}_{n}")] = pos[names.index(f"{side}_hip")]
    flat = from_globals(names, parents, rots, pos)
    with pytest.raises(UnusableInputError, match="zero-length leg"):
        RetargetPlan(sk, cmap, flat, identity_map(flat))
    plan = RetargetPlan(sk, cmap, sk, cmap)
    other = smooth_clip(removed(sk, "spine2"))
    with pytest.raises(UsageError):
        retarget_clip(plan, other)
    with pytest.raises(UsageError):
        retarget_clip(plan, clip, ik="sometimes")
    with pytest.raises(infuse.InputError, match="not finite"):
        infuse.Motion(sk, 30.0, np.full((2, sk.num_joints, 4), np.nan), np.zeros((2, 3)))


def test_retargeters_are_registered():
    from infuse import registry

    table = registry.retargeters()
    assert {"default", "paper"} <= set(table)
    sk = canonical()
    clip = smooth_clip(sk, frames=20)
    out = table["paper"].retarget(clip, identity_map(sk), reframed(sk), identity_map(sk))
    assert out.num_frames == 20


def test_body_names_are_canonical():
    assert set(BODY_NAMES) <= set(canonical().names)
