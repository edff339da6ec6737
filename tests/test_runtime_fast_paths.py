"""The runtime's fast paths agree with the plain formulas they replace: quaternion products and
rotations on small and large batches, chain forward kinematics, local offsets, swings without roll,
limb IK, recent frames, block boundaries and the gaze smoothing of characters at rest."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from infuse import Motion, Skeleton, forward_kinematics
from infuse import quaternions as quat
from infuse.runtime import Clip, Runtime
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk
from infuse.runtime.swing import SWING_AXES, local_axes, local_offsets, local_turns, swing

from runtime_characters import synthetic_character

rng = np.random.default_rng(11)


def unit_quats(*shape):
    return Rotation.random(int(np.prod(shape)), random_state=int(rng.integers(1 << 30))).as_quat().reshape(shape + (4,))


def written_out_product(a, b):
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack((aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz), axis=-1)


@pytest.mark.parametrize("shapes", [((4,), (4,)), ((15, 4), (15, 4)), ((4,), (150, 4)), ((2, 4), (150, 2, 4)),
                                    ((1, 15, 9, 4), (1, 1, 9, 4)), ((150, 65, 4), (150, 65, 4))])
def test_products_and_rotations_match_the_written_out_formulas_on_every_batch_size(shapes):
    a, b = rng.normal(size=shapes[0]), rng.normal(size=shapes[1])  # not unit: the product is bilinear
    assert np.allclose(quat.multiply(a, b), written_out_product(a, b), rtol=0, atol=1e-14)
    q = unit_quats(*shapes[1][:-1])
    for v in (rng.normal(size=shapes[1][:-1] + (3,)), rng.normal(size=3)):
        expected = Rotation.from_quat(q.reshape(-1, 4)).apply(np.broadcast_to(v, q.shape[:-1] + (3,)).reshape(-1, 3).copy())
        assert np.allclose(quat.rotate(q, v).reshape(-1, 3), expected, rtol=0, atol=1e-13)


def test_small_and_large_batches_agree_to_rounding():
    a, b = unit_quats(600), unit_quats(600)
    whole = quat.multiply(a, b)  # above SMALL_BATCH
    pieces = np.concatenate([quat.multiply(a[k:k + 100], b[k:k + 100]) for k in range(0, 600, 100)])
    assert quat.SMALL_BATCH < 600 and np.abs(whole - pieces).max() < 1e-15


def random_skeleton(j=14):
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, j)])
    parents[7] = -1  # a second root
    return Skeleton([f"j{i}" for i in range(j)], parents, rng.normal(size=(j, 3)), unit_quats(j))


@pytest.mark.parametrize("frames", [1, 15, 150])
def test_chain_fk_matches_full_forward_kinematics(frames):
    sk = random_skeleton()
    local = unit_quats(frames, sk.num_joints)
    root = rng.normal(size=(frames, 3))
    moved = rng.normal(size=(frames, sk.num_joints, 3))
    for translations in (None, moved):
        g_rot, g_pos = forward_kinematics(sk, local, root, translations)
        for joints in ([5], [13, 2], [0], [7, 8, 9], list(range(sk.num_joints))):
            rot, pos = chain_fk(sk, local, root, translations, joints)
            assert np.allclose(quat.canonical_sign(rot), quat.canonical_sign(g_rot[:, joints]), atol=1e-12)
            assert np.allclose(pos, g_pos[:, joints], atol=1e-12)


def test_chain_fk_on_columns_and_leading_axes():
    sk = random_skeleton()
    local = unit_quats(3, 10, sk.num_joints)  # characters, frames
    root = rng.normal(size=(3, 10, 3))
    joints = [11, 4]
    columns = sorted({0, *range(sk.num_joints)} - {12})  # any superset of the ancestors, in order
    full = chain_fk(sk, local, root, None, joints)
    part = chain_fk(sk, local[..., columns, :], root, None, joints, columns)
    assert np.allclose(full[0], part[0], atol=0) and np.allclose(full[1], part[1], atol=0)
    g_rot, g_pos = forward_kinematics(sk, local[1], root[1])
    assert np.allclose(full[1][1], g_pos[:, joints], atol=1e-12)


def test_local_offsets_and_swing_without_roll():
    aligned, delta = unit_quats(5), unit_quats(20, 5)
    expected = quat.multiply(quat.multiply(aligned, delta), quat.conjugate(aligned))
    assert np.allclose(local_offsets(aligned, delta), expected, atol=1e-15)
    h, p = rng.normal(size=(20, 5)), rng.normal(size=(20, 5))
    assert np.array_equal(swing(h, p), swing(h, p, np.zeros((20, 5))))


@pytest.mark.parametrize("component", [0, 1, 2])
def test_turns_about_one_axis_match_local_offsets_of_a_swing(component):
    aligned, angles = unit_quats(4), rng.normal(size=(30, 4))
    hpr = [np.zeros((30, 4))] * 3
    hpr[component] = angles
    expected = local_offsets(aligned, swing(*hpr))
    turns = local_turns(local_axes(aligned, SWING_AXES[component]), angles)
    assert np.allclose(turns, expected, atol=1e-15)


def test_limb_ik_reaches_and_keeps_the_end_rotation():
    # a chain bent in one plane: root -> a -> b -> twist -> c, bones of 0.4 m and 0.35 m
    offsets = np.array([[0, 1.0, 0], [0.1, 0, 0], [0, -0.4, 0], [0, -0.2, 0], [0, -0.15, 0]])
    sk = Skeleton(["root", "a", "b", "twist", "c"], np.array([-1, 0, 1, 2, 3]), offsets, quat.identity((5,)))
    frames = 30
    local = quat.from_axis_angle(np.array([1.0, 0, 0]), np.linspace(0.1, 0.6, frames))[:, None].repeat(5, axis=1)
    root = np.zeros((frames, 3))
    g_rot0, g_pos0 = forward_kinematics(sk, local, root)
    for shift, exact in (((0.0, 0.08, 0.02), True), ((0.05, 0.08, 0.02), False)):  # in the limb's plane, or not
        solved = local.copy()
        goal = g_pos0[:, 4] + np.array(shift)
        left = solve_limb(sk, solved, root, None, (1, 2, 4), goal, pole=np.array([0, 0, 1.0]))
        g_rot, g_pos = forward_kinematics(sk, solved, root)
        assert np.allclose(left, np.linalg.norm(g_pos[:, 4] - goal, axis=-1), atol=1e-12)  # what is left, measured
        assert np.all(left < 1e-9) if exact else np.all(left < 0.01)
        assert np.allclose(quat.canonical_sign(g_rot[:, 4]), quat.canonical_sign(g_rot0[:, 4]), atol=1e-9)


def sway(skeleton, frames=40) -> Motion:
    """A looping clip: every joint sways a few degrees about its own axis, the root moves forward."""
    phase = 2.0 * np.pi * np.arange(frames)[:, None] / (frames - 1) + np.arange(skeleton.num_joints)[None]
    axes = rng.normal(size=(skeleton.num_joints, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    rotations = quat.from_axis_angle(np.broadcast_to(axes, (frames,) + axes.shape), 0.1 * np.sin(phase))
    root = skeleton.rest_translations[0] + np.linspace(0.0, 1.0, frames)[:, None] * np.array([0.0, 0.0, 1.0])
    return Motion(skeleton, 24.0, rotations, root, name="sway")


def test_last_frames_span_blocks_in_the_characters_own_frame():
    character = synthetic_character()
    rt = Runtime(fps=30, block_frames=7)
    name = rt.add_character(character, position=(1.0, 0.0, 2.0), heading_deg=90.0)
    rt.activate(name, Clip(sway(character.skeleton)), 0.0)
    rt.run(1.0)
    motion = rt.motion(name)
    rotations, roots = rt.last_frames(name, 10)
    rig = rt.rig(name)
    own = quat.rotate(quat.conjugate(rig.rotation), motion.root_translations[-10:] - rig.position)
    assert rotations.shape == (10, character.skeleton.num_joints, 4)
    assert np.allclose(roots, own, atol=1e-12)
    assert np.allclose(rotations[:, 1:], motion.local_rotations[-10:, 1:], atol=0)
    assert len(rt.last_frames(name, 1000)[0]) == 30


def test_cast_poses_are_every_characters_last_poses_side_by_side():
    """Runtime.cast_poses (the live loop's frames, every character at once) equals last_poses character by
    character, across blocks, placed or not; a character joining within the frames asked for gives None."""
    character = synthetic_character()
    rt = Runtime(fps=30, block_frames=7)
    names = [rt.add_character(character, name, position=position, heading_deg=heading)
             for name, position, heading in (("a", (1.0, 0.0, 2.0), 90.0), ("b", (0.0, 0.0, 0.0), 0.0), ("c", (-1.0, 0.5, 0.0), -30.0))]
    for name in names:
        rt.activate(name, Clip(sway(character.skeleton)), 0.0)
    rt.run(1.0)
    rt.step(3)
    layout, rotations, roots, morphs = rt.cast_poses(12)  # frames of three blocks: 2 + 7 + 3
    assert rotations.shape[0] == roots.shape[0] == morphs.shape[0] == 12
    for name in names:
        c = layout.character_index[name]
        (j0, j1), (m0, m1) = layout.joint_spans[c], layout.morph_spans[c]
        own = rt.last_poses(name, 12)
        assert np.array_equal(rotations[:, j0:j1], own[0]) and np.array_equal(roots[:, c], own[1])
        assert np.array_equal(morphs[:, m0:m1], own[2])
    assert len(rt.cast_poses(1000)[1]) == 33  # every frame evaluated
    rt.rig("b").rotation = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), 0.5)  # turned as a scene turns one
    rt.rig("a").position = np.array([2.0, 0.0, 2.0])
    layout, rotations, roots, morphs = rt.cast_poses(4)
    for name in names:
        c = layout.character_index[name]
        own = rt.last_poses(name, 4)
        assert np.array_equal(rotations[:, slice(*layout.joint_spans[c])], own[0]) and np.array_equal(roots[:, c], own[1])
    rt.add_character(character, "d")
    rt.step(2)
    assert rt.cast_poses(2) is not None and rt.cast_poses(3) is None


def test_blocks_of_any_size_give_the_same_frames():
    """Clips, gazes at points and objects and saccades carry their state across blocks (two characters
    looking at each other: tests/test_gaze_blocks.py)."""
    from infuse_gaze import Gaze
    from infuse_saccade.controller import Saccades

    character = synthetic_character()
    clip = sway(character.skeleton)
    out = []
    for block in (150, 7, 1):
        rt = Runtime(fps=30, block_frames=block)
        a = rt.add_character(character, "a")
        b = rt.add_character(character, "b", position=(0.0, 0.0, 2.0), heading_deg=180.0)
        rt.add_target("lamp", lambda t: np.stack((np.sin(t), 1.6 + 0 * t, 1.0 + np.cos(t)), axis=-1))
        for name, target in ((a, "lamp"), (b, (0.3, 1.2, -1.0))):
            rt.activate(name, Clip(clip), 0.0)
            rt.activate(name, Gaze(target, influence="WAIST"), 0.2)
            rt.activate(name, Saccades("talk"), 0.0)
        rt.activate(a, Gaze((2.0, 1.5, 1.0), influence="HEAD", priority="head"), 0.6)  # takes over within a block
        rt.run(1.5)
        out.append(np.stack([rt.motion(n).local_rotations for n in (a, b)]))
    assert np.allclose(out[0], out[1], atol=1e-12) and np.allclose(out[0], out[2], atol=1e-12)


def test_gaze_rows_at_rest_stay_exactly_at_rest():
    from infuse_gaze import solver

    desired = rng.normal(size=(3, 40, 2))
    desired[1] = 0.0
    smoothing, max_step = np.full((3, 40), 0.3), np.full((3, 40), 0.05)
    state = np.zeros((3, 2))
    state[0] = (0.1, -0.2)
    final, path = solver.follow(desired, smoothing, max_step, state)
    assert np.array_equal(path[1], np.zeros((40, 2))) and np.array_equal(final[1], (0.0, 0.0))
    single = solver.follow(desired[[0, 2]], smoothing[[0, 2]], max_step[[0, 2]], state[[0, 2]])
    assert np.array_equal(single[1], path[[0, 2]]) and np.array_equal(single[0], final[[0, 2]])
