"""Foot skate counts the sole's travel: synthetic rigid feet rolling, sliding and twisting."""
from __future__ import annotations

import numpy as np
import pytest

from infuse.contacts import FootContacts, foot_frames, sole_positions
from infuse.metrics import foot_skate

#: A flat foot (metres, +Y up, +Z forward): the ankle 9 cm up, the ball joint 11 cm ahead and 3 cm up;
#: the sole point under the heel, at the ball's height below the ankle.
ANKLE = np.array([0.0, 0.09, 0.0])
BALL = np.array([0.0, 0.03, 0.11])
HEEL = np.array([0.0, 0.03, 0.0])
FLAT = 10
MOVING = 20


def rotation(axis: str, angles: np.ndarray) -> np.ndarray:
    """(F, 3, 3) rotations by ``angles`` (F,) radians about the X or Y axis (right-handed)."""
    c, s = np.cos(angles), np.sin(angles)
    one, zero = np.ones_like(angles), np.zeros_like(angles)
    rows = ([[one, zero, zero], [zero, c, -s], [zero, s, c]] if axis == "x"
            else [[c, zero, s], [zero, one, zero], [-s, zero, c]])
    return np.moveaxis(np.array(rows), (0, 1), (1, 2))


def rigid_foot(pivot: np.ndarray, axis: str, angle: float, slide: np.ndarray = np.zeros(3)) -> np.ndarray:
    """(F, 3, 3) positions of root, ankle, ball: the foot flat for :data:`FLAT` frames, then over
    :data:`MOVING` frames turned by ``angle`` radians about ``axis`` through ``pivot`` and moved by
    ``slide`` (metres); the root walks 1 m in all."""
    t = np.concatenate((np.zeros(FLAT), np.linspace(0.0, 1.0, MOVING)))
    turn = rotation(axis, angle * t)
    joints = np.stack((ANKLE, BALL)) - pivot
    feet = np.einsum("fij,pj->fpi", turn, joints) + pivot + t[:, None, None] * slide
    root = np.zeros((len(t), 1, 3))
    root[:, 0, 2] = np.linspace(0.0, 1.0, len(t))
    return np.concatenate((root, feet), axis=1)


def contacts(frames: int, planted: tuple[bool, bool] = (True, True)) -> FootContacts:
    """One foot (ankle joint 1, ball joint 2) planted throughout (each point as ``planted`` says
    after the flat frames), the other without points; ground at 0, leg 0.85 m."""
    flags = np.ones((frames, 2), dtype=bool)
    flags[FLAT:] = planted
    return FootContacts(np.array([1, 2]), np.array([0, 0]), flags, 0.0, 0.85, np.zeros((frames, 2)))


def skate_cm(pos: np.ndarray, planted: tuple[bool, bool] = (True, True)) -> float:
    return foot_skate(pos, contacts(len(pos), planted), root=0).per_metre


def test_sole_points_lie_under_the_flat_foot_and_move_with_it():
    pos = rigid_foot(np.zeros(3), "y", 0.6, np.array([0.05, 0.02, 0.1]))
    found = contacts(len(pos))
    sole = sole_positions(found, pos[:, 1:])
    assert sole[:FLAT] == pytest.approx(np.broadcast_to(np.stack((HEEL, BALL)), (FLAT, 2, 3)))
    # rigidly attached: each sole point keeps its distances to both joints in every frame
    for j in (0, 1):
        for s in (0, 1):
            d = np.linalg.norm(sole[:, s] - pos[:, 1 + j], axis=-1)
            assert d == pytest.approx(np.full(len(d), d[0]), abs=1e-9)
    frames = foot_frames(pos[:, 1], pos[:, 2])
    assert np.einsum("fij,fkj->fik", frames, frames) == pytest.approx(np.broadcast_to(np.eye(3), frames.shape), abs=1e-12)


def test_rolling_about_the_ball_counts_nothing():
    """The heel rises 30 degrees about the ball: the ankle swings 4 cm forward along its arc, the
    ball stays, the sole under the heel rises (what is left: it moves forward by 11 cm x (1 - cos)
    along its arc before it is up; the joints would count 0.47 cm)."""
    pos = rigid_foot(BALL, "x", np.radians(30.0))
    assert np.linalg.norm(pos[-1, 1, [0, 2]] - pos[0, 1, [0, 2]]) > 0.04
    assert skate_cm(pos) < 0.1


def test_rolling_about_the_heel_counts_nothing():
    """The toes come up 20 degrees about the heel's sole point (the heel rocker): the ankle swings
    back, the ball rises, the sole under the heel stays (the joints would count 1.03 cm)."""
    pos = rigid_foot(HEEL, "x", np.radians(-20.0))
    assert np.linalg.norm(pos[-1, 1, [0, 2]] - pos[0, 1, [0, 2]]) > 0.02
    assert skate_cm(pos) < 0.1


def test_sliding_flat_counts_the_whole_travel():
    pos = rigid_foot(np.zeros(3), "x", 0.0, np.array([0.06, 0.0, 0.08]))
    assert skate_cm(pos) == pytest.approx(10.0)


def test_twisting_about_the_ball_counts_the_heel_travel():
    """The flat foot turns 30 degrees about the vertical through its ball: the heel's sole point
    sweeps an arc of 11 cm radius on the ground, the ball stays; the foot travels the mean of its
    two points."""
    angle = np.radians(30.0)
    pos = rigid_foot(BALL, "y", angle)
    arc = 0.11 * angle
    assert skate_cm(pos) == pytest.approx(100.0 * arc / 2.0, rel=1e-3)


def test_sliding_while_rolling_counts_the_slide():
    """The heel rises 30 degrees about the ball while the foot slides 5 cm: with only the ball
    planted the foot travels the slide; with both planted at least the ball's full slide is
    counted, averaged with the lifting heel's weighted travel."""
    pos = rigid_foot(BALL, "x", np.radians(30.0), np.array([0.0, 0.0, 0.05]))
    assert skate_cm(pos, planted=(False, True)) == pytest.approx(5.0, rel=1e-6)
    both = skate_cm(pos)
    assert 2.5 <= both < 5.0
    assert both == pytest.approx(2.5 + 0.5 * (skate_cm(pos, planted=(True, False))), rel=1e-6)


def test_a_foot_without_ball_counts_its_ankle():
    pos = rigid_foot(np.zeros(3), "x", 0.0, np.array([0.0, 0.0, 0.1]))
    flags = np.ones((len(pos), 1), dtype=bool)
    found = FootContacts(np.array([1]), np.array([0]), flags, 0.0, 0.85, np.zeros((len(pos), 2)))
    assert sole_positions(found, pos[:, [1]]) == pytest.approx(pos[:, [1]])
    assert foot_skate(pos, found, root=0).per_metre == pytest.approx(10.0)
