"""Noisy takes are low-passed before a locomotion pack is built from them (infuse.packs.denoise); clean
takes are left exactly as they are."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.contacts import feet, position_noise
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.packs import build_pack
from infuse import quaternions as quat
from infuse.packs.cycles import closest_loop_end
from infuse.packs.denoise import denoised, low_passed, noise_frames
from infuse.packs.importers import import_bvh_folder
from infuse.packs.walk_test import trial_pack

import motion_variants as mv
from corpus_data import corpus_file, require_corpus

SMARTBODY = ("smartbody/behaviorsets/MaleLocomotion/motions", "*.skm")


@pytest.fixture(scope="module")
def smartbody():
    folder, pattern = SMARTBODY
    return mv.read_set(sorted((require_corpus() / folder).glob(pattern)), "sb-male")


@pytest.fixture(scope="module")
def pair(smartbody):
    sk = smartbody.skeleton
    return feet(sk, map_skeleton(infuse.Asset(None, "bvh", sk, dict(smartbody.takes))))


def test_clean_takes_are_left_as_they_are(smartbody, pair):
    for take in ("ChrUtah_Walk001", "ChrUtah_Run001", "ChrUtah_Turn90Lf01", "ChrUtah_Idle001"):
        motion = smartbody.takes[take]
        assert noise_frames(motion, pair) == 1
        out, half = denoised(motion, pair)
        assert out is motion and half == 1


def test_a_fast_clean_take_is_left_as_it_is():
    """A dash's feet are seldom at rest, so the noise measure reaches frames where they still move: Bandai
    dataset-1's masculine dash measures 1.9 mm (0.0024 leg lengths), 3.8 mm resampled to 24 fps, and was
    low-passed over 5 frames; the walks beside it measure 0.1 mm. Below 0.006 leg lengths a take is clean."""
    take = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_dash_masculinity_001.bvh")
    asset = infuse.load(take)
    motion = next(iter(asset.motions.values()))
    dash = feet(asset.skeleton, map_skeleton(asset))
    for m in (motion, mv.sample(motion, np.arange(0.0, motion.duration, 1.0 / 24.0) * motion.fps, 24.0)):
        assert noise_frames(m, dash) == 1
        assert denoised(m, dash)[0] is m


def test_a_noisy_take_is_brought_back_toward_its_clean_poses(smartbody, pair):
    noisy = mv.variant(smartbody, "jitter")
    feet_points = [j for f in pair for j in f.points]
    for take in ("ChrUtah_Walk001", "ChrUtah_Turn90Lf01"):
        clean = motion_fk(smartbody.takes[take])[1]
        before = noisy.takes[take]
        after, half = denoised(before, pair)
        assert half > 1
        moved_before = motion_fk(before)[1]
        moved_after = motion_fk(after)[1]
        error_before = np.linalg.norm(moved_before - clean, axis=-1).mean()
        error_after = np.linalg.norm(moved_after - clean, axis=-1).mean()
        assert error_after < 0.6 * error_before, (take, error_before, error_after)  # Walk001: 28 -> 15 mm
        assert position_noise(moved_after[:, feet_points]) < 0.3 * position_noise(moved_before[:, feet_points])
        np.testing.assert_allclose(np.linalg.norm(after.local_rotations, axis=-1), 1.0, atol=1e-9)


def test_low_pass_keeps_quadratics_and_short_clips():
    t = np.arange(20.0)[:, None] * np.array([[1.0, -2.0]])
    values = 0.5 * t ** 2 + 3.0 * t + 1.0
    np.testing.assert_allclose(low_passed(values, 3), values, atol=1e-9)
    short = np.arange(5.0)[:, None] ** 3
    np.testing.assert_array_equal(low_passed(short, 3), short)


@pytest.fixture(scope="module")
def noisy_walks(smartbody, tmp_path_factory):
    """Worst figures of the SmartBody set on X Bot, as recorded and with rotation noise, over walks to
    targets 4 m away."""
    work = tmp_path_factory.mktemp("denoise")
    xbot = infuse.Character("Xbot", infuse.load(corpus_file("runxaway-models/Xbot.glb")))
    out = {}
    for name in ("original", "jitter"):
        motion_set = smartbody if name == "original" else mv.variant(smartbody, name)
        pack = build_pack(import_bvh_folder(mv.write_set(motion_set, work / "sets" / name), work / "packs" / name, name=name))
        out[name] = trial_pack(xbot, pack, speeds=[1.3], distances=(4.0,), angles=(0.0, 90.0, 180.0, -90.0)).worst()
    return out


def test_a_noisy_cycle_ends_on_the_pose_nearest_its_first():
    """Strikes found through noise may be a frame or two off: the loop ends, within the low-pass's reach,
    on the frame whose pose comes nearest the first."""
    period = 32
    t = np.arange(100)
    angles = np.stack([0.4 * np.sin(2 * np.pi * t / period + k) for k in range(4)], axis=1)  # (F, 4 joints)
    rot = quat.from_rotvec(angles[..., None] * np.array([1.0, 0.0, 0.0]))
    assert closest_loop_end(rot, (10, 40), 3) == 42
    assert closest_loop_end(rot, (10, 40), 0) == 40


def test_a_noisy_set_walks_to_targets_with_little_more_skate(noisy_walks):
    """Rotation noise on every joint cost a whole walk to a target 4 m away up to 95 cm of foot skate
    (turns on the spot and starts played noise and all, cycles closed over noisy poses); low-passed,
    11.7 cm against 3.2 for the set as recorded (what is left: the noise the low-pass leaves in the
    transitions, which are played as they are). Since a flat foot held by its heel keeps its heading:
    11.0 against 2.1; since takes that start by turning are told by their feet (starts, not blended) and
    strafes of three steps stride from right to right: 12.4 against 1.8, nearly all of it the noisy turn
    on the spot to the right and the first steps after it (4.8 and 7.4 cm; 4.0 and 6.8 before, the same
    clip among differently retargeted examples). The noise adds at most 11 cm to a whole walk."""
    clean, noisy = noisy_walks["original"], noisy_walks["jitter"]
    assert noisy["miss_m"] <= 0.05 and noisy["loops"] == 0, noisy
    assert noisy["target_skate_cm"] <= clean["target_skate_cm"] + 11.0, (clean, noisy)
