"""Gaze on four real characters, measured on the output motion with forward kinematics.

Eye (or, without eyes, head) forward directions come from each character's reference pose and mapping:
the rest pose when it stands upright, else the first frame of its clip (the Bandai BVH keeps every
bone along one axis at rest), held under the gaze.
"""
from __future__ import annotations


import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.runtime import Clip, Runtime
from infuse.runtime.swing import ellipse_scale, swing_angles
from infuse_gaze import GROUPS, Gaze
from infuse_gaze.model import GROUP_NAMES

from corpus_data import labels
from runtime_characters import CORPUS_CHARACTERS, body_axes, corpus_character, first_frame, reference_frame

KEYS = tuple(CORPUS_CHARACTERS)
#: (heading, pitch) degrees from the eyes in the character's frame, within every character's limits.
DIRECTIONS = ((0.0, 0.0), (35.0, 10.0), (-50.0, -15.0), (70.0, 20.0), (-85.0, 5.0), (20.0, -30.0))
DISTANCE_M = 2.0
FPS = 30.0


def look_joints(character) -> list[int]:
    """The joints whose forward is the gaze: both eyes, else the head."""
    m, sk = character.mapping, character.skeleton
    if m["eyeball_left"] and m["eyeball_right"]:
        return [sk.index[m["eyeball_left"]], sk.index[m["eyeball_right"]]]
    return [sk.index[m["skullbase"]]]


def setup(rt: Runtime, key: str, name: str, **place):
    """Add a copy of a corpus character, holding its reference pose when that is a clip frame."""
    character = corpus_character(key)
    rt.add_character(character, name=name, **place)
    _, _, held = reference_frame(character)
    if held:
        rt.activate(name, Clip(first_frame(next(iter(character.asset.motions.values())))), 0.0)
    return character


def target_at(character, heading_deg, pitch_deg, distance=DISTANCE_M):
    left, up, forward = body_axes(character)
    _, pos, _ = reference_frame(character)
    origin = pos[look_joints(character)].mean(axis=0)
    h, p = np.radians(heading_deg), np.radians(pitch_deg)
    return origin + distance * (np.cos(p) * (np.sin(h) * left + np.cos(h) * forward) + np.sin(p) * up)


def gaze_errors(character, motion, targets) -> np.ndarray:
    """(F,) degrees: the largest angle, over the look joints, between their forward and the direction to
    ``targets`` (F, 3) or (3,), on ``motion`` (the forward rotates with each joint from the reference pose)."""
    ref_rot, _, _ = reference_frame(character)
    _, _, forward = body_axes(character)
    g_rot, g_pos = infuse.motion_fk(motion)
    errors = []
    for j in look_joints(character):
        local = quat.rotate(quat.conjugate(ref_rot[j]), forward)
        f = quat.rotate(g_rot[:, j], local)
        d = np.asarray(targets) - g_pos[:, j]
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        errors.append(np.degrees(np.arccos(np.clip(np.sum(f * d, axis=-1), -1.0, 1.0))))
    return np.max(errors, axis=0)


@pytest.fixture(scope="module")
def static_runs():
    """Every character gazing at every direction (one copy each, all in one runtime), for 2.5 s."""
    rt = Runtime(fps=FPS)
    cases = []
    for key in KEYS:
        for k, (h, p) in enumerate(DIRECTIONS):
            name = f"{key}-{k}"
            character = setup(rt, key, name)
            target = target_at(character, h, p)
            rt.activate(name, Gaze(tuple(target)), 0.0)
            cases.append((key, name, character, target, (h, p)))
    rt.run(2.5)
    return rt, cases


@pytest.mark.parametrize("key", KEYS)
def test_gaze_error_after_settling_is_within_2_degrees(static_runs, key):
    rt, cases = static_runs
    for case_key, name, character, target, direction in cases:
        if case_key != key:
            continue
        errors = gaze_errors(character, rt.motion(name), target)
        assert errors[0] > 20 or direction == (0.0, 0.0)  # it really had to turn
        assert errors[-15:].max() <= 2.0, f"{name} {direction}: {errors[-15:].max():.2f} degrees"


def joint_offsets(rt, name, base_rotations):
    """Per gaze joint: (group, joints in the group, (F,) heading, pitch, roll radians) of the output's turn
    from the base pose, in the joint's aligned frame."""
    rig = rt.rig(name)
    out = rt.motion(name).local_rotations
    rows = []
    for group in GROUPS:
        present = [rig.joint(j) for j in group.joints if rig.joint(j) is not None]
        for j in present:
            turn = quat.multiply(quat.conjugate(base_rotations[:, j]), out[:, j])
            a = rig.aligned[j]
            h, p, r = swing_angles(quat.multiply(quat.conjugate(a), quat.multiply(turn, a)))
            count = 1 if group.name == "eyes" else len(present)
            rows.append((group, count, j, turn, h, p, r))
    return rows


def base_pose(rt, name, frames):
    """(F, J, 4) local rotations under the gaze: the rest pose or the held first frame."""
    rig = rt.rig(name)
    _, _, held = reference_frame(rig.character)
    if held:
        clip = next(iter(rig.character.asset.motions.values()))
        return np.repeat(clip.local_rotations[:1], frames, axis=0)
    return np.repeat(rig.skeleton.rest_rotations[None], frames, axis=0)


@pytest.fixture(scope="module")
def sweeping_runs():
    """Every character sweeping from far left to far right and up and down, whole body, then back to rest."""
    rt = Runtime(fps=FPS)
    cases = []
    for key in KEYS:
        character = setup(rt, key, key)
        rt.activate(key, Gaze(tuple(target_at(character, 85.0, 25.0)), influence="WHOLE"), 0.0, 1.5)
        rt.activate(key, Gaze(tuple(target_at(character, -160.0, -60.0)), influence="WHOLE"), 1.5, 3.0)
        rt.activate(key, Gaze(tuple(target_at(character, 10.0, 50.0, 0.5))), 3.0, 4.5)
        cases.append(key)
    rt.run(6.0)
    return rt, cases


@pytest.mark.parametrize("key", KEYS)
def test_no_joint_exceeds_its_limit(sweeping_runs, key):
    rt, _ = sweeping_runs
    frames = rt.motion(key).num_frames
    checked = set()
    for group, count, j, turn, h, p, r in joint_offsets(rt, key, base_pose(rt, key, frames)):
        heading, up, down, roll = np.radians([group.heading_deg, group.up_deg, group.down_deg, group.roll_deg]) / count
        h, p = np.where(np.abs(h) < 1e-9, 0.0, h), np.where(np.abs(p) < 1e-9, 0.0, p)  # rounding on locked axes
        scale = ellipse_scale(h, p, heading, up, down)
        assert scale.max() <= 1.0 + 1e-6, f"{key}: {rt.rig(key).skeleton.names[j]} at {scale.max():.3f} of its limit"
        assert np.abs(r).max() <= roll + 1e-6
        if np.abs(h).max() > 0.5 * heading:
            checked.add(group.name)
    assert {"lumbar", "thoracic"} <= checked  # the sweep pushed the spine to its limits


@pytest.mark.parametrize("key", KEYS)
def test_no_angular_velocity_spike_above_the_configured_speed(sweeping_runs, key):
    rt, _ = sweeping_runs
    frames = rt.motion(key).num_frames
    fastest = {}
    for group, count, j, turn, h, p, r in joint_offsets(rt, key, base_pose(rt, key, frames)):
        speed = np.degrees(quat.angle_between(turn[:-1], turn[1:])) * FPS  # deg/s between frames
        limit = group.speed_deg_s / count
        assert speed.max() <= limit * 1.01 + 1e-6, f"{key}: {rt.rig(key).skeleton.names[j]} at {speed.max():.1f} deg/s"
        fastest[group.name] = max(fastest.get(group.name, 0.0), speed.max() / limit)
    assert max(fastest.values()) > 0.9  # some joint did move at its top speed
    # After the last gaze ends (4.5 s) everything settles back to the base pose.
    last = joint_offsets(rt, key, base_pose(rt, key, frames))
    assert all(np.degrees(quat.angle_between(turn[-1], quat.IDENTITY)) < 0.5 for *_, turn, h, p, r in last)


@pytest.mark.parametrize("key", ["utah", "xbot"])
def test_tracks_a_moving_target(key):
    rt = Runtime(fps=FPS)
    character = setup(rt, key, key)
    left, up, forward = body_axes(character)
    _, pos, _ = reference_frame(character)
    origin = pos[look_joints(character)].mean(axis=0)

    def target(t):  # 45 degrees either side, up and down, at 1.5 m; a turn every 4 s (about 70 deg/s)
        t = np.asarray(t, dtype=np.float64)[..., None]
        h, p = np.radians(45.0) * np.sin(2 * np.pi * t / 4.0), np.radians(15.0) * np.sin(4 * np.pi * t / 4.0)
        return origin + 1.5 * (np.cos(p) * (np.sin(h) * left + np.cos(h) * forward) + np.sin(p) * up)

    rt.activate(key, Gaze(target), 0.0)
    rt.run(6.0)
    times = np.arange(180) / FPS
    errors = gaze_errors(character, rt.motion(key), target(times))
    assert errors[30:].max() <= 2.0


def test_influence_selects_the_joints_that_move():
    rt = Runtime(fps=FPS)
    character = setup(rt, "utah", "eyes")
    setup(rt, "utah", "whole")
    goal = tuple(target_at(character, 30.0, 10.0))
    rt.activate("eyes", Gaze(goal, influence="EYES"), 0.0)
    rt.activate("whole", Gaze(goal, influence="WHOLE"), 0.0)
    rt.run(2.0)
    rest = rt.rig("eyes").skeleton.rest_rotations
    for name, moving in (("eyes", {"eyes"}), ("whole", set(GROUP_NAMES))):
        out = rt.motion(name).local_rotations[-1]
        for group in GROUPS:
            angles = [np.degrees(quat.angle_between(out[rt.rig(name).joint(j)], rest[rt.rig(name).joint(j)]))
                      for j in group.joints if rt.rig(name).joint(j) is not None]
            assert (max(angles) > 0.5) == (group.name in moving), (name, group.name, angles)
        assert gaze_errors(character, rt.motion(name), goal)[-1] <= 2.0


def test_offset_angle_and_direction():
    rt = Runtime(fps=FPS)
    character = setup(rt, "rpm", "rpm")
    goal = tuple(target_at(character, 10.0, 0.0))
    rt.activate("rpm", Gaze(goal, offset_angle_deg=15.0, offset_direction="RIGHT"), 0.0)
    rt.run(2.0)
    errors = gaze_errors(character, rt.motion("rpm"), goal)
    assert abs(errors[-1] - 15.0) < 1.0
    aside = gaze_errors(character, rt.motion("rpm"), target_at(character, -5.0, 0.0))
    assert aside[-1] < 1.0  # 15 degrees to the right of 10 degrees left


def test_two_characters_look_each_other_in_the_face():
    rt = Runtime(fps=FPS)
    utah = setup(rt, "utah", "utah")
    rpm = setup(rt, "rpm", "rpm", position=(0.6, 0.0, 2.0), heading_deg=180.0)
    rt.activate("utah", Gaze("rpm"), 0.0)
    rt.activate("rpm", Gaze("utah:face"), 0.0)
    rt.run(2.5)
    g_rot_u, g_pos_u = infuse.motion_fk(rt.motion("utah"))
    g_rot_r, g_pos_r = infuse.motion_fk(rt.motion("rpm"))
    face_u = g_pos_u[:, look_joints(utah)].mean(axis=1)
    face_r = g_pos_r[:, look_joints(rpm)].mean(axis=1)
    assert gaze_errors(utah, rt.motion("utah"), face_r)[-15:].max() <= 2.0
    # rpm stands turned 180 degrees: its forward, read from its own rest pose, turns with it.
    motion = rt.motion("rpm")
    turned = gaze_errors(rpm, motion, face_u)
    assert turned[-15:].max() <= 2.0


def test_the_heuristic_mapper_agrees_with_the_labels_on_the_gaze_joints():
    chain = ("base", "spine1", "spine2", "spine3", "spine4", "spine5", "skullbase", "eyeball_left", "eyeball_right",
             "l_hip", "r_hip")
    by_file = {doc["file"]: doc for doc in labels()}
    for key, rel in CORPUS_CHARACTERS.items():
        mapping = corpus_character(key).mapping
        label = by_file[rel]["mapping"]
        assert {n: mapping[n] for n in chain} == {n: label.get(n) for n in chain}, key


def test_gaze_command_renders_and_saves(tmp_path):
    from infuse.cli import main

    from corpus_data import corpus_file

    out, saved = tmp_path / "gaze.png", tmp_path / "gaze.glb"
    path = "0.8,1.6,1.5; -0.8,1.8,1.5; 0,1.2,1.2"
    code = main(["gaze", str(corpus_file(CORPUS_CHARACTERS["rpm"])), "-o", str(out), "--strip", "3", "--duration", "2",
                 "--target-path", path, "--blink", "--saccades", "talk", "--save", str(saved)])
    assert code == 0 and out.stat().st_size > 10_000
    back = infuse.load(saved)
    weights = dict(zip(back.motions["gaze"].morph_names, back.motions["gaze"].morph_weights.T))
    assert back.motions["gaze"].num_frames == 60
    assert {n for n, w in weights.items() if np.any(w > 0)} <= {"eyeBlinkLeft", "eyeBlinkRight"}
    assert main(["gaze", str(corpus_file(CORPUS_CHARACTERS["rpm"])), "-o", str(out), "--target-path", "1,2"]) == 2


def test_a_character_binds_each_kind_of_gaze_once():
    """Gazes bind to their character once per groups moved and group pointing (read-only, shared by its
    gazes) and report what the character lacks every time; other groups, or the same character in another
    runtime, are bound anew, and every binding is the one worked out alone."""
    from dataclasses import fields

    from infuse_gaze.binding import bind_chain
    from infuse_gaze.model import INFLUENCES

    from runtime_characters import synthetic_character

    eyeless = synthetic_character("eyeless", drop=("eyeball_left", "eyeball_right"))
    runtimes = [Runtime(fps=30), Runtime(fps=30)]
    for rt in runtimes:
        rt.add_character(eyeless)
    rig, other = (rt.rig("eyeless") for rt in runtimes)
    notes: list[str] = []
    eyes = Gaze("a", influence="EYES").bind(rig, notes.append)
    assert Gaze("b", influence="EYES").bind(rig, notes.append) is eyes and not eyes.present.flags.writeable
    assert len(notes) == 2 and notes[0] == notes[1] and "has no eyes" in notes[0]
    head = Gaze("a", influence="HEAD").bind(rig, notes.append)
    assert head is not eyes and Gaze("a", influence="EYES").bind(other, notes.append) is not eyes
    for influence, binding in (("EYES", eyes), ("HEAD", head)):
        alone = bind_chain(rig, INFLUENCES[influence], "eyes", lambda note: None)
        for field in fields(alone):
            assert np.array_equal(getattr(binding, field.name), getattr(alone, field.name)), (influence, field.name)
