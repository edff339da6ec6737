"""infuse.grounding: how low a character's feet go, soles included, and clips moved onto y = 0."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from corpus_data import corpus_file, require_corpus
from infuse.contacts import feet
from infuse.grounding import foot_height, grounded, on_ground, sole_depth
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton

BRAD = "smartbody/mesh/brad/Brad.dae"
UTAH = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
SOLDIER = "colesam-uploads/Soldier.glb"


@pytest.fixture(scope="module")
def brad():
    require_corpus()
    asset = infuse.load(corpus_file(BRAD))
    return asset, map_skeleton(asset)


def test_brad_stands_a_metre_down_and_his_soles_reach_below_his_toe_joints(brad):
    asset, mapping = brad
    depth = sole_depth(asset, feet(asset.skeleton, mapping))
    assert 0.002 < depth < 0.03  # the shoe's sole under the toe and ankle joints
    assert foot_height(asset, mapping) == pytest.approx(-1.008, abs=0.005)
    clip = asset.motions["Brad"]
    assert foot_height(asset, mapping, clip, sole=depth) == pytest.approx(foot_height(asset, mapping, clip))


def test_grounded_moves_the_whole_clip_rigidly_onto_the_ground(brad):
    asset, mapping = brad
    clip = asset.motions["Brad"]
    height = foot_height(asset, mapping, clip)
    up = grounded(clip, height)
    assert foot_height(asset, mapping, up) == pytest.approx(0.0, abs=1e-9)
    shift = motion_fk(up)[1] - motion_fk(clip)[1]
    assert np.allclose(shift, [0.0, -height, 0.0], atol=1e-9)
    assert np.array_equal(up.local_rotations, clip.local_rotations)


def test_a_skeleton_without_a_mesh_stands_on_its_lowest_foot_joint():
    require_corpus()
    asset = infuse.load(corpus_file(UTAH))
    mapping = map_skeleton(asset)
    assert sole_depth(asset, feet(asset.skeleton, mapping)) == 0.0
    assert foot_height(asset, mapping) == pytest.approx(asset.skeleton.rest_global_positions[:, 1].min(), abs=0.02)


def test_every_root_moves_and_a_character_without_legs_stays():
    require_corpus()
    asset = infuse.load(corpus_file(SOLDIER))
    assert len(asset.skeleton.roots) > 1
    clip = next(iter(asset.motions.values()))
    lifted = grounded(clip, -0.5)
    shift = motion_fk(lifted)[1] - motion_fk(clip)[1]
    assert np.allclose(shift, [0.0, 0.5, 0.0], atol=1e-9)  # joints under every root
    legless = {"base": asset.skeleton.names[0]}
    assert on_ground(asset, legless, clip) is clip
