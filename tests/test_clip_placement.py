"""A clip played with a placement (turned about +Y and moved) is the clip's copy placed so, with no copy
made: alone, played together with characters placing it otherwise or not at all, looping on, held at
its first root, and in additive mode; a bad placement is a usage error."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Clip, Runtime

from runtime_characters import synthetic_character

UP = np.array([0.0, 1.0, 0.0])


def _walkish(sk: infuse.Skeleton, frames: int = 20) -> infuse.Motion:
    """A clip on ``sk`` whose joints sway and whose root travels forward and bobs (a looping cycle)."""
    rng = np.random.default_rng(3)
    t = np.arange(frames) / 30.0
    axes = rng.normal(size=(sk.num_joints, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = 0.3 * np.sin(2 * np.pi * t[:, None] / t[-1] + rng.uniform(0, 6, sk.num_joints))
    rotations = quat.from_axis_angle(np.broadcast_to(axes, (frames, sk.num_joints, 3)), angles)
    roots = np.stack((0.05 * np.sin(3 * t), 0.9 + 0.02 * np.cos(6 * t), 0.6 * t + 0.3), axis=1)
    return infuse.Motion(sk, 30.0, rotations, roots, name="cycle")


def _placed_copy(motion: infuse.Motion, turn: np.ndarray, shift: np.ndarray) -> infuse.Motion:
    rotations = np.array(motion.local_rotations)
    rotations[:, 0] = quat.multiply(turn, rotations[:, 0])
    return motion.replace(local_rotations=rotations, root_translations=quat.rotate(turn, motion.root_translations) + shift)


def _played(clips: dict[str, Clip], frames: int, block: int, mode: str | None = None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    runtime = Runtime(fps=30.0)
    for name, clip in clips.items():
        runtime.add_character(synthetic_character(name), name)
        runtime.activate(name, clip, 0.0, mode=mode)
    for _ in range(frames // block):
        runtime.step(block)
    return {name: (runtime.motion(name).local_rotations, runtime.motion(name).root_translations) for name in clips}


@pytest.mark.parametrize("block", [1, 7])
@pytest.mark.parametrize("root_motion", [True, False])
def test_a_placed_clip_plays_as_its_placed_copy(block, root_motion):
    sk = synthetic_character().skeleton
    motion = _walkish(sk)
    turns = {"a": quat.from_axis_angle(UP, 2.1), "b": quat.from_axis_angle(UP, -0.7)}
    shifts = {"a": np.array([1.5, 0.0, -2.0]), "b": np.array([-0.3, 0.01, 0.8])}
    placed = _played({"a": Clip(motion, root_motion=root_motion, placement=(turns["a"], shifts["a"])),
                      "b": Clip(motion, root_motion=root_motion, placement=(turns["b"], shifts["b"])),
                      "c": Clip(motion, root_motion=root_motion)}, 56, block)  # played together: one group
    for name in "ab":
        alone = _played({name: Clip(motion, root_motion=root_motion, placement=(turns[name], shifts[name]))}, 56, block)
        copy = _played({name: Clip(_placed_copy(motion, turns[name], shifts[name]), root_motion=root_motion)}, 56, block)
        for got in (placed[name], alone[name]):
            assert np.abs(quat.canonical_sign(got[0]) - quat.canonical_sign(copy[name][0])).max() < 1e-12
            assert np.abs(got[1] - copy[name][1]).max() < 1e-12
    unplaced = _played({"c": Clip(motion, root_motion=root_motion)}, 56, block)["c"]
    assert np.array_equal(placed["c"][0], unplaced[0]) and np.array_equal(placed["c"][1], unplaced[1])
    # the placement shows: the root turned about +Y and moved, the travel turned with it
    if root_motion:
        travel = placed["a"][1][-1] - placed["a"][1][0]
        assert np.allclose(travel, quat.rotate(turns["a"], unplaced[1][-1] - unplaced[1][0]), atol=1e-12)


def test_an_additive_placed_clip_adds_what_its_placed_copy_adds():
    sk = synthetic_character().skeleton
    motion = _walkish(sk)
    turn, shift = quat.from_axis_angle(UP, 0.9), np.array([0.4, 0.0, 0.2])
    got = _played({"a": Clip(motion, placement=(turn, shift))}, 30, 4, mode="additive")["a"]
    copy = _played({"a": Clip(_placed_copy(motion, turn, shift))}, 30, 4, mode="additive")["a"]
    assert np.abs(quat.canonical_sign(got[0]) - quat.canonical_sign(copy[0])).max() < 1e-12
    assert np.abs(got[1] - copy[1]).max() < 1e-12


@pytest.mark.parametrize("placement", [
    ((0.0, 0.0, 0.0, 2.0), (0.0, 0.0, 0.0)),  # not a unit quaternion
    (tuple(quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.5)), (0.0, 0.0, 0.0)),  # not about +Y
    ((0.0, 0.0, 0.0, 1.0), (0.0, np.nan, 0.0)),
    ((0.0, 0.0, 0.0, 1.0), (0.0, 0.0)),
])
def test_a_bad_placement_is_a_usage_error(placement):
    motion = _walkish(synthetic_character().skeleton, 4)
    with pytest.raises(UsageError, match="placement"):
        Clip(motion, placement=placement)
