"""Limb IK with a pole bends a limb toward the pole whatever side a nearly straight pose leaves it bent to:
a knee a degree or two past straight (a blend of takes, mocap noise) asked to bend bent backward before."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.runtime.limb_ik import solve_limb
from test_limb_ik_batch import two_legs

FORWARD = np.array([0.0, 0.0, 1.0])


def _knee_ahead(sk, legs, local, root) -> np.ndarray:
    """(F, 2) how far (m) each knee lies ahead (+Z) of the line from its hip to its ankle."""
    _, pos = forward_kinematics(sk, local, root)
    out = []
    for hip, knee, ankle in legs:
        line = pos[:, ankle] - pos[:, hip]
        t = np.einsum("fi,fi->f", pos[:, knee] - pos[:, hip], line) / np.einsum("fi,fi->f", line, line)
        out.append((pos[:, knee] - (pos[:, hip] + t[:, None] * line))[:, 2])
    return np.stack(out, axis=1)


def _bent(sk, legs, degrees: np.ndarray) -> np.ndarray:
    """(F, J, 4) local rotations with each knee bent by ``degrees`` (F,) about +X (negative: backward)."""
    local = quat.identity((len(degrees), sk.num_joints))
    for hip, knee, _ in legs:
        local[:, hip] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(-0.5 * degrees))
        local[:, knee] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(degrees))
    return local


@pytest.mark.parametrize("shared_pole", [True, False])
def test_a_knee_past_straight_bends_toward_the_pole(shared_pole):
    sk, legs = two_legs(False)
    past = np.array([-0.3, -1.0, -1.9, -3.0, -8.0, -25.0])  # degrees backward, as blends and takes leave knees
    local = _bent(sk, legs, past)
    root = np.zeros((len(past), 3))
    assert np.all(_knee_ahead(sk, legs, local, root) < 0.0)
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + np.array([0.0, 0.12, 0.02])  # the foot raised: the knee must bend
    pole = FORWARD if shared_pole else np.broadcast_to(FORWARD, (len(past), 2, 3))
    solved = local.copy()
    left = solve_limb(sk, solved, root, None, legs, goals, pole=pole)
    _, after = forward_kinematics(sk, solved, root)
    assert np.all(left < 1e-9)
    assert np.allclose(after[:, [leg[2] for leg in legs]], goals, atol=1e-9)
    assert np.all(_knee_ahead(sk, legs, solved, root) > 0.05)  # every knee forward, toward the pole


def test_a_clearly_bent_knee_keeps_its_plane():
    """A knee bent the natural way by more than a few degrees bends on in its own plane (turned off the pole)."""
    sk, legs = two_legs(False)
    local = _bent(sk, legs, np.full(4, 20.0))
    side = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.radians(30.0))  # legs turned 30 degrees off the pole
    for hip, _, _ in legs:
        local[:, hip] = quat.multiply(side, local[:, hip])
    root = np.zeros((4, 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + np.array([0.0, 0.1, 0.0])
    with_pole, without = local.copy(), local.copy()
    solve_limb(sk, with_pole, root, None, legs, goals, pole=FORWARD)
    solve_limb(sk, without, root, None, legs, goals)
    assert np.allclose(with_pole, without, atol=1e-12)


def test_the_bend_follows_a_knee_through_straight_without_a_jump():
    """A knee going from bent forward through straight to a little backward, its foot raised: the solved
    knee moves by little between neighbouring frames (it flipped backward before)."""
    sk, legs = two_legs(False)
    degrees = np.linspace(6.0, -3.0, 91)
    local = _bent(sk, legs, degrees)
    root = np.zeros((len(degrees), 3))
    _, pos = forward_kinematics(sk, local, root)
    goals = pos[:, [leg[2] for leg in legs]] + np.array([0.0, 0.1, 0.0])
    solved = local.copy()
    solve_limb(sk, solved, root, None, legs, goals, pole=FORWARD)
    g, _ = forward_kinematics(sk, solved, root)
    turn = np.degrees(quat.angle_between(g[:-1], g[1:])).max()
    assert turn < 1.0
