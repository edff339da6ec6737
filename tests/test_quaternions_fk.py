import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from infuse import Motion, Skeleton, batch_fk, motion_fk
from infuse import quaternions as quat
from infuse.errors import InputError

rng = np.random.default_rng(7)


def random_quats(*shape):
    return Rotation.random(int(np.prod(shape)), random_state=3).as_quat().reshape(shape + (4,))


def test_multiply_and_rotate_match_scipy():
    a, b = random_quats(50), random_quats(50)[::-1]
    v = rng.normal(size=(50, 3))
    expected = (Rotation.from_quat(a) * Rotation.from_quat(b)).as_quat()
    assert np.allclose(quat.canonical_sign(quat.multiply(a, b)), quat.canonical_sign(expected))
    assert np.allclose(quat.rotate(a, v), Rotation.from_quat(a).apply(v))


def test_euler_order_is_intrinsic_first_axis_outermost():
    q = quat.from_euler("ZXY", [30, 20, 10], degrees=True)
    rz = quat.from_axis_angle([0, 0, 1], np.radians(30))
    rx = quat.from_axis_angle([1, 0, 0], np.radians(20))
    ry = quat.from_axis_angle([0, 1, 0], np.radians(10))
    assert np.allclose(quat.canonical_sign(q), quat.canonical_sign(quat.multiply(quat.multiply(rz, rx), ry)))


def test_between_and_slerp():
    u, v = rng.normal(size=(20, 3)), rng.normal(size=(20, 3))
    q = quat.between(u, v)
    out = quat.rotate(q, u)
    assert np.allclose(out / np.linalg.norm(out, axis=1, keepdims=True), v / np.linalg.norm(v, axis=1, keepdims=True))
    opposite = quat.between(np.array([1.0, 0, 0]), np.array([-1.0, 0, 0]))
    assert np.allclose(quat.rotate(opposite, [1.0, 0, 0]), [-1, 0, 0])
    a, b = random_quats(10), random_quats(10)[::-1]
    mid = quat.slerp(a, b, 0.5)
    assert np.allclose(quat.angle_between(a, mid), quat.angle_between(mid, b))


def _chain_skeleton(j=6):
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, j)])
    return Skeleton(
        [f"j{i}" for i in range(j)], parents, rng.normal(size=(j, 3)), random_quats(j),
        end_site_parents=[j - 1], end_site_offsets=[[0, 0.1, 0]],
    )


def _matrix_chain_fk(sk, rots, root, trans=None):
    """Independent reference: 4x4 matrices multiplied joint by joint."""
    frames, j = rots.shape[:2]
    out = np.zeros((frames, j, 3))
    for f in range(frames):
        world = [None] * j
        for i in range(j):
            m = np.eye(4)
            m[:3, :3] = Rotation.from_quat(rots[f, i]).as_matrix()
            t = sk.rest_translations[i] if trans is None else trans[f, i]
            m[:3, 3] = root[f] if i == 0 else t
            world[i] = m if sk.parents[i] < 0 else world[sk.parents[i]] @ m
            out[f, i] = world[i][:3, 3]
    return out


def test_fk_matches_matrix_chain_and_batches():
    sk = _chain_skeleton(9)
    clips = []
    for n in (5, 7):
        rots = random_quats(n, 9)
        root = rng.normal(size=(n, 3))
        jt = rng.normal(size=(n, 9, 3))
        clips.append(Motion(sk, 30.0, rots, root, jt, name=f"c{n}"))
    for clip in clips:
        _, pos = motion_fk(clip)
        assert np.allclose(pos, _matrix_chain_fk(sk, clip.local_rotations, clip.root_translations, clip.joint_translations), atol=1e-9)
    batched = batch_fk(clips)
    for clip, (rot, pos) in zip(clips, batched):
        ref_rot, ref_pos = motion_fk(clip)
        assert np.allclose(pos, ref_pos) and np.allclose(rot, ref_rot)


def test_skeleton_rejects_bad_order_and_nan():
    with pytest.raises(InputError, match="parent does not precede"):
        Skeleton(["a", "b"], [1, -1], np.zeros((2, 3)), quat.identity((2,)))
    with pytest.raises(InputError, match="not finite"):
        Skeleton(["a", "b"], [-1, 0], [[0, 0, 0], [np.nan, 0, 0]], quat.identity((2,)))
    sk = _chain_skeleton(3)
    rots = random_quats(4, 3)
    rots[2, 1, 0] = np.nan
    with pytest.raises(InputError, match="frame 2"):
        Motion(sk, 30.0, rots, np.zeros((4, 3)))


def test_transformed_skeleton_rotates_the_whole_figure():
    sk = _chain_skeleton(5)
    q = quat.from_axis_angle([1, 0, 0], -np.pi / 2)
    moved = sk.transformed(scale=0.01, rotation=q)
    assert np.allclose(moved.rest_global_positions, quat.rotate(q, sk.rest_global_positions * 0.01))
