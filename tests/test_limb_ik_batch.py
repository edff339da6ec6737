"""Several limbs in one limb-IK solve: each limb as solving it alone gives, whatever the limbs' shapes."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.runtime.limb_ik import LimbSolve, solve_limb, solve_limb_ends, solve_limb_ends_together
from infuse.skeleton import Skeleton

rng = np.random.default_rng(7)


def two_legs(twist: bool) -> tuple[Skeleton, list[tuple[int, int, int]]]:
    """A pelvis with two legs (hip, knee, ankle), the left one with a twist joint below its knee when ``twist``."""
    names = ["pelvis", "l_hip", "l_knee"] + (["l_twist"] if twist else []) + ["l_ankle", "r_hip", "r_knee", "r_ankle"]
    offsets = [[0, 1.0, 0], [0.1, 0, 0], [0, -0.45, 0]] + ([[0, -0.2, 0]] if twist else []) + \
        [[0, -0.2 if twist else -0.4, 0], [-0.1, 0, 0], [0, -0.45, 0], [0, -0.4, 0]]
    parents = list(range(-1, len(names) - 4)) + [0, len(names) - 3, len(names) - 2]
    sk = Skeleton(names, np.array(parents), np.array(offsets, dtype=float), quat.identity((len(names),)))
    index = {n: i for i, n in enumerate(names)}
    return sk, [tuple(index[f"{s}_{j}"] for j in ("hip", "knee", "ankle")) for s in "lr"]


@pytest.mark.parametrize("twist", [False, True])
@pytest.mark.parametrize("frames", [1, 40, 300])
@pytest.mark.parametrize("shared", [False, True])
def test_both_legs_at_once_match_each_leg_alone(twist, frames, shared):
    sk, legs = two_legs(twist)
    local = quat.normalize(rng.normal(size=(frames, sk.num_joints, 4)))
    root = rng.normal(size=(frames, 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + 0.1 * rng.normal(size=(frames, 2, 3))
    weight = rng.uniform(size=frames) if shared else rng.uniform(size=(frames, 2))
    pole = np.array([0.0, 0.0, 1.0]) if shared else rng.normal(size=(frames, 2, 3))
    for keep_end in (True, False):
        alone, together = local.copy(), local.copy()
        left = np.stack([solve_limb(sk, alone, root, None, leg, goals[:, k], weight=weight if shared else weight[:, k],
                                    pole=pole if shared else pole[:, k], keep_end=keep_end)
                         for k, leg in enumerate(legs)], axis=1)
        both = solve_limb(sk, together, root, None, legs, goals, weight=weight, pole=pole, keep_end=keep_end)
        assert both.shape == (frames, 2)
        # The quaternion helpers pick their formulas by batch size: the same maths to rounding.
        assert np.allclose(together, alone, rtol=0.0, atol=1e-12)
        assert np.allclose(both, left, rtol=0.0, atol=1e-12)
        assert not np.allclose(together, local)  # the legs did move


@pytest.mark.parametrize("twist", [False, True])
@pytest.mark.parametrize("several", [False, True])
def test_solved_ends_are_where_forward_kinematics_puts_them(twist, several):
    sk, legs = two_legs(twist)
    frames = 30
    local = quat.normalize(rng.normal(size=(frames, sk.num_joints, 4)))
    root = rng.normal(size=(frames, 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + 0.1 * rng.normal(size=(frames, 2, 3))
    weight = (rng.uniform(size=(frames, 2)) > 0.3).astype(float)
    joints, goal, w = (legs, goals, weight) if several else (legs[0], goals[:, 0], weight[:, 0])
    plain, solved = local.copy(), local.copy()
    left = solve_limb(sk, plain, root, None, joints, goal, weight=w, pole=np.array([0.0, 0.0, 1.0]))
    distance, above, ends = solve_limb_ends(sk, solved, root, None, joints, goal, weight=w, pole=np.array([0.0, 0.0, 1.0]))
    assert np.array_equal(solved, plain) and np.array_equal(distance, left)  # the same solve
    g_rot, g_pos = forward_kinematics(sk, solved, root)
    c = np.array([leg[2] for leg in legs])[slice(None) if several else 0]
    assert np.allclose(ends, g_pos[:, c], rtol=0.0, atol=1e-12)
    assert np.allclose(quat.canonical_sign(above), quat.canonical_sign(g_rot[:, sk.parents[c]]), rtol=0.0, atol=1e-12)
    assert not np.allclose(solved, local)  # the legs did move


def test_solves_together_give_each_as_alone():
    """Poses of two skeletons, legs of both and one leg alone, with and without poles and weights: solved
    together, each as solved alone, to the bit."""
    plain, twisted = two_legs(False), two_legs(True)
    cases = []
    for (sk, legs), frames, several, pole, weighted, keep_end in (
            (plain, 3, True, "frames", True, True), (twisted, 5, True, "one", False, True), (plain, 1, True, "limbs", True, False),
            (twisted, 4, False, "frames", True, True), (plain, 2, False, None, False, True), (twisted, 3, True, None, True, True)):
        local = quat.normalize(rng.normal(size=(frames, sk.num_joints, 4)))
        root = rng.normal(size=(frames, 3))
        _, pos = forward_kinematics(sk, local, root)
        k = 2 if several else 1
        goal = pos[:, [leg[2] for leg in legs[:k]]] + 0.1 * rng.normal(size=(frames, k, 3))
        poles = {"frames": rng.normal(size=(frames, 3)), "one": np.array([0.0, 0.0, 1.0]), "limbs": rng.normal(size=(frames, k, 3)),
                 None: None}[pole]
        weight = (rng.uniform(size=(frames, k)) > 0.3).astype(float) if weighted else None
        end = quat.normalize(rng.normal(size=(frames, k, 4))) if not keep_end else None
        if not several:
            goal, weight, end = goal[:, 0], None if weight is None else weight[:, 0], None if end is None else end[:, 0]
            poles = poles if poles is None or poles.ndim < 3 else poles[:, 0]
        cases.append(dict(skeleton=sk, local_rotations=local, root_translations=root, joint_translations=None,
                          joints=legs if several else legs[0], goal=goal, weight=weight, pole=poles, keep_end=keep_end, end_rotation=end))
    alone = [dict(c, local_rotations=c["local_rotations"].copy()) for c in cases]
    together = [dict(c, local_rotations=c["local_rotations"].copy()) for c in cases]
    each = [solve_limb_ends(**c) for c in alone]
    both = solve_limb_ends_together([LimbSolve(**c) for c in together])
    assert len(both) == len(each)
    for c, a, t, e, b in zip(cases, alone, together, each, both):
        assert np.array_equal(t["local_rotations"], a["local_rotations"])
        assert not np.array_equal(t["local_rotations"], c["local_rotations"])  # the legs did move
        for x, y in zip(e, b):
            assert (x is None and y is None) or np.array_equal(x, y)


def test_straight_legs_bend_toward_the_pole_and_reach():
    sk, legs = two_legs(False)
    frames = 20
    local = quat.identity((frames, sk.num_joints))
    root = np.zeros((frames, 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + np.array([0.0, 0.15, 0.0])  # up toward the hips: the knees bend
    solved = local.copy()
    left = solve_limb(sk, solved, root, None, legs, goals, pole=np.array([0.0, 0.0, 1.0]))
    _, after = forward_kinematics(sk, solved, root)
    assert np.all(left < 1e-9)
    assert np.allclose(after[:, [leg[2] for leg in legs]], goals, atol=1e-9)
    assert np.all(after[:, [leg[1] for leg in legs], 2] > 0.05)  # both knees forward, toward the pole


def test_both_feet_phases_at_once_match_each_foot_alone():
    from infuse_locomotion.phase_keys import foot_phase

    mine = np.sort(rng.uniform(size=(2, 4)), axis=1)
    theirs = np.sort(rng.uniform(size=(60, 2, 4)), axis=2)
    phase = rng.uniform(size=60)
    both = foot_phase(mine, theirs, phase)
    assert both.shape == (60, 2)
    for k in (0, 1):
        assert np.array_equal(both[:, k], foot_phase(mine[k], theirs[:, k], phase))
    assert np.all((both >= 0.0) & (both < 1.0))
