"""Blinks: human rates, the closure curve on morph targets, eyelid joints, and what is missing."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import Character, quaternions as quat
from infuse.mapping import map_skeleton
from infuse.runtime import Runtime
from infuse_blink import RATES_PER_MIN, Blink, BlinkSchedule, closure

from corpus_data import corpus_file
from runtime_characters import corpus_character


@pytest.mark.parametrize("activity", sorted(RATES_PER_MIN))
def test_rates_are_human(activity):
    rate = RATES_PER_MIN[activity]
    starts = BlinkSchedule(60.0 / rate, 0.35, seed=5).until(3600.0)
    per_minute = np.sum(starts < 3600.0) / 60.0
    assert per_minute == pytest.approx(rate, rel=0.05)
    assert np.diff(starts).min() >= 0.35 - 1e-9


def test_closure_curve():
    t = np.array([-0.1, 0.0, 0.0415, 0.083, 0.125, 0.167, 0.25, 0.3])
    assert np.allclose(closure(t), [0, 0, 0.5, 1.0, 0.665, 0.33, 0.0, 0.0], atol=1e-3)


def test_morph_targets_of_the_rpm_avatar_follow_the_curve():
    rt = Runtime(fps=60)
    rt.add_character(corpus_character("rpm"), name="rpm")
    blink = Blink("conversation", seed=2)
    rt.activate("rpm", blink, 0.0)
    rt.run(20.0)
    played = rt.motion("rpm")
    assert set(played.morph_names) == {"eyeBlinkLeft", "eyeBlinkRight"}
    left = played.morph_weight("eyeBlinkLeft")
    assert np.array_equal(left, played.morph_weight("eyeBlinkRight"))
    starts = rt.activities[0].binding.schedule.until(20.0)
    expected = np.zeros_like(left)
    for s in starts[starts < 20.0]:
        expected = np.maximum(expected, closure(played.frame_times - s))
    assert np.allclose(left, expected)
    assert 4 <= len(starts[starts < 20.0]) <= 16 and left.max() > 0.9


def test_a_vrm_blink_expression_without_morph_targets_is_left_alone(tmp_path):
    """This VRM's ``blink`` expression binds materials only: the blink drives nothing it cannot show,
    and the character is written after blinking."""
    asset = infuse.load(corpus_file("vrm-specification/samples/VRMC_vrm_expressions_isBinary_Overrides/vrm/"
                                    "VRMC_vrm_expressions_isBinary_Overrides.vrm"))
    assert "blink" in asset.meta["vrm_expressions"] and "blink" not in asset.morph_targets
    rt = Runtime(fps=30)
    rt.add_character(Character("vrm", asset, mapping=map_skeleton(asset)))
    rt.activate("vrm", Blink(rate_per_min=30, seed=1), 0.0)
    rt.run(10.0)
    assert rt.motion("vrm").morph_names == ()
    infuse.save(rt.export("vrm", "blinking"), tmp_path / "vrm.glb")
    assert list(infuse.load(tmp_path / "vrm.glb").motions) == ["blinking"]


def test_eyelid_joints_close_when_there_are_no_morph_targets():
    rt = Runtime(fps=30)
    rt.add_character(corpus_character("utah"), name="utah")
    rt.activate("utah", Blink(rate_per_min=40, seed=4), 0.0)
    rt.run(10.0)
    sk = rt.rig("utah").skeleton
    lid = sk.index["upper_eyelid_left"]
    angle = np.degrees(quat.angle_between(rt.motion("utah").local_rotations[:, lid], sk.rest_rotations[lid]))
    assert angle.max() == pytest.approx(30.0, abs=3.0) and np.median(angle) < 1e-6


def test_a_character_without_eyelids_is_reported():
    rt = Runtime(fps=30)
    rt.add_character(corpus_character("xbot"), name="xbot")
    rt.activate("xbot", Blink(), 0.0)
    rt.run(1.0)
    assert ("xbot", "has no eyelid morph targets or joints: blinks are not shown") in rt.notes
