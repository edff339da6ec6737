"""Transition clips played whole: a pack's starts and turns on the spot, from standing, with their own root
motion placed where the character stands and faces, handing over to the steering at their end. Measured on
the output with FK (SmartBody's FemaleLocomotion set on Xbot)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import infuse
from infuse.contacts import foot_contacts, sole_positions
from infuse.metrics import foot_skate
from infuse.packs import build_pack, import_smartbody, infuse_character
from infuse.packs.analysis import TRANSITION_END_S, headings
from infuse.packs.walk_test import PARTS, walk_parts
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file, require_corpus

infuse_locomotion = pytest.importorskip("infuse_locomotion")
transitions = infuse_locomotion.transitions
Locomotion = infuse_locomotion.Locomotion
FPS = 30


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


@pytest.fixture(scope="module")
def space(xbot, tmp_path_factory):
    """SmartBody's FemaleLocomotion set imported, built and infused onto Xbot (through a cache)."""
    folder = import_smartbody(corpus_file("smartbody/behaviorsets/FemaleLocomotion"), tmp_path_factory.mktemp("packs") / "female",
                              name="sb-female")
    build_pack(folder)
    cache = tmp_path_factory.mktemp("cache")
    infuse_character(infuse.Character("x", xbot), [str(folder)], cache=cache)
    again = infuse_character(infuse.Character("x", xbot), [str(folder)], cache=cache)
    assert again.cached
    return next(iter(again.spaces.values()))


def walk(xbot, space, target, seconds):
    """The output motion, root joint ground path (F, 2) and pelvis ground path (F, 2) of a walk to ``target``."""
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("x", xbot))
    rt.activate(name, controller("locomotion", pack=space, speed=0.5, target=target), 0.0)
    rt.run(seconds)
    m = rt.motion(name)
    rig = rt.rig(name)
    _, pos = infuse.motion_fk(m)
    return m, pos, rig


def arrival_s(pelvis: np.ndarray, target) -> float:
    """Seconds until the pelvis ground path (F, 2) is within 5 cm of ``target`` for good."""
    away = np.nonzero(np.linalg.norm(pelvis - np.asarray(target), axis=-1) > 0.05)[0]
    return (away[-1] + 1) / FPS if away.size else 0.0


def test_infused_transitions_carry_their_kind_and_are_kept_whole(space):
    clips = space.clips
    assert clips["Idle01_ToWalk01"].transition == "start" and clips["Walk01_ToIdle01"].transition == "stop"
    assert clips["Turn90Lf01"].transition == "turn" and clips["Turn180Rt01"].transition == "turn"
    assert clips["Walk01"].transition is None and clips["Idle01_StepForwardLf01"].transition is None  # a step is not played
    start = clips["Idle01_ToWalk01"]
    assert start.motion.num_frames == 81  # the whole take (2.67 s), not a cycle of it
    p = start.parameters
    assert p["travel_z"] > 1.0 and abs(p["travel_x"]) < 0.2 and abs(math.degrees(p["turn"])) < 15.0
    assert p["speed_start"] < p["speed_end"]
    assert math.degrees(clips["Turn90Lf01"].parameters["turn"]) == pytest.approx(90.0, abs=15.0)
    assert math.degrees(clips["Turn90Rt01"].parameters["turn"]) == pytest.approx(-90.0, abs=15.0)
    assert math.hypot(clips["Turn90Lf01"].parameters["travel_x"], clips["Turn90Lf01"].parameters["travel_z"]) < 0.1
    played = transitions.played(space, 0.1)
    assert {c.transition for c in played} == {"start", "turn", "stop"}
    # A turn that walks off at its end is not one that leaves the character standing.
    assert "Idle01_ToWalk01_Turn360Rt01" not in {c.name for c in played}


def test_a_walk_from_standing_plays_the_start_whole_then_steers(xbot, space):
    target = (0.0, 5.0)
    m, pos, rig = walk(xbot, space, target, 14.0)
    clip = space.clips["Idle01_ToWalk01"]
    hand = transitions.handover_s(clip, FPS)
    frames = int(round(hand * FPS))
    expected = transitions.placed_root(clip, transitions.placement(clip, 0.0, 0.0, 0.0, 0.5), np.arange(frames) / FPS, FPS)
    pelvis = pos[:, rig.joint("base")][:, [0, 2]]
    assert np.abs(pelvis[:frames] - expected).max() < 1e-6  # its own root motion, its pelvis placed at the origin
    assert np.linalg.norm(pelvis[-15:].mean(axis=0) - target) < 0.05
    length = np.linalg.norm(np.diff(pelvis, axis=0), axis=-1).sum()
    assert length < 1.15 * 5.0
    # The feet carry on through the handover: no foot moves much more in a frame there than it does walking
    # (SmartBody female's Walk01 and Walk02 coincide in the blend space and share their weight: the step
    # into their blend is 1.22 times the walking step's largest; into Walk01 alone it was 1.03).
    ankles = pos[:, [rig.joint("l_ankle"), rig.joint("r_ankle")]]
    step = np.linalg.norm(np.diff(ankles, axis=0), axis=-1).max(axis=1)
    around = step[frames - 5:frames + int(transitions.HANDOVER_S * FPS) + 5]
    walking = step[frames + 30:frames + 90]
    assert around.max() <= 1.25 * walking.max()


@pytest.mark.parametrize("angle, name", [(180.0, "Turn180Rt01"), (-90.0, "Turn90Rt01")])
def test_a_large_turn_from_standing_plays_the_nearest_turn_on_the_spot(xbot, space, angle, name):
    target = (4.0 * math.sin(math.radians(angle)), 4.0 * math.cos(math.radians(angle)))
    m, pos, rig = walk(xbot, space, target, 18.0)
    clip = space.clips[name]
    frames = int(round(transitions.handover_s(clip, FPS) * FPS))
    turned = np.unwrap(headings(pos, {"l_hip": rig.joint("l_hip"), "r_hip": rig.joint("r_hip")}))
    span = int(TRANSITION_END_S * FPS)
    change = np.degrees(turned[frames - span:frames].mean() - turned[:span].mean())
    assert change == pytest.approx(math.degrees(clip.parameters["turn"]), abs=10.0)
    pelvis = pos[:, rig.joint("base")][:, [0, 2]]
    assert np.linalg.norm(pelvis[:frames] - pelvis[0], axis=-1).max() < 0.3  # on the spot
    assert np.linalg.norm(pelvis[-15:].mean(axis=0) - target) < 0.05
    assert np.linalg.norm(np.diff(pelvis, axis=0), axis=-1).sum() < 1.15 * 4.0 + 0.3


def test_a_walk_ends_with_the_stop_clip_on_its_target(xbot, space, monkeypatch):
    placed = []
    original = transitions.stop_placement

    def record(clip, fps, x, z, target):
        placed.append((clip.name, original(clip, fps, x, z, target)))
        return placed[-1][1]

    monkeypatch.setattr(transitions, "stop_placement", record)
    target = (1.0, 5.0)
    _, pos, rig = walk(xbot, space, target, 16.0)
    (name, (_, _, _, scale, _)), = placed
    assert name == "Walk01_ToIdle01" and 1.0 / transitions.STOP_SCALES < scale < transitions.STOP_SCALES
    pelvis = pos[:, rig.joint("base")][:, [0, 2]]
    assert np.linalg.norm(pelvis[-15:].mean(axis=0) - target) < 0.01  # its travel scaled onto the target
    assert np.ptp(pelvis[-60:], axis=0).max() < 0.01  # and standing there


def test_transitions_are_placed_by_the_pelvis_on_a_rig_whose_root_sits_away_from_it(xbot, tmp_path):
    """X Bot with a root joint 0.85 m from its hips: its turn, start and stop clips start where its
    pelvis stands (placed about joint 0 they would jump by the offset) and it stands on its target."""
    from test_locomotion_feet import rooted_away

    folder = import_smartbody(corpus_file("smartbody/behaviorsets/FemaleLocomotion"), tmp_path / "female", name="sb-female")
    build_pack(folder)
    rooted = rooted_away(xbot, np.array([-0.45, -0.1, -0.72]))
    space = next(iter(infuse_character(infuse.Character("r", rooted), [str(folder)]).spaces.values()))
    target = (0.0, -4.0)
    _, pos, rig = walk(rooted, space, target, 18.0)
    pelvis = pos[:, rig.joint("base")][:, [0, 2]]
    assert np.linalg.norm(np.diff(pelvis, axis=0), axis=-1).max() < 0.05  # no jump at any handover
    assert np.linalg.norm(pelvis[-15:].mean(axis=0) - target) < 0.05


def test_the_plan_counts_the_transitions(xbot, space):
    """The walk's planned arrival is the output's, within a stride (the walk begins its stop clip at the
    clip's gait phase, the plan where it has as far to go), and its planned rest (what a scene's end time
    waits for) comes after it."""
    stride = max(c.keys[2] - c.keys[0] for c in space.group("locomotion") if c.role != "idle")
    for target in ((0.0, -4.0), (-4.0, 0.0), (0.0, 5.0)):
        plan = Locomotion(pack=space, speed=0.5, target=target).plan(FPS)
        _, pos, rig = walk(xbot, space, target, 18.0)
        measured = arrival_s(pos[:, rig.joint("base")][:, [0, 2]], target)
        assert plan.arrives_s == pytest.approx(measured, abs=stride)
        assert plan.rests_s > measured
    turn = space.clips["Turn180Rt01"]
    plan = Locomotion(pack=space, speed=0.5, target=(0.0, -4.0)).plan(FPS)
    assert plan.arrives_s > transitions.handover_s(turn, FPS) + 4.0 / 0.5  # the turn, then the walk


def test_landings_are_pinned_from_where_the_heel_reached_the_ground():
    """A foot landing moving: its heel reached the ground frames before the contact was found."""
    frames = 20
    phases = np.zeros((frames, 2, 2), dtype=bool)
    phases[10:, 0, :] = True  # the left foot lands at frame 10
    phases[:, 1, :] = True  # the right foot stands throughout
    heights = np.full((frames, 2, 2), 0.08)
    heights[:, :, 0] = 0.10
    heights[:10, 0, 0] = np.linspace(0.2, 0.10, 10)
    heights[7:10, 0, 0] = 0.101  # on the ground three frames early
    heights[:10, 0, 1] = np.linspace(0.2, 0.09, 10)
    out = transitions.grounded(phases, heights, 0.003, 0.01, 0.25)
    assert out[7:10, 0, 0].all() and not out[:7, 0, 0].any()
    assert not out[:10, 0, 1].any()  # the ball is not down early
    assert (out[:, 1] == phases[:, 1]).all()


def sole_slide(m, mapping) -> np.ndarray:
    """(F - 1, 2) metres each foot's sole slides on the ground in each frame of motion ``m``: the
    farthest a sole point (:func:`infuse.contacts.sole_positions`: the ball, the sole under the heel)
    moves horizontally while within 3 mm of its planted height at both ends of the frame."""
    g_rot, g_pos = infuse.motion_fk(m)
    found = foot_contacts(m, mapping, fk=(g_rot, g_pos))
    sole = sole_positions(found, g_pos[:, found.points])
    height = sole[..., 1]
    planted = np.nanpercentile(np.where(found.flags, height, np.nan), 5.0, axis=0)
    low = height - planted < 0.003
    moved = np.linalg.norm(np.diff(sole[..., [0, 2]], axis=0), axis=-1) * (low[1:] & low[:-1])
    return np.stack([moved[:, found.foot_of_point == k].max(axis=1) for k in (0, 1)], axis=1)


def test_a_turn_on_the_spot_turns_its_feet_off_the_ground(xbot, space):
    """Turn180Lf01 swivels its left foot 127 degrees on its heel, the ball sweeping the floor, then
    drags it on its ball: those feet are lifted while they turn (25.5 cm of sole slide in the turn
    before, on this walk)."""
    clip = space.clips["Turn180Lf01"]
    target = (4.0 * math.sin(math.radians(135.0)), 4.0 * math.cos(math.radians(135.0)))
    m, pos, rig = walk(xbot, space, target, 16.0)
    frames = int(round(transitions.handover_s(clip, FPS) * FPS))
    turned = np.unwrap(headings(pos, {"l_hip": rig.joint("l_hip"), "r_hip": rig.joint("r_hip")}))
    span = int(TRANSITION_END_S * FPS)
    assert np.degrees(turned[frames - span:frames].mean() - turned[:span].mean()) == pytest.approx(
        math.degrees(clip.parameters["turn"]), abs=15.0)  # this turn was played
    slide = sole_slide(m, rig.mapping)[:frames]
    assert slide.sum() < 0.02 and slide.max() < 0.005
    assert np.linalg.norm(pos[-15:, rig.joint("base")][:, [0, 2]].mean(axis=0) - target) < 0.05


def test_a_foot_sliding_flat_in_a_turn_is_lifted(xbot, space):
    """Turn180Lf01 slides its right foot flat on the floor at its end (about 12 cm at up to 0.57 m/s,
    faster than a foot lands, so its contacts break in the middle of it: two drags of 3 cm found, each
    too short to lift): a foot lying flat counts as down, the slide is lifted, and on the spot the walk
    2 m away at 135 degrees skates at most 1 cm (1.5 before; the project's foot skate on the frames
    :func:`~infuse.packs.walk_test.walk_parts` puts on the spot)."""
    target = (2.0 * math.sin(math.radians(135.0)), 2.0 * math.cos(math.radians(135.0)))
    m, pos, rig = walk(xbot, space, target, 12.0)
    found = foot_contacts(m, rig.mapping, fk=infuse.motion_fk(m))
    base = rig.joint("base")
    parts = walk_parts(pos[:, base][:, [0, 2]], 0.5)[1:]
    assert (parts == PARTS.index("on the spot")).sum() > 30  # it turns on the spot
    assert 100.0 * foot_skate(pos, found, base, steps=parts == PARTS.index("on the spot")).travel < 1.0


def test_a_start_eases_into_the_speed_of_the_walk_after_it(xbot, space):
    """Idle01_ToWalk01 ends at 0.69 m/s; walking on at 0.5 m/s, its travel eases down to 0.5 by the
    handover, so the pelvis does not slow from 0.69 to 0.39 m/s there (as it did)."""
    clip = space.clips["Idle01_ToWalk01"]
    assert clip.parameters["speed_end"] > 0.6
    _, pos, rig = walk(xbot, space, (0.0, 5.0), 14.0)
    frames = int(round(transitions.handover_s(clip, FPS) * FPS))
    pelvis = pos[:, rig.joint("base")][:, [0, 2]]
    window = 6  # 0.2 s: about a quarter of a stride, over which the sway mostly cancels
    speed = np.linalg.norm(pelvis[window:] - pelvis[:-window], axis=-1) * FPS / window
    around = speed[frames - 15:frames + 30]
    assert around.min() > 0.47 and around.max() < 0.56  # 0.45-0.70 before


def test_a_walk_evaluated_frame_by_frame_is_the_walk_evaluated_in_blocks(xbot, space):
    """The stop clip begins at its gait phase and the walk's last strides are paced for it from each
    frame's own phase: a walk evaluated a frame at a time (as live) plays the stop as in blocks."""
    out = []
    for block in (1, 150):
        rt = Runtime(fps=FPS, block_frames=block)
        name = rt.add_character(infuse.Character("x", xbot))
        rt.activate(name, controller("locomotion", pack=space, speed=0.5, target=(1.0, 5.0)), 0.0)
        rt.run(16.0)
        out.append(infuse.motion_fk(rt.motion(name))[1])
    assert np.abs(out[0] - out[1]).max() < 1e-4
