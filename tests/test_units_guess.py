"""infuse.conventions: the unit guess (standing height against an adult's, ties to the more common unit)."""
from __future__ import annotations

import numpy as np
import pytest

from infuse.conventions import (HUMAN_HEIGHT_RANGE_M, UNIT_SCALES, body_height, body_joints, figure_height,
                                guess_unit, standing_heights, unit_miss, upright)

ALL_UNITS = tuple(UNIT_SCALES)


def _figure(height=1.75, head_top=True, arms="T"):
    """A stick figure, metres, +Y up: pelvis first (index 0), then legs, spine, head and arms."""
    hip = 0.52 * height
    points = [(0, hip, 0), (0.1, hip, 0), (0.1, 0.5 * hip, 0), (0.1, 0.05, 0), (0.1, 0.0, 0.15),
              (-0.1, hip, 0), (-0.1, 0.5 * hip, 0), (-0.1, 0.05, 0), (-0.1, 0.0, 0.15),
              (0, hip + 0.3 * height, 0), (0, 0.87 * height, 0)]
    if head_top:
        points.append((0, height, 0))
    shoulder = 0.82 * height
    reach = 0.4 * height
    for side in (1, -1):
        hand = (side * reach, shoulder, 0) if arms == "T" else (side * 0.2, shoulder + reach, 0)
        points += [(side * 0.2, shoulder, 0), hand]
    return np.array(points, dtype=np.float64)


@pytest.mark.parametrize("unit", ALL_UNITS)
def test_each_unit_is_found_for_an_adult(unit):
    size = 1.75 / UNIT_SCALES[unit]
    assert guess_unit(size, ALL_UNITS) == unit
    assert unit_miss(size, unit) == 0.0


def test_miss_is_the_log_distance_to_the_adult_range():
    lo, hi = HUMAN_HEIGHT_RANGE_M
    assert unit_miss(hi * 2, "m") == pytest.approx(np.log(2))
    assert unit_miss(lo / 3 / UNIT_SCALES["cm"], "cm") == pytest.approx(np.log(3))


def test_near_ties_go_to_the_unit_listed_first():
    size = 22.0  # 2.2 m in dm, 1.24 m in CMU units: both just outside the range
    assert abs(unit_miss(size, "dm") - unit_miss(size, "cmu")) < 0.05
    assert guess_unit(size, ("cmu", "dm")) == "cmu"
    assert guess_unit(size, ("dm", "cmu")) == "dm"
    size = 17.0  # 1.7 m in dm, 0.96 m in CMU units: no tie, order does not matter
    assert guess_unit(size, ("cmu", "dm")) == guess_unit(size, ("dm", "cmu")) == "dm"


def test_unusable_sizes_fall_back_to_metres():
    for size in (0.0, -1.0, float("nan"), float("inf")):
        assert guess_unit(size, ("cm", "inch")) == "m"


def test_standing_height_reads_the_legs_when_the_head_top_is_missing():
    full = _figure()
    headless = _figure(head_top=False)
    assert float(standing_heights(full, 0)) == pytest.approx(1.75)
    assert np.ptp(headless[:, 1]) == pytest.approx(0.87 * 1.75)
    assert float(standing_heights(headless, 0)) == pytest.approx(1.75)  # hip height / 0.52
    # Several poses at once, vectorized over the leading axis.
    poses = np.stack((_figure(1.6, head_top=False), _figure(1.9, head_top=False)))
    assert standing_heights(poses, 0) == pytest.approx([1.6, 1.9])


def test_standing_height_ignores_a_hip_out_of_place():
    figure = _figure()
    no_legs = figure[[0, 9, 10, 11, 12, 13, 14, 15]]  # pelvis, spine, head and arms only
    assert float(standing_heights(no_legs, 0)) == pytest.approx(np.ptp(no_legs[:, 1]))


def test_a_rest_pose_that_does_not_stand_is_measured_on_the_frames():
    standing = _figure()
    lying = standing[:, [0, 2, 1]]  # the figure on its back, head along +Z
    assert upright(standing) and not upright(lying)
    frames = np.stack([_figure(1.75), _figure(1.80), _figure(1.70, arms="up")[:, [0, 2, 1]]])
    assert figure_height(standing, 0) == pytest.approx(1.75)
    assert figure_height(lying, 0, frames) == pytest.approx(1.775)  # median of the two standing frames
    assert figure_height(lying, 0) == pytest.approx(np.ptp(lying, axis=0).max())  # nothing stands
    assert figure_height(standing[:1], 0) == 0.0


def test_a_skeleton_is_measured_on_its_body_without_leading_joints():
    # world root on the ground far away -> reference -> pelvis, which branches into legs, spine and arms
    figure = _figure(head_top=False)
    parents = [-1, 0, 1, 2, 3, 4, 5, 2, 7, 8, 9, 2, 11, 11, 13, 11, 15]
    far = np.array([[40.0, -3.0, 0.0], [40.0, 0.0, 0.0]])
    positions = np.concatenate((far, figure))
    assert list(body_joints(np.array(parents))) == list(range(2, 17))
    assert body_height(positions, parents) == pytest.approx(1.75)  # legs read, head top missing
    head_top = np.array([[0.0, 1.75, 0.0]])
    assert body_height(positions, parents, head_top, np.array([12])) == pytest.approx(1.75)
    assert body_height(positions, parents, far[:1], np.array([0])) == pytest.approx(1.75)  # a site off the body is left out
    chain = np.array([-1, 0, 1])
    assert list(body_joints(chain)) == [0, 1, 2]
