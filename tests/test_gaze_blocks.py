"""Two characters gazing at each other give the same frames whatever the evaluation block size.

Each one's target is the other's face as a first pass of the block places it; that pass carries its
own smoothing from block to block, so where blocks begin does not change the result.
"""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.scene import Scene

from runtime_characters import synthetic_character

BLOCKS = (7, 45, 150)


def mutual_gaze(block_frames: int) -> dict[str, np.ndarray]:
    """Local rotations (F, J, 4) of two breathing, blinking characters 1.8 m apart looking at each
    other's face, each turning about 34 degrees (one with the waist, the other with the shoulders), 4 s
    in blocks of ``block_frames``."""
    scene = Scene(fps=30.0, quiet=True, block_frames=block_frames)
    scene.add_character(synthetic_character("ann"), "ann", position=(0.0, 0.0, 0.0), facing=0.0)
    scene.add_character(synthetic_character("bob"), "bob", position=(1.0, 0.0, 1.5), facing=180.0)
    scene.gaze("ann", "bob", at=0.0, influence="WAIST")
    scene.gaze("bob", "ann", at=0.4, influence="SHOULDER")
    scene.run(4.0)
    return {name: scene.motion(name).local_rotations for name in ("ann", "bob")}


@pytest.fixture(scope="module")
def runs():
    return {block: mutual_gaze(block) for block in BLOCKS}


@pytest.mark.parametrize("block", BLOCKS[:-1])
def test_mutual_gaze_does_not_depend_on_the_block_size(runs, block):
    for name, rotations in runs[BLOCKS[-1]].items():
        other = runs[block][name]
        assert other.shape == rotations.shape == (120,) + rotations.shape[1:]
        assert np.degrees(quat.angle_between(rotations, other)).max() < np.degrees(1e-6), name


def test_the_characters_did_turn_toward_each_other(runs):
    character = synthetic_character()
    for name, rotations in runs[BLOCKS[-1]].items():
        for joint in ("spine3", "skullbase"):
            j = character.skeleton.index[joint]
            turned = np.degrees(quat.angle_between(rotations[0, j], rotations[-1, j]))
            assert turned > 2.0, f"{name}'s {joint} hardly moved ({turned:.2f} degrees): the test would show no block effect"
