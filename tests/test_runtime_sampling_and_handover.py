"""Sampling a subset of a clip's joints gives the full sampling's columns; a controller's handover
decides what a following activity starts from (nothing by default, the walk's whole state for
locomotion, its path restarting)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from infuse import Motion
from infuse.runtime import Clip, Controller, sample_motion

from runtime_characters import synthetic_character


@pytest.fixture(scope="module")
def motion():
    sk = synthetic_character().skeleton
    frames = 12
    rot = Rotation.random(frames * sk.num_joints, random_state=3).as_quat().reshape(frames, sk.num_joints, 4)
    rng = np.random.default_rng(5)
    jt = np.repeat(sk.rest_translations[None], frames, axis=0) + 0.01 * rng.normal(size=(frames, sk.num_joints, 3))
    return Motion(sk, 30.0, rot, rng.normal(size=(frames, 3)), joint_translations=jt, name="random")


@pytest.mark.parametrize("times", [np.linspace(0.0, 0.9, 17), np.arange(8) / 30.0, np.array([-0.2, 5.0])])
@pytest.mark.parametrize("loop", [True, False])
def test_a_subset_of_joints_samples_as_the_full_clip_does(motion, times, loop):
    joints = np.array([5, 1, 7])
    full = sample_motion(motion, times, loop)
    part = sample_motion(motion, times, loop, joints=joints)
    assert np.array_equal(part[0], full[0][:, joints])
    assert np.array_equal(part[1], full[1])
    assert np.array_equal(part[2], full[2][:, joints])
    assert np.array_equal(part[3], full[3])
    assert part[0].shape == (len(times), 3, 4)


def test_a_single_frame_clip_samples_a_subset_too(motion):
    still = motion.replace(local_rotations=motion.local_rotations[:1], root_translations=motion.root_translations[:1],
                           joint_translations=motion.joint_translations[:1])
    part = sample_motion(still, np.array([0.0, 0.4]), True, joints=[2, 0])
    assert np.array_equal(part[0], still.local_rotations[[0, 0]][:, [2, 0]])
    assert np.array_equal(part[2], still.joint_translations[[0, 0]][:, [2, 0]])


def test_controllers_start_afresh_after_another_unless_they_say_otherwise(motion):
    assert Controller().handover({"x": 1.0}) == {}
    assert Clip(motion).handover({"x": 1.0}) == {}


def test_a_walk_takes_over_the_whole_state_of_the_walk_before_but_its_path(motion):
    from infuse.runtime import controller
    from infuse_locomotion.state import LocomotionState

    walk = controller("locomotion", target=(0.0, 1.0))
    old = LocomotionState(x=1.5, heading=0.3, waypoint=2)
    old.pins = np.ones((2, 3))
    state = walk.handover({LocomotionState: old})[LocomotionState]
    assert state.waypoint == 0 and old.waypoint == 2
    assert state.x == 1.5 and state.heading == 0.3
    state.pins[0, 0] = 9.0  # a copy: the old walk's feet stay where they are
    assert old.pins[0, 0] == 1.0
    assert walk.handover({}) == {}  # a walk not evaluated yet hands nothing on
