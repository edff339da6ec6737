"""The batched paths the locomotion controller takes give what the one-at-a-time paths give: several
looping clips sampled in one gather, several clips' foot phases at once, limb IK given the limbs'
global frames or an end rotation to take, weights written only where they fall within the hull."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from infuse import Motion
from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.packs import Tessellation
from infuse.runtime import sample_motion
from infuse.runtime.clip import LoopTable
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk

from runtime_characters import synthetic_character

rng = np.random.default_rng(11)


def random_motion(sk, frames: int, seed: int, translations: bool) -> Motion:
    rot = Rotation.random(frames * sk.num_joints, random_state=seed).as_quat().reshape(frames, sk.num_joints, 4)
    jt = None
    if translations:
        jt = np.repeat(sk.rest_translations[None], frames, axis=0) + 0.01 * rng.normal(size=(frames, sk.num_joints, 3))
    return Motion(sk, 30.0, rot, rng.normal(size=(frames, 3)), joint_translations=jt, name=f"m{seed}")


@pytest.mark.parametrize("translations", [False, True])
def test_a_loop_table_samples_each_motion_as_sample_motion_does(translations):
    sk = synthetic_character().skeleton
    motions = [random_motion(sk, frames, seed, translations) for seed, frames in enumerate((12, 31, 2, 1))]
    table = LoopTable(motions)
    sets = rng.integers(0, 3, size=sk.num_joints)
    sets[0] = 1  # the root follows joint 0's times
    which = np.array([1, 0, 3, 1, 2])
    times = rng.uniform(-2.0, 5.0, size=(len(which), 3, 20))
    times[3, 2] = np.arange(20) / 30.0  # a set on the motion's own frames: held, not interpolated
    rot, root, jt = table.sample(which, times, sets)
    assert rot.shape == (4, len(which), 20, sk.num_joints) and root.shape == (3, len(which), 20)
    # Component-major samples, frame-major as sample_motion gives them.
    rot, root = np.moveaxis(rot, 0, -1), np.moveaxis(root, 0, -1)
    jt = None if jt is None else np.moveaxis(jt, 0, -1)
    for u, i in enumerate(which):
        m = motions[i]
        for s in range(3):
            r, p, j, _ = sample_motion(m, times[u, s] % max(m.duration, 1e-9), loop=True)
            cols = np.nonzero(sets == s)[0]
            # The table interpolates on sign-continuous rotations: the same rotations, signs aside.
            side = np.sign(np.sum(rot[u][:, cols] * r[:, cols], axis=-1, keepdims=True))
            assert np.allclose(rot[u][:, cols] * side, r[:, cols], rtol=0.0, atol=1e-12)
            if s == sets[0]:
                assert np.allclose(root[u], p, rtol=0.0, atol=1e-12)
            if translations:
                assert np.allclose(jt[u][:, cols], j[:, cols], rtol=0.0, atol=1e-12)
    assert (jt is None) == (not translations)


def test_several_clips_foot_phases_and_times_at_once():
    from infuse_locomotion.phase_keys import foot_phase, warp

    mine = np.sort(rng.uniform(size=(3, 2, 4)), axis=2)
    theirs = np.sort(rng.uniform(size=(40, 2, 4)), axis=2)
    phase = rng.uniform(size=40)
    keys = np.sort(rng.uniform(0.0, 2.0, size=(3, 3)), axis=1)
    clips = foot_phase(mine, theirs, phase)
    assert clips.shape == (3, 40, 2)
    times = warp(keys[:, None, None], clips)
    for u in range(3):
        assert np.array_equal(clips[u], foot_phase(mine[u], theirs, phase))
        assert np.array_equal(times[u], warp(keys[u], clips[u]))
    assert np.array_equal(warp(keys[:, None], phase)[1], warp(keys[1], phase))


def legs():
    """A pelvis with two legs (hip, knee, ankle, toe)."""
    from infuse.skeleton import Skeleton

    names = ["pelvis", "l_hip", "l_knee", "l_ankle", "l_toe", "r_hip", "r_knee", "r_ankle", "r_toe"]
    parents = [-1, 0, 1, 2, 3, 0, 5, 6, 7]
    offsets = [[0, 1.0, 0], [0.1, 0, 0], [0, -0.45, 0], [0, -0.4, 0], [0, -0.05, 0.12],
               [-0.1, 0, 0], [0, -0.45, 0], [0, -0.4, 0], [0, -0.05, 0.12]]
    sk = Skeleton(names, np.array(parents), np.array(offsets, dtype=float), quat.identity((len(names),)))
    return sk, [(1, 2, 3), (5, 6, 7)]


def test_limb_ik_given_the_limbs_frames_or_an_end_rotation():
    sk, limbs = legs()
    frames = 30
    local = quat.normalize(np.array([0.0, 0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=(frames, sk.num_joints, 4)))
    root = rng.normal(size=(frames, 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [3, 7]] + 0.1 * rng.normal(size=(frames, 2, 3))
    weight = (rng.uniform(size=(frames, 2)) > 0.3).astype(float)
    plain, given = local.copy(), local.copy()
    g_rot, g_pos = chain_fk(sk, local, root, None, [1, 2, 3, 0, 5, 6, 7, 0])
    chains = (g_rot.reshape(frames, 2, 4, 4), g_pos.reshape(frames, 2, 4, 3))
    left = solve_limb(sk, plain, root, None, limbs, goals, weight=weight)
    assert np.allclose(solve_limb(sk, given, root, None, limbs, goals, weight=weight, chains=chains), left, atol=1e-12)
    assert np.allclose(given, plain, rtol=0.0, atol=1e-12)
    # An end rotation to take: as solving without keeping the end, then setting it under its new parent.
    feet = quat.normalize(rng.normal(size=(frames, 2, 4)))
    turned, after = local.copy(), local.copy()
    solve_limb(sk, turned, root, None, limbs, goals, weight=weight, end_rotation=feet)
    solve_limb(sk, after, root, None, limbs, goals, weight=weight, keep_end=False)
    parents, _ = chain_fk(sk, after, root, None, [2, 6])
    for k, (_, _, ankle) in enumerate(limbs):
        after[:, ankle] = quat.multiply(quat.conjugate(parents[:, k]), feet[:, k])
    assert np.allclose(np.abs(np.sum(turned * after, axis=-1)), 1.0, rtol=0.0, atol=1e-12)
    g_rot, _ = chain_fk(sk, turned, root, None, [3, 7])
    assert np.allclose(np.abs(np.sum(g_rot * feet, axis=-1)), 1.0, rtol=0.0, atol=1e-12)
    # Without the distance left: the same pose.
    quiet = local.copy()
    assert solve_limb(sk, quiet, root, None, limbs, goals, weight=weight, end_rotation=feet, distance=False) is None
    assert np.array_equal(quiet, turned)
    # Weights of 0 and 1 only: the solved pose on the frames of weight 1, the pose as it was elsewhere.
    untouched = weight == 0.0
    assert np.array_equal(plain[:, [1, 2]][untouched[:, 0]], local[:, [1, 2]][untouched[:, 0]])


def test_tessellation_weights_inside_and_outside_the_hull():
    points = rng.uniform(size=(9, 3))
    t = Tessellation.build(("a", "b", "c"), [str(i) for i in range(9)], points)
    queries = np.concatenate((rng.uniform(-0.5, 1.5, size=(300, 3)), points, 0.5 * (points[:4] + points[4:8])))
    w, inside = t.weights(queries)
    # One simplex at a time: inside the first simplex holding the query, else the nearest clamped point.
    y = t.reduced(queries)
    corners = t.reduced(t.points)[t.simplices]
    for q in range(len(queries)):
        bary = []
        for c in corners:
            lam = np.linalg.pinv((c[1:] - c[0]).T) @ (y[q] - c[0])
            bary.append(np.concatenate(([1.0 - lam.sum()], lam)))
        held = [s for s, b in enumerate(bary) if np.all(b >= -1e-9)]
        expected = np.zeros(len(points))
        if held:
            expected[t.simplices[held[0]]] = bary[held[0]]
        else:
            clamped = [np.clip(b, 0.0, None) / max(np.clip(b, 0.0, None).sum(), 1e-12) for b in bary]
            s = int(np.argmin([np.linalg.norm(b @ c - y[q]) for b, c in zip(clamped, corners)]))
            expected[t.simplices[s]] = clamped[s]
        assert inside[q] == bool(held)
        assert np.allclose(w[q], expected, rtol=0.0, atol=1e-9), q
    assert inside[300:].all() and not inside[:300].all()
    assert np.array_equal(t.contains(queries), inside)
