"""infuse.transforms: matrices in, Skeleton/Motion out, global joint positions kept exactly."""
import numpy as np

from infuse import quaternions as quat
from infuse import transforms
from infuse.kinematics import forward_kinematics, motion_fk


def _random_tree(rng, n):
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, n)])
    local = transforms.compose(rng.normal(size=(n, 3)), quat.normalize(rng.normal(size=(n, 4))),
                               rng.uniform(0.5, 2.0, size=(n, 3)))
    return parents, local


def test_compose_decompose_round_trip():
    rng = np.random.default_rng(1)
    t, r, s = rng.normal(size=(50, 3)), quat.normalize(rng.normal(size=(50, 4))), rng.uniform(0.1, 3, size=(50, 3))
    t2, r2, s2 = transforms.decompose(transforms.compose(t, r, s))
    assert np.allclose(t, t2) and np.allclose(s, s2)
    assert np.allclose(quat.angle_between(r, r2), 0.0, atol=1e-6)


def test_decompose_mirror_gives_negative_scale():
    m = transforms.compose(np.zeros(3), quat.IDENTITY, np.array([1.0, -2.0, 1.0]))
    _, r, s = transforms.decompose(m)
    assert np.isclose(np.prod(s), -2.0)
    assert np.isclose(np.linalg.det(quat.to_matrix(r)), 1.0)


def test_global_matrices_match_a_per_node_chain():
    rng = np.random.default_rng(2)
    parents, local = _random_tree(rng, 12)
    g = transforms.global_matrices(parents, local[None])[0]
    for i in range(12):
        m, k = np.eye(4), i
        while k >= 0:
            m = local[k] @ m
            k = parents[k]
        assert np.allclose(g[i], m)


def test_skeleton_from_globals_keeps_joint_positions_with_folded_nodes_and_scale():
    rng = np.random.default_rng(3)
    parents, local = _random_tree(rng, 15)
    g = transforms.frame_change(0.01, "Z") @ transforms.global_matrices(parents, local[None])[0]
    joints = [0, 2, 3, 5, 7, 8, 11, 14]  # the others are folded away
    jpar = []
    for j in joints:
        p = parents[j]
        while p >= 0 and p not in joints:
            p = parents[p]
        jpar.append(joints.index(p) if p >= 0 else -1)
    sk = transforms.skeleton_from_globals([f"j{j}" for j in joints], jpar, g[joints])
    assert np.allclose(sk.rest_global_positions, g[joints, :3, 3], atol=1e-9)
    _, rot, _ = transforms.decompose(g[joints])
    assert np.allclose(quat.angle_between(sk.rest_global_rotations, rot), 0.0, atol=1e-6)


def test_motion_from_globals_reproduces_every_frame():
    rng = np.random.default_rng(4)
    parents, local = _random_tree(rng, 6)
    frames = np.repeat(local[None], 20, axis=0)
    frames[:, 1:, :3, 3] += rng.normal(scale=0.1, size=(20, 5, 3))  # animated translations
    g = transforms.global_matrices(parents, frames)
    sk = transforms.skeleton_from_globals([f"j{i}" for i in range(6)], parents, g[0])
    motion = transforms.motion_from_globals(sk, 30.0, g, name="wiggle")
    assert motion.joint_translations is not None
    _, pos = motion_fk(motion)
    assert np.allclose(pos, g[..., :3, 3], atol=1e-9)
    still = transforms.motion_from_globals(sk, 30.0, np.repeat(g[:1], 3, axis=0))
    assert still.joint_translations is None
    _, pos = forward_kinematics(sk, still.local_rotations, still.root_translations)
    assert np.allclose(pos, g[:1, :, :3, 3], atol=1e-9)


def test_decompose_sheared_block_gives_the_nearest_rotation():
    from scipy.linalg import polar

    parent = transforms.compose(np.zeros(3), quat.IDENTITY, np.array([1.0, 3.0, 1.0]))
    child = transforms.compose(np.zeros(3), quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.5))
    _, rot, _ = transforms.decompose(parent @ child)
    nearest, _ = polar((parent @ child)[:3, :3])
    assert np.allclose(quat.to_matrix(rot), nearest, atol=1e-9)


def test_sampled_motion_in_chunks_equals_one_pass():
    rng = np.random.default_rng(5)
    parents, local = _random_tree(rng, 5)
    frames = np.repeat(local[None], 10, axis=0)
    frames[:, :, :3, 3] += rng.normal(scale=0.1, size=(10, 5, 3))
    g = transforms.global_matrices(parents, frames)
    sk = transforms.skeleton_from_globals([f"j{i}" for i in range(5)], parents, g[0])
    whole = transforms.motion_from_globals(sk, 30.0, g)
    calls = []

    def between(a, b):
        calls.append((a, b))
        return g[a:b]

    chunked = transforms.sampled_motion(sk, 30.0, 10, between, chunk=3)
    assert calls == [(0, 3), (3, 6), (6, 9), (9, 10)]
    assert np.allclose(chunked.local_rotations, whole.local_rotations)
    assert np.allclose(chunked.local_translations(), whole.local_translations())
