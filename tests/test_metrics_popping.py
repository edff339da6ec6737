"""The popping measure: each joint's largest turn of global orientation between frames, against the source's."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import metrics
from infuse import quaternions as quat


def _turning(frames: int, step_deg: float, axis=(0.0, 1.0, 0.0)) -> np.ndarray:
    """(F, 4) rotations turning ``step_deg`` degrees a frame about ``axis``."""
    angles = np.radians(step_deg) * np.arange(frames)
    return quat.from_axis_angle(np.broadcast_to(np.array(axis), (frames, 3)), angles)


def test_largest_turns_per_joint_in_degrees():
    g = np.stack([_turning(10, 5.0), _turning(10, -12.0, (1.0, 0.0, 0.0))], axis=1)  # (F, 2, 4)
    assert metrics.largest_turns(g) == pytest.approx([5.0, 12.0])
    assert metrics.largest_turns(g[:1]).tolist() == [0.0, 0.0]
    flipped = g.copy()
    flipped[4:] *= -1.0  # the same orientations: q and -q
    assert metrics.largest_turns(flipped) == pytest.approx([5.0, 12.0])


def test_a_joint_that_flips_in_one_frame_pops():
    source = np.stack([_turning(20, 5.0), _turning(20, 2.0)], axis=1)
    flip = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(117.0))
    output = source.copy()
    output[10:, 1] = quat.multiply(flip, output[10:, 1])
    index = {"l_ankle": 0, "r_ankle": 1}
    pop = metrics.popping(source, index, output, index)
    assert not pop.ok and pop.worst == "r_ankle"
    # the largest turn is the flip and the frame's own 2 degrees, about different axes
    assert 115.0 < pop.turns()[1] < 119.0 and pop.turns()[0] == pytest.approx(2.0)
    assert pop.excess == pytest.approx(pop.turns()[1] - (1.5 * 2.0 + 10.0))
    same = metrics.popping(source, index, source, index)
    assert same.ok and same.excess == pytest.approx(-(0.5 * 2.0 + 10.0))


def test_popping_compares_joints_by_canonical_name_on_both_skeletons():
    source = np.stack([_turning(8, 3.0), _turning(8, 40.0)], axis=1)
    output = np.stack([_turning(8, 40.0), _turning(8, 3.0), _turning(8, 90.0)], axis=1)
    pop = metrics.popping(source, {"base": 0, "l_knee": 1}, output, {"l_knee": 0, "base": 1, "l_toe": 2})
    assert set(pop.per_joint) == {"base", "l_knee"}  # l_toe has no source counterpart
    assert pop.ok and pop.per_joint["l_knee"] == pytest.approx((40.0, 40.0))
    only = metrics.popping(source, {"base": 0, "l_knee": 1}, output, {"l_knee": 0, "base": 1}, names=["base"])
    assert set(only.per_joint) == {"base"}
