"""Controllers that evaluate every character at once give the frames they give one character at a time.

Clips, breathing, blinks and saccades evaluate all their jobs of a block together, through the block's
PoseTable, and keep state from block to block (the saccade in progress, when the eyelids stay open).
Here they run side by side with the same controllers forced to play one job at a time
(``Controller.evaluate``, job by job through ``evaluate_one``), on a cast that takes every path: copies
of one clip with the same content, clips held on their frames and interpolated in one block, a clip
holding its root, a crossfade, a character with two breathing activities, eyelids as morph targets and
as joints, a character without eyes, speech told while running, characters looking at each other, a
character added while running, and blocks of 1 and of 7 frames.
"""
from __future__ import annotations

import numpy as np
import pytest

from infuse import Motion
from infuse import quaternions as quat
from infuse.runtime import Clip, Controller, Runtime, blend_weights
from infuse.runtime.layers import blend_weights_of
from infuse.runtime.pose import PoseBlock, PoseTable, TableLayout

from runtime_characters import synthetic_character

rng = np.random.default_rng(7)


def swaying(skeleton, frames: int = 40, fps: float = 24.0) -> Motion:
    """A looping clip: every joint sways about its own axis, the root moves forward."""
    phase = 2.0 * np.pi * np.arange(frames)[:, None] / (frames - 1) + np.arange(skeleton.num_joints)[None]
    axes = np.random.default_rng(3).normal(size=(skeleton.num_joints, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    rotations = quat.from_axis_angle(np.broadcast_to(axes, (frames,) + axes.shape), 0.1 * np.sin(phase))
    root = skeleton.rest_translations[0] + np.linspace(0.0, 1.0, frames)[:, None] * np.array([0.0, 0.0, 1.0])
    return Motion(skeleton, fps, rotations, root, name="sway")


def cast_runtime(block_frames: int) -> tuple[Runtime, list[str]]:
    from infuse_blink.controller import Blink
    from infuse_breathing.controller import Breathing
    from infuse_gaze import Gaze
    from infuse_saccade.controller import Saccades

    blinking = synthetic_character("blinking", morphs=("eyeBlinkLeft", "eyeBlinkRight", "jawOpen"))
    lidded = synthetic_character("lidded")
    eyeless = synthetic_character("eyeless", drop=("eyeball_left", "eyeball_right"))
    clip = swaying(lidded.skeleton)
    copy = clip.replace(local_rotations=clip.local_rotations.copy(), name="sway copy")  # same content, another object
    rt = Runtime(fps=30, block_frames=block_frames, report=lambda *_: None)
    names = [rt.add_character(blinking, "a"), rt.add_character(lidded, "b", position=(0.0, 0.0, 2.0), heading_deg=180.0),
             rt.add_character(eyeless, "c", position=(2.0, 0.0, 1.0), heading_deg=-90.0),
             rt.add_character(lidded, "d", position=(-2.0, 0.0, 1.0), heading_deg=90.0)]
    rt.activate("a", Clip(clip), 0.0)
    rt.activate("b", Clip(copy, offset_s=0.3), 0.0)
    rt.activate("c", Clip(clip, speed=0.55), 0.0)  # between the clip's frames while the others are on them
    rt.activate("d", Clip(copy, root_motion=False, loop=False), 0.0)
    rt.activate("c", Clip(copy, offset_s=0.5), 1.0, blend_in_s=0.5)  # a crossfade: c's clips one after the other
    for k, name in enumerate(names):
        rt.activate(name, Breathing(rate_bpm=12.0 + 5 * k, phase=0.2 * k, depth=0.8), 0.1 * k, blend_in_s=0.4)
        rt.activate(name, Blink(rate_per_min=90.0, seed=k), 0.0)
        rt.activate(name, Saccades("talk" if k % 2 else "think", seed=k), 0.05 * k, blend_in_s=0.3)
    rt.activate("a", Breathing(rate_bpm=30.0, depth=0.5), 0.5)  # a second breath on one character: one after the other
    rt.activate("a", Gaze("b"), 0.0)  # faces: each looks at the other's eyes
    rt.activate("b", Gaze("a"), 0.0)
    rt.activate("c", Gaze((0.0, 1.6, 0.0)), 0.2)
    rt.activate("d", Gaze(lambda t: np.stack((np.sin(t), 1.5 + 0 * t, np.cos(t)), axis=-1), influence="HEAD"), 0.0)
    return rt, names


def play(block_frames: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    from infuse_blink.controller import Blink
    from infuse_breathing.controller import Breathing
    from infuse_gaze import Gaze
    from infuse_saccade.controller import Saccades

    rt, names = cast_runtime(block_frames)
    rt.run(1.2)
    rt.add_speech("b", 1.5, 2.1)  # told while running: saccades pause and come back
    rt.add_speech("d", 0.8, 1.4)  # told late, partly in the past
    late = synthetic_character("late", morphs=("blink",))
    names.append(rt.add_character(late, "e", position=(0.0, 0.0, -2.0)))  # joins the table while it runs
    rt.activate("e", Clip(swaying(late.skeleton), speed=1.3), rt.time)
    rt.activate("e", Breathing(), rt.time)
    rt.activate("e", Blink(rate_per_min=100.0, seed=9), rt.time)
    rt.activate("e", Saccades("listen", seed=9), rt.time)
    rt.activate("e", Gaze("a"), rt.time)
    rt.run(2.4)
    return [(rt.motion(n).local_rotations, rt.motion(n).root_translations, rt.morph_weights(n)) for n in names]


@pytest.mark.parametrize("block_frames", [1, 7])
def test_batched_controllers_give_the_frames_of_one_job_at_a_time(block_frames, monkeypatch):
    from infuse_blink.controller import Blink
    from infuse_breathing.controller import Breathing
    from infuse_saccade.controller import Saccades

    batched = play(block_frames)
    one_at_a_time = classmethod(Controller.evaluate.__func__)
    for cls in (Clip, Breathing, Blink, Saccades):
        monkeypatch.setattr(cls, "evaluate", one_at_a_time)
    alone = play(block_frames)
    for (rot, root, morph), (rot1, root1, morph1) in zip(batched, alone):
        assert np.abs(rot - rot1).max() < 1e-12
        assert np.abs(root - root1).max() < 1e-12
        assert morph.shape == morph1.shape and np.abs(morph - morph1).max(initial=0.0) < 1e-12
    # The cast does move: blinks closed the eyelids (morphs and joints), the eyes made saccades.
    rot_a, _, morph_a = batched[0]
    assert morph_a.max() > 0.9
    rest = synthetic_character("lidded").skeleton.rest_rotations
    assert np.abs(batched[1][0][:, 9] - rest[9]).max() > 0.1  # b's upper eyelid joint
    eyes = np.abs(np.diff(rot_a[:, 7], axis=0)).max()
    assert eyes > 0.01


def test_blend_weights_of_many_activities_are_each_ones_to_the_bit():
    times = np.arange(40) / 30.0 + 0.25
    cases = [(0.3, None, 0.3, 0.3), (0.0, None, 0.0, 0.0), (0.5, 1.0, 0.0, 0.0), (0.2, 0.9, 0.4, 0.25),
             (1.2, None, 0.5, 0.5), (-1.0, 0.4, 0.1, 0.0), (0.25, 0.25, 0.0, 0.2), (0.0, 5.0, 0.3, 1.0)]
    arrays = np.array([(s, np.inf if e is None else e, i, o) for s, e, i, o in cases]).T
    many = blend_weights_of(times, *arrays)
    for row, (s, e, i, o) in zip(many, cases):
        for block in (times, times[:1], times[7:19]):
            lo = int(np.searchsorted(times, block[0]))
            one = blend_weights(block, s, e, i, o)
            assert np.array_equal(blend_weights_of(block, *arrays)[cases.index((s, e, i, o))], one)
            assert np.array_equal(row[lo:lo + len(block)], one)


@pytest.mark.parametrize("mode", ["override", "additive"])
def test_table_writes_match_each_characters_pose_block(mode):
    from infuse.runtime import Mode

    characters = [synthetic_character("p"), synthetic_character("q", drop=("spine5",))]
    rt = Runtime(fps=30, report=lambda *_: None)
    rigs = [rt.rig(rt.add_character(c)) for c in characters]
    frames = 5
    table = PoseTable(TableLayout(rigs), frames)
    joints = [np.array([1, 4, 9]), np.array([2, 3])]
    rotations = [quat.normalize(rng.normal(size=(frames, len(j), 4))) for j in joints]
    weights = [np.array([0.0, 0.25, 1.0, 0.6, 1.0]), np.ones(frames)]  # partly on; fully on
    weights.append(np.zeros(frames))  # a third write, all off: left as it is
    joints.append(np.array([5]))
    rotations.append(quat.normalize(rng.normal(size=(frames, 1, 4))))
    owners = [0, 1, 0]
    poses = [PoseBlock(rig, frames) for rig in rigs]
    for pose, first in zip(poses, (0, rigs[0].skeleton.num_joints)):  # start both from a pose that is not rest
        start = quat.normalize(rng.normal(size=(frames, pose.rig.skeleton.num_joints, 4)))
        pose.local_rotations[:] = start
        table.local_rotations[:, first:first + start.shape[1]] = start
    for j, r, w, c in zip(joints, rotations, weights, owners):
        poses[c].set_rotations(j, r, w, Mode(mode))
    columns = np.concatenate([j + table.first_joint[rigs[c].name] for j, c in zip(joints, owners)])
    weight = np.concatenate([np.repeat(w[:, None], len(j), axis=1) for j, w in zip(joints, weights)], axis=1)
    table.set_rotations(columns, np.concatenate(rotations, axis=1), weight, Mode(mode), list(table.poses.values()))
    for pose, rig in zip(poses, rigs):
        assert np.abs(table.poses[rig.name].local_rotations - pose.local_rotations).max() < 1e-15
