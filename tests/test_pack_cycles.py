"""Recorded takes made usable as locomotion examples (:mod:`infuse.packs.cycles`): straightened,
aligned and closed cycles, the steadiest stride, transitions recognized by what they do; and packs
imported from SmartBody and Bandai sets built with them. Measured with FK."""
from __future__ import annotations

import math

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.motion import Motion
from infuse.packs.analysis import headings, locomotion_parameters
from infuse.packs.cycles import alignment, close_loop, steadiest_cycle, straighten, strides, transition_kind
from infuse.skeleton import Skeleton

from corpus_data import corpus_file

FPS = 30.0


def walker(turn_deg_s: float, frames: int = 61, moving_root: bool = True) -> Motion:
    """A pelvis with two hips and a knee-less leg each, walking a circle at 1.2 m/s turning
    ``turn_deg_s``, its hips swaying +-10 degrees twice a second; the travel on the root joint, or on
    a child of a still root joint."""
    names = ("root", "hips", "l_hip", "r_hip", "l_foot", "r_foot")
    parents = np.array([-1, 0, 1, 1, 2, 3])
    offsets = np.array([[0, 0, 0], [0, 0.9, 0], [0.1, 0, 0], [-0.1, 0, 0], [0, -0.85, 0], [0, -0.85, 0]], dtype=float)
    sk = Skeleton(names, parents, offsets, np.tile([0.0, 0.0, 0.0, 1.0], (6, 1)))
    t = np.arange(frames) / FPS
    w = math.radians(turn_deg_s)
    heading = w * t + math.radians(10.0) * np.sin(2 * math.pi * 2.0 * t)
    r = 1.2 / w if w else None
    path = (np.stack((r * (1 - np.cos(w * t)), 0 * t, r * np.sin(w * t)), axis=-1) if r
            else np.stack((0 * t, 0 * t, 1.2 * t), axis=-1))
    rot = np.tile([0.0, 0.0, 0.0, 1.0], (frames, 6, 1))
    yaw = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), heading)
    if moving_root:
        rot[:, 0] = yaw
        return Motion(sk, FPS, rot, path, name="walk")
    rot[:, 1] = yaw
    jt = np.tile(offsets, (frames, 1, 1))
    jt[:, 1] = path + offsets[1]
    return Motion(sk, FPS, rot, np.zeros((frames, 3)), jt, name="walk")


def measured(motion: Motion, cycle=(0, 60)) -> dict:
    _, pos = infuse.motion_fk(motion)
    index = {"base": 1, "l_hip": 2, "r_hip": 3}
    return locomotion_parameters(pos[:, 1], headings(pos, index), cycle, FPS)


@pytest.mark.parametrize("moving_root", [True, False])
def test_a_curving_take_is_straightened(moving_root):
    take = walker(20.0, moving_root=moving_root)
    before = measured(take)
    assert math.degrees(before["turn_rate"]) == pytest.approx(20.0, abs=0.5)
    straight = straighten(take, before, (0, 60), before["turn_rate"])
    after = measured(straight)
    assert abs(math.degrees(after["turn_rate"])) < 0.05
    assert after["speed"] == pytest.approx(1.2 * (1.0 if moving_root else 1.0), rel=0.01)  # the arc's length, now straight
    _, pos = infuse.motion_fk(straight)
    lateral = pos[:, 1, 0] - pos[0, 1, 0]
    assert np.abs(lateral).max() < 0.01  # a straight line


def test_a_walk_travelling_off_its_facing_is_aligned():
    take = walker(0.0)
    p = measured(take)
    p["direction"], p["lateral_speed"] = math.radians(6.0), 1.2 * math.sin(math.radians(6.0))  # as if the hips faced 6 deg off
    assert alignment(p["direction"]) == pytest.approx(math.radians(6.0))
    assert alignment(math.radians(170.0)) == pytest.approx(math.radians(-10.0))
    assert alignment(math.radians(40.0)) == 0.0  # a strafe stays one
    turned = straighten(take, p, (0, 60), 0.0, alignment(p["direction"]))
    h = headings(infuse.motion_fk(turned)[1], {"l_hip": 2, "r_hip": 3})
    h0 = headings(infuse.motion_fk(take)[1], {"l_hip": 2, "r_hip": 3})
    assert np.degrees(h - h0) == pytest.approx(6.0, abs=1e-6)  # the body turned onto its travel, the path kept


def test_a_cycle_is_closed_into_a_loop():
    take = walker(0.0)
    bent = np.array(take.local_rotations)
    bent[:, 4] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.linspace(0.0, 0.4, take.num_frames))  # drifts 23 deg
    take = take.replace(local_rotations=bent)
    closed, gap = close_loop(take, (10, 40))
    assert gap == pytest.approx(math.degrees(0.4 * 30 / 60), abs=0.01)
    r = closed.local_rotations
    assert np.degrees(quat.angle_between(r[10], r[40])).max() < 1e-6
    assert np.degrees(quat.angle_between(r[:10], take.local_rotations[:10])).max() < 1e-9  # before the cycle: as it was


def test_the_steadiest_stride_of_a_take():
    steps = [{"foot": f, "strike": t} for f, t in (("left", 0.0), ("right", 0.5), ("left", 1.0), ("right", 1.5),
                                                    ("left", 2.0), ("right", 2.5), ("left", 3.0))]
    speeds = {(0, 30): 0.4, (30, 60): 1.2, (60, 90): 1.3}  # starting from standing
    assert steadiest_cycle(steps, speeds.get, FPS) in ((30, 60), (60, 90))
    assert steadiest_cycle([{"foot": "left", "strike": 0.0}], speeds.get, FPS) is None


def test_transitions_are_recognized_by_what_they_do():
    leg, f = 0.9, 60
    still = np.zeros((f, 3))
    walking = np.stack((np.zeros(f), np.zeros(f), np.linspace(0.0, 2.4, f)), axis=-1)
    ramp = np.clip(np.linspace(-0.5, 1.0, f), 0.0, None)  # standing for a third of the clip, then walking
    starting = np.stack((np.zeros(f), np.zeros(f), 2.4 * ramp), axis=-1)
    stopping = np.stack((np.zeros(f), np.zeros(f), 2.4 - 2.4 * ramp[::-1]), axis=-1)
    flat, turning = np.zeros(f), np.linspace(0.0, math.pi, f)
    flags = np.ones((f, 2), bool)
    assert transition_kind(flags, still, flat, FPS, leg, 0) == "none"
    assert transition_kind(flags, still, turning, FPS, leg, 3) == "turn"
    assert transition_kind(flags, walking, flat, FPS, leg, 4) is None
    assert transition_kind(flags, starting, flat, FPS, leg, 4) == "start"
    assert transition_kind(flags, stopping, flat, FPS, leg, 4) == "stop"
    assert transition_kind(flags, walking, flat, FPS, leg, 8) is None  # a take: walking throughout
    short = np.stack((np.zeros(f), np.zeros(f), np.linspace(0.0, 0.4, f)), axis=-1)
    assert transition_kind(flags, short, flat, FPS, leg, 2) == "step"


def test_a_start_that_turns_first_stands_on_both_feet():
    """A start that turns before its first step shifts its weight with both feet down: the pelvis moves
    0.2 leg lengths per second (SmartBody's turning starts), faster than a body standing still, so
    only the feet tell that it stands; a walk's double support does not last long enough to count."""
    leg, f = 0.9, 60
    shift = 0.2 * leg * np.arange(f) / FPS  # the weight shifting, then walking from frame 15 on
    pelvis = np.stack((np.zeros(f), np.zeros(f), np.where(np.arange(f) < 15, shift, shift[15] + 1.2 * (np.arange(f) - 15) / FPS)), axis=-1)
    flat = np.zeros(f)
    standing_first = np.ones((f, 2), bool)
    standing_first[15:20, 0] = standing_first[30:35, 1] = standing_first[45:50, 0] = False
    assert transition_kind(standing_first, pelvis, flat, FPS, leg, 3) == "start"
    walking = standing_first.copy()
    walking[4:8, 1] = False  # double support of 0.13 s: walking from the first frame
    assert transition_kind(walking, pelvis, flat, FPS, leg, 3) is None


def test_a_take_of_three_steps_strides_from_right_to_right():
    """A strafe recorded as right, left, right strikes has no left-to-left stride: its stride runs from
    right strike to right strike, keyed at the left strike between, the next right and one stride on."""
    three = [{"foot": "right", "strike": 0.4}, {"foot": "left", "strike": 0.8}, {"foot": "right", "strike": 1.2}]
    assert strides(three) == [(0.4, 1.2, [0.8, 1.2, 1.6])]
    assert steadiest_cycle(three, lambda s: 1.0, FPS) == (12, 36)
    four = three + [{"foot": "left", "strike": 1.6}]
    assert strides(four) == [(0.8, 1.6, [0.8, 1.2, 1.6])]  # left to left when there is one


def test_a_stride_with_a_leap_is_passed_over():
    """Of a take's strides, one whose right strike comes at two thirds of it (a leap: the flight before
    the landing long) is no cycle when the take has an even one, whatever their speeds."""
    take = [{"foot": "left", "strike": 0.0}, {"foot": "right", "strike": 0.5}, {"foot": "left", "strike": 1.0},
            {"foot": "right", "strike": 1.67}, {"foot": "left", "strike": 2.0}]
    assert steadiest_cycle(take, {(0, 30): 1.5, (30, 60): 2.2}.get, FPS) == (0, 30)
    assert steadiest_cycle(take[2:], lambda s: 2.2, FPS) == (30, 60)  # the only stride: taken


@pytest.fixture(scope="module")
def smartbody_as_bvh(tmp_path_factory):
    """SmartBody's MaleLocomotion motions written as BVH and imported as a third party's folder (no file
    name tells a start from a walk), and the same set mirrored, built."""
    import motion_variants as mv
    from infuse.packs import build_pack, import_bvh_folder

    root = tmp_path_factory.mktemp("smartbody_as_bvh")
    original = mv.read_set(sorted(corpus_file("smartbody/behaviorsets/MaleLocomotion/motions").glob("*.skm")), "sb")
    return {name: build_pack(import_bvh_folder(mv.write_set(s, root / "sets" / name), root / name, name=name))
            for name, s in (("original", original), ("mirrored", mv.mirrored(original)))}


def test_takes_imported_without_names_blend_only_steady_strides(smartbody_as_bvh):
    """The turning starts (both feet down 0.5 s while the weight shifts) are starts, the take from idle to
    walk and the one from stop to walk (one or two steps, ends 50 degrees apart) are not blended, and the
    strafes of three steps (no left-to-left stride) are. Before, the turning starts were blended as
    cycles turning 41-85 deg/s, and the mirrored set's walks to a target 135 degrees away jumped 0.4 m
    sideways within 0.3 s and looped."""
    for pack in smartbody_as_bvh.values():
        clips = {c["name"]: c for c in pack.analysis["clips"]}
        for name in ("ChrUtah_Idle01_ToWalk01_Turn180Lf01", "ChrUtah_Idle01_ToWalk01_Turn90Lf01"):
            assert clips[name]["transition"] == "start", (pack.name, name)
        blended = set(pack.analysis["tessellations"]["locomotion"]["labels"])
        assert not blended & {"ChrUtah_Idle001_ToWalk001", "ChrUtah_StopToWalkRt01"}
        assert {"ChrUtah_StrafeFastLf01", "ChrUtah_StrafeSlowLf01", "ChrUtah_StrafeFastRt01", "ChrUtah_StrafeSlowRt01"} <= blended


def test_a_walk_with_a_jump_blends_its_walking_stride(smartbody_as_bvh):
    """SmartBody's walk and run with a jump each hold one stride with the leap (the other foot striking at
    64-67% of it, the pelvis rising 26 cm): it was the walk's cycle, a 2.17 m/s "jog" that leapt, and a walk
    asked at 2.2 m/s bounced its pelvis 23 cm. Their even strides are the cycles (1.51 and 4.18 m/s)."""
    for pack in smartbody_as_bvh.values():
        clips = {c["name"]: c for c in pack.analysis["clips"]}
        for name in ("ChrUtah_WalkJumpWalk01", "ChrUtah_RunJumpRun01"):
            c = clips[name]
            left, right, _ = c["keys"]
            a, b = c["cycle"]
            assert abs((right - left) * c["fps"] / (b - a) - 0.5) <= 0.1, (pack.name, name, c["keys"], c["cycle"])


def test_a_standing_take_is_the_idle_of_a_set_without_names(smartbody_as_bvh, imported):
    """A folder naming no roles still has an idle: the longest take standing still throughout (both feet
    down, the feet and pelvis staying put, the hands within 0.2 leg lengths of where they mostly are),
    closed into a loop. SmartBody's idle (its hands 0.002 leg lengths) is; Bandai's wave and raised hand
    (0.6 and more) and SmartBody's foot lifts (shorter) are not."""
    for pack in smartbody_as_bvh.values():
        clips = {c["name"]: c for c in pack.analysis["clips"]}
        idle = clips["ChrUtah_Idle001"]
        assert idle["role"] == "idle" and idle["loop"] and "transition" not in idle
        assert [c["name"] for c in clips.values() if c["role"] == "idle"] == ["ChrUtah_Idle001"]
        assert "ChrUtah_Idle001" in pack.analysis["tessellations"]["locomotion"]["labels"]
    _, bandai = imported
    assert not [c["name"] for c in bandai.analysis["clips"] if c["role"] == "idle"]


def test_a_mirrored_set_walks_to_targets_without_loops(smartbody_as_bvh):
    """The mirrored set's walks to targets 135 degrees to the left (which looped, 386-405 degrees turned,
    path 1.17x): no loop, paths at most 1.15x, within 5 cm (measured: 82-89 degrees, 1.04-1.07x)."""
    from infuse.packs.walk_test import trial_pack

    character = infuse.Character("Xbot", infuse.load(corpus_file("runxaway-models/Xbot.glb")))
    trial = trial_pack(character, smartbody_as_bvh["mirrored"], speeds=[1.3], distances=(2.0, 4.0), angles=(135.0,))
    for t in trial.targets:
        assert not t.loops and t.path_ratio <= 1.15 and t.miss_m <= 0.05, t


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """SmartBody's FemaleLocomotion and Bandai dataset-2's normal style, imported and built."""
    from infuse.packs import build_pack, import_bvh_folder, import_smartbody

    root = tmp_path_factory.mktemp("imported")
    female = build_pack(import_smartbody(corpus_file("smartbody/behaviorsets/FemaleLocomotion"), root / "female"))
    bandai = build_pack(import_bvh_folder(corpus_file("bandai/Bandai-Namco-Research-Motiondataset-2/data"), root / "d2",
                                          pattern="dataset-2_*_normal_*.bvh"))
    return female, bandai


def test_imported_transitions_are_recognized_and_not_blended(imported):
    female, bandai = imported
    clips = {c["name"]: c for c in female.analysis["clips"]}
    assert clips["Turn90Lf01"]["transition"] == "turn" and clips["Turn180Rt01"]["transition"] == "turn"
    assert clips["Idle01_ToWalk01"]["transition"] == "start" and clips["Walk01_ToIdle01"]["transition"] == "stop"
    assert clips["Idle01_StepForwardLf01"]["transition"] == "step"
    blended = set(female.analysis["tessellations"]["locomotion"]["labels"])
    assert not blended & {n for n, c in clips.items() if c.get("transition")}
    others = {c["name"]: c for c in bandai.analysis["clips"]}
    wave = others["dataset-2_wave-right-hand_normal_001"]
    assert wave["transition"] == "none" and wave["role"] == "other"
    assert any("not locomotion" in line for line in bandai.analysis["report"])


def test_imported_takes_become_straight_closed_cycles(imported):
    _, bandai = imported
    for c in bandai.analysis["clips"]:
        if c["role"] != "cycle":
            continue
        p = c["parameters"]
        made = c["derived"]
        if abs(made.get("straightened_deg_s", 0.0)) > 0.0:
            assert abs(math.degrees(p["turn_rate"])) < 0.5, c["name"]
        if made.get("aligned_deg"):
            assert abs(math.degrees(p["direction"])) < 0.5, c["name"]
        assert c["cycle"][1] > c["cycle"][0]
    motions = bandai.motions
    walk = next(c for c in bandai.analysis["clips"] if c["name"] == "dataset-2_walk_normal_001")
    a, b = walk["cycle"]
    r = motions[walk["name"]].local_rotations
    assert np.degrees(quat.angle_between(r[a, 2:], r[b, 2:])).max() < 0.5  # the loop closes below the pelvis
    assert bandai.analysis["coverage"]["top"][0] > 3.0  # its run, straight ahead
