"""Starts from the cycles, measured on the output with FK: while the idle fades out under the walk's
first step, a foot whose heel the blended pose lifts is held by its ball, not by its ankle (the ball
swept forward along the ground: SmartBody's MaleLocomotion set, which has no start clip, on Brad),
and a foot on its ball keeps it on the ground, not in it (the built-in packs); a walk's foot skate
split by its parts adds up to the whole walk's."""
from __future__ import annotations

import math

import numpy as np
import pytest

import infuse
from infuse import footing
from infuse.contacts import FootContacts, foot_contacts, sole_positions
from infuse.metrics import foot_skate
from infuse.packs.walk_test import PARTS, trial_pack, walk_parts
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file, require_corpus
from pack_support import smartbody_space

pytest.importorskip("infuse_locomotion")
FPS = 30
#: A sole point counts as sliding while within this height (m) of its planted height at both ends of a frame.
LOW_M = 0.003


def test_a_foot_the_pose_lifts_off_its_heel_is_held_by_its_ball():
    """Flags that hold a foot down without telling heel from ball (both half down, as the idle's fading
    share gives) hold it by the ankle, unless the pose has lifted its heel; a foot without a ball stays
    on its ankle, and a foot the flags let go stays free."""
    heel = np.array([[0.7, 0.7, 0.3]])
    ball = np.array([[0.7, 0.7, 0.3]])
    has_ball = np.array([True, False, True])
    assert footing.anchors(heel, ball, has_ball).tolist() == [[footing.ANKLE, footing.ANKLE, footing.FREE]]
    risen = np.array([[True, True, True]])
    assert footing.anchors(heel, ball, has_ball, risen).tolist() == [[footing.BALL, footing.ANKLE, footing.FREE]]
    still = np.array([[False, False, False]])
    assert footing.anchors(heel, ball, has_ball, still).tolist() == footing.anchors(heel, ball, has_ball).tolist()


def lifted_foot(frames: int = 30) -> tuple[np.ndarray, FootContacts]:
    """Positions (F, 3, 3) of root, ankle and ball of one foot flagged planted throughout: still on the
    ground for the first half, then 5 cm up (above the skate measure's lift) moving 1 cm a frame; the
    root walks 1 m."""
    pos = np.zeros((frames, 3, 3))
    pos[:, 0, 2] = np.linspace(0.0, 1.0, frames)
    pos[:, 1] = (0.0, 0.09, 0.0)
    pos[:, 2] = (0.0, 0.03, 0.11)
    half = frames // 2
    pos[half:, 1:, 1] += 0.05
    pos[half:, 1:, 2] += 0.01 * np.arange(1, frames - half + 1)[:, None]
    found = FootContacts(np.array([1, 2]), np.array([0, 0]), np.ones((frames, 2), dtype=bool), 0.0, 0.85,
                         np.zeros((frames, 2)))
    return pos, found


def test_skate_split_by_steps_takes_the_planted_height_of_the_whole_clip():
    """The lifted half, measured on its own, would take its own height as planted and count all of
    its travel; split by steps it keeps the whole clip's planted height (the ground), lies above the
    lift and counts nothing, and the parts add up to the whole."""
    pos, found = lifted_foot()
    halves = np.arange(1, len(pos)) >= len(pos) // 2
    whole = foot_skate(pos, found, 0).travel
    first, second = (foot_skate(pos, found, 0, steps=s).travel for s in (~halves, halves))
    assert first + second == pytest.approx(whole)
    assert second < 0.001  # only the step up counts, a little
    alone = FootContacts(found.points, found.foot_of_point, found.flags & (np.arange(len(pos)) >= len(pos) // 2)[:, None],
                         found.ground, found.leg_length, found.lowest)
    assert foot_skate(pos, alone, 0).travel > 0.1  # the old split: the lifted half's own height taken as planted


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


def test_a_walks_parts_add_up_to_the_whole(xbot):
    """Foot skate of walks to targets over their parts (on the spot, start, walk, stop, settle) adds
    up to the whole walk's, the built-in pack on Xbot."""
    trial = trial_pack(infuse.Character("x", xbot), "locomotion-male", speeds=[1.2], distances=(4.0,), angles=(0.0, 135.0))
    for t in trial.targets:
        assert set(t.part_skate_cm) == set(PARTS)
        assert sum(t.part_skate_cm.values()) == pytest.approx(t.skate_cm, abs=1e-9)
        assert t.skate_cm > 0.0


@pytest.fixture(scope="module")
def brad():
    require_corpus()
    return infuse.load(corpus_file("smartbody/ChrBrad/ChrBrad.sk"))


@pytest.fixture(scope="module")
def male_space(brad, tmp_path_factory):
    """SmartBody's MaleLocomotion set imported, built and infused onto Brad."""
    return smartbody_space(brad, "MaleLocomotion", tmp_path_factory.mktemp("packs"))


def start_slide(asset, pack, target, seconds: float) -> np.ndarray:
    """(S, 2) metres each foot's sole slides in each frame of the start of a walk to ``target``: the
    farthest a sole point (:func:`infuse.contacts.sole_positions`) moves horizontally while within
    :data:`LOW_M` of its planted height at both ends of the frame, over the frames
    :func:`~infuse.packs.walk_test.walk_parts` calls the start."""
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("b", asset))
    rt.activate(name, controller("locomotion", pack=pack, speed=1.3, target=target), 0.0)
    rt.run(seconds)
    m, rig = rt.motion(name), rt.rig(name)
    g_rot, g_pos = infuse.motion_fk(m)
    found = foot_contacts(m, rig.mapping, fk=(g_rot, g_pos))
    sole = sole_positions(found, g_pos[:, found.points])
    height = sole[..., 1]
    planted = np.nanpercentile(np.where(found.flags, height, np.nan), 5.0, axis=0)
    low = height - planted < LOW_M
    moved = np.linalg.norm(np.diff(sole[..., [0, 2]], axis=0), axis=-1) * (low[1:] & low[:-1])
    per_foot = np.stack([moved[:, found.foot_of_point == k].max(axis=1) for k in (0, 1)], axis=1)
    start = walk_parts(g_pos[:, rig.joint("base")][:, [0, 2]])[1:] == PARTS.index("start")
    assert start.sum() > 10  # the walk does start from standing
    return per_foot[start]


@pytest.mark.parametrize("angle_deg", [0.0, 45.0])
def test_a_start_from_the_cycles_keeps_its_feet_still(brad, male_space, angle_deg):
    """The set has no start clip: its first steps blend out of the idle. Walking 4 m ahead and 4 m at
    45 degrees, neither foot slides more than 1.5 cm in all over the start, nor 5 mm in a frame (at
    45 degrees the right foot's ball swept 8.3 cm forward, up to 2.2 cm a frame, while its heel rose
    about a held ankle, and the left foot turned about its heel with the turn the idle's share of
    the pose does not show: 9.9 cm in all)."""
    target = (4.0 * math.sin(math.radians(angle_deg)), 4.0 * math.cos(math.radians(angle_deg)))
    slide = start_slide(brad, male_space, target, 12.0)
    assert slide.sum() < 0.015 and slide.max() < 0.005


@pytest.mark.parametrize("angle_deg", [0.0, 45.0])
def test_a_built_in_packs_start_keeps_its_feet_still(brad, angle_deg):
    """The built-in pack's first step from standing pushed the ball of the foot leaving the ground up
    to 2 cm into it, and let it go still down: it slid 3.3 cm in one frame (3.7 cm over the start 4 m
    ahead, 6.5 at 45 degrees)."""
    target = (4.0 * math.sin(math.radians(angle_deg)), 4.0 * math.cos(math.radians(angle_deg)))
    slide = start_slide(brad, "locomotion-male", target, 12.0)
    assert slide.sum() < 0.02 and slide.max() < 0.005
