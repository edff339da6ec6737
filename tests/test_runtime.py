"""The controller runtime on a synthetic character: layers, modes, priorities, blending, stepping, outputs."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Clip, Controller, Layer, Mode, Runtime, Tracks, blend_weights, controller_components
from infuse.runtime.swing import EllipseClamp, clamp_ellipse, ellipse_scale, local_offsets, swing, swing_angles

from runtime_characters import synthetic_character


class Turn(Controller):
    """Test controller: turns one canonical joint by a fixed heading (degrees) in its aligned frame."""

    kind = "turn"
    layer = Layer.POSTURE
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, joint: str, heading_deg: float, layer: Layer = Layer.POSTURE, mode: Mode = Mode.ADDITIVE):
        self.joint, self.heading = joint, np.radians(heading_deg)
        self.layer, self.mode = layer, mode

    def bind(self, rig, report):
        return rig.joint(self.joint), rig.aligned[rig.joint(self.joint)]

    def evaluate_one(self, job, block):
        joint, aligned = job.binding
        delta = local_offsets(aligned, swing(np.full((len(block), 1), self.heading), np.zeros((len(block), 1))))
        if job.mode is Mode.OVERRIDE:
            rest = job.rig.skeleton.rest_rotations[[joint]]
            delta = quat.multiply(rest, delta)
        job.pose.set_rotations([joint], delta, job.weight, job.mode)


def heading_deg(rt, name, joint, frames=slice(None)):
    rig = rt.rig(name)
    j = rig.joint(joint)
    local = rt.motion(name).local_rotations[frames, j]
    rest = rig.skeleton.rest_rotations[j]
    h, _, _ = swing_angles(quat.multiply(quat.conjugate(rig.aligned[j]), quat.multiply(quat.multiply(quat.conjugate(rest), local), rig.aligned[j])))
    return np.degrees(h)


def test_swing_round_trip_and_ellipse():
    rng = np.random.default_rng(1)
    h, p, r = rng.uniform(-1.2, 1.2, 50), rng.uniform(-1.2, 1.2, 50), rng.uniform(-1, 1, 50)
    q = swing(h, p, r)
    back = swing_angles(q)
    assert np.allclose(back, (h, p, r), atol=1e-9)
    forward = quat.rotate(q, np.array([0.0, 0.0, 1.0]))
    assert np.allclose(forward, np.stack((np.cos(p) * np.sin(h), np.sin(p), np.cos(p) * np.cos(h)), 1), atol=1e-12)
    ch, cp = clamp_ellipse(h, p, 0.5, 0.3, 0.2)
    assert np.all(ellipse_scale(ch, cp, 0.5, 0.3, 0.2) <= 1 + 1e-12)
    inside = ellipse_scale(h, p, 0.5, 0.3, 0.2) <= 1
    assert np.allclose(ch[inside], h[inside]) and np.allclose(cp[inside], p[inside])


def test_ellipse_clamp_with_fixed_limits_is_clamp_ellipse():
    """EllipseClamp gives clamp_ellipse's angles bit for bit, with every limit open (its short way) or some
    locked, on angles inside and outside the limits, zeros of either sign included."""
    rng = np.random.default_rng(4)
    heading, pitch = rng.uniform(-1.5, 1.5, (6, 20)), rng.uniform(-1.5, 1.5, (6, 20))
    heading[0, :3], pitch[1, :3] = (0.0, -0.0, 0.0), (-0.0, 0.0, -0.0)
    limits = rng.uniform(0.2, 0.9, (3, 20))
    locked = limits.copy()
    locked[0, ::4], locked[2, 1::5] = 0.0, 0.0
    for chosen in (limits, locked):
        clamp = EllipseClamp(*chosen)
        assert clamp.open == (chosen is limits)
        for got, want in zip(clamp(heading, pitch), clamp_ellipse(heading, pitch, *chosen)):
            assert np.array_equal(got, want)
    assert np.any(ellipse_scale(heading, pitch, *limits) > 1.0) and np.any(ellipse_scale(heading, pitch, *limits) < 1.0)


def test_blend_weights_ramps_and_steps():
    t = np.linspace(0, 4, 401)
    w = blend_weights(t, 1.0, 3.0, 0.5, 0.5)
    assert w[t < 1.0].max() == 0 and w[(t >= 1.5) & (t <= 2.5)].min() == 1 and w[t >= 3.0].max() == 0
    assert np.all(np.diff(w[(t >= 1) & (t <= 1.5)]) >= 0)
    assert blend_weights(np.array([0.99, 1.0]), 1.0, None, 0.0, 0.0).tolist() == [0.0, 1.0]


def test_layers_priorities_and_modes():
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"))
    rt.activate("a", Turn("spine3", 10.0), 0.0)                          # additive, posture layer
    rt.activate("a", Turn("spine3", 5.0), 0.0, priority=-1)             # additive, applied first
    rt.activate("a", Turn("spine4", 30.0, mode=Mode.OVERRIDE), 0.0)     # override, priority 0
    rt.activate("a", Turn("spine4", -20.0, mode=Mode.OVERRIDE), 0.0, priority=5)  # wins: applied last
    rt.activate("a", Turn("spine4", 7.0, layer=Layer.HEAD), 0.0)        # a later layer adds on top
    rt.run(0.5)
    assert np.allclose(heading_deg(rt, "a", "spine3"), 15.0)
    assert np.allclose(heading_deg(rt, "a", "spine4"), -13.0)


def test_override_weight_blends_with_the_pose_below():
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"))
    rt.activate("a", Turn("spine3", 40.0, mode=Mode.OVERRIDE), 1.0, 2.0, blend_in_s=0.5, blend_out_s=0.5)
    rt.run(2.5)
    h = heading_deg(rt, "a", "spine3")
    t = np.arange(len(h)) / 30
    w = blend_weights(t, 1.0, 2.0, 0.5, 0.5)
    assert np.allclose(h, 40.0 * w, atol=1e-6)  # slerp about one axis is linear in the angle


def test_blocks_see_activities_changed_by_assignment():
    """The runtime keeps its activities' schedule as arrays from block to block: an end, a blend, a start
    or a priority assigned straight to an activity (as a controller taking over from another does), an
    activity added or the activities forgotten, all show from the next block on, as when given at the start."""
    def build(moved: bool):
        rt = Runtime(fps=30, block_frames=1)
        rt.add_character(synthetic_character("a"))
        ending = rt.activate("a", Turn("spine3", 30.0, mode=Mode.OVERRIDE), 0.0, None if moved else 1.0,
                             blend_out_s=0.0 if moved else 0.4)
        later = rt.activate("a", Turn("spine4", 20.0), 5.0 if moved else 0.5, blend_in_s=0.3)
        first = rt.activate("a", Turn("spine4", -50.0, mode=Mode.OVERRIDE), 0.0, priority=-5 if moved else 5)
        return rt, ending, later, first

    told, _, _, _ = build(False)
    told.run(2.0)
    changed, ending, later, first = build(True)
    changed.run(0.3)  # ten blocks of one frame with the first schedule
    ending.end_s, ending.blend_out_s = 1.0, 0.4
    later.start_s = 0.5
    first.priority = 5
    changed.run(1.7)
    for joint in ("spine3", "spine4"):
        assert np.allclose(heading_deg(changed, "a", joint)[9:], heading_deg(told, "a", joint)[9:], atol=1e-9), joint
    assert np.allclose(heading_deg(changed, "a", "spine3")[40:], 0.0, atol=1e-9)  # ended, blended out
    assert np.allclose(heading_deg(changed, "a", "spine4")[15:], -50.0, atol=1e-9)  # the override now after the turn
    changed.activate("a", Turn("spine2", 12.0), changed.time)
    changed.step()
    assert np.isclose(heading_deg(changed, "a", "spine2")[-1], 12.0)
    changed.forget(0.1)
    changed.run(0.5)
    assert np.allclose(heading_deg(changed, "a", "spine2")[-5:], 12.0)
    assert np.allclose(heading_deg(changed, "a", "spine3")[-5:], 0.0, atol=1e-9)


def test_step_by_step_equals_one_run_and_blocks():
    from infuse_gaze import Gaze

    def build(block_frames):
        rt = Runtime(fps=30, block_frames=block_frames)
        rt.add_character(synthetic_character("a"))
        rt.activate("a", Gaze(lambda t: np.stack((np.sin(t), 1.6 + 0 * t, 2.0 + 0 * t), -1)), 0.2)
        rt.activate("a", Turn("spine1", 5.0), 0.5, 1.5, blend_in_s=0.3)
        return rt

    whole = build(1000)
    whole.run(2.0)
    stepped = build(7)
    for _ in range(60):
        stepped.step()
    chunked = build(7)
    chunked.run(2.0)
    a = whole.motion("a").local_rotations
    assert a.shape[0] == 60
    assert np.allclose(a, stepped.motion("a").local_rotations, atol=1e-12)
    assert np.allclose(a, chunked.motion("a").local_rotations, atol=1e-12)


def test_clip_loops_and_carries_the_root_forward():
    ch = synthetic_character("walker")
    sk = ch.skeleton
    frames = 31
    rot = np.repeat(sk.rest_rotations[None], frames, axis=0)
    rot[:, sk.index["l_knee"]] = quat.from_axis_angle(np.array([1.0, 0, 0]), np.linspace(0, 1, frames) * np.sin(np.linspace(0, np.pi, frames)))
    root = np.stack((np.zeros(frames), np.full(frames, 1.0), np.linspace(0, 1.0, frames)), 1)  # 1 m per cycle
    walk = infuse.Motion(sk, 30.0, rot, root, name="walk")
    rt = Runtime(fps=30)
    rt.add_character(ch)
    rt.activate("walker", Clip(walk), 0.0)
    rt.run(3.0)
    m = rt.motion("walker")
    assert np.allclose(m.root_translations[::30, 2], np.arange(len(m.root_translations[::30])))
    assert np.allclose(m.local_rotations[30], m.local_rotations[60])  # a cycle is 30 frames
    once = Runtime(fps=30)
    once.add_character(synthetic_character("walker"))
    activity = once.activate("walker", Clip(walk, loop=False), 0.5)
    assert activity.end_s == pytest.approx(1.5)


def test_tracks_write_morph_weights_and_export():
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("face", morphs=("smile", "jawOpen")))
    times = np.array([0.0, 0.5, 1.0])
    rt.activate("face", Tracks(times, morph_weights={"smile": [0.0, 1.0, 0.0], "frown": [1, 1, 1]}), 0.0,
                blend_in_s=0.0, blend_out_s=0.0)
    rt.run(1.0)
    assert rt.activities[0].end_s == 1.0
    played = rt.motion("face")
    assert played.morph_names == ("smile",) and played.morph_weights.shape == (30, 1)
    assert np.allclose(played.morph_weight("smile"), np.interp(np.arange(30) / 30, times, [0, 1, 0]))
    assert ("face", "tracks: no morph target 'frown'; its track is skipped") in rt.notes
    asset = rt.export("face", "talk")
    assert list(asset.motions) == ["talk"] and np.array_equal(asset.motions["talk"].morph_weights, played.morph_weights)


def test_reports_once_and_degrades_without_eyes(capsys):
    from infuse_gaze import Gaze

    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("noeyes", drop=("eyeball_left", "eyeball_right")))
    rt.activate("noeyes", Gaze((1.0, 1.7, 2.0)), 0.0)
    rt.activate("noeyes", Gaze((-1.0, 1.7, 2.0)), 2.0)
    rt.run(1.0)
    err = capsys.readouterr().err
    assert err.count("has no eyes: gaze turns the head and spine instead") == 1
    assert heading_deg(rt, "noeyes", "skullbase")[-1] > 5  # the head turned toward the target


def test_usage_errors():
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"))
    with pytest.raises(UsageError):
        rt.add_character(synthetic_character("a"))
    with pytest.raises(UsageError):
        rt.activate("nobody", Turn("spine1", 1), 0)
    with pytest.raises(UsageError):
        rt.activate("a", Turn("spine1", 1), 2.0, 1.0)
    with pytest.raises(UsageError):
        rt.target("nothing")


def test_controllers_are_plugins():
    kinds = set(controller_components())
    assert {"clip", "tracks", "gaze", "saccade", "head", "blink", "breathing"} <= kinds


def test_bml_activations_are_realized():
    from infuse.bml import Scheduler

    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("brad"))
    rt.add_character(synthetic_character("rachel"), position=(1.0, 0.0, 2.0), heading_deg=180.0)
    scheduler = Scheduler()
    blocks = scheduler.submit('<bml id="b1" characterId="brad" xmlns="http://www.bml-initiative.org/bml/bml-1.0">'
                              '<gaze id="g1" target="rachel" influence="HEAD" start="0" end="3"/>'
                              '<head id="h1" lexeme="NOD" start="1"/></bml>')
    assert not blocks[0].failed
    activities = [rt.realize(a) for a in scheduler.activations("brad")]
    assert [a.controller.kind for a in activities] == ["gaze", "head"]
    assert activities[1].end_s == pytest.approx(2.0)  # one repeat at 1 Hz
    rt.run(3.0)
    g_rot, g_pos = infuse.motion_fk(rt.motion("rachel"))
    assert np.allclose(g_pos[0, 0], (1.0, 1.0, 2.0))  # rachel's pelvis, where she was placed
    assert heading_deg(rt, "brad", "skullbase")[40] > 5.0  # brad's head turned left, toward her
    pitch = np.degrees(swing_angles(rt.motion("brad").local_rotations[:, rt.rig("brad").joint("spine4")])[1])
    assert np.ptp(pitch[30:60]) > 5.0  # and nodded while looking


def test_placed_characters_gaze_at_world_targets():
    from infuse_gaze import Gaze

    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"), position=(3.0, 0.0, -1.0), heading_deg=90.0)
    target = np.array([3.0 + 2.0, 1.7, -1.0 + 0.5])  # ahead of it (its front now faces +X), a little to its right
    rt.activate("a", Gaze(tuple(target)), 0.0)
    rt.run(1.5)
    g_rot, g_pos = infuse.motion_fk(rt.motion("a"))
    sk = rt.rig("a").skeleton
    for eye in ("eyeball_left", "eyeball_right"):
        j = sk.index[eye]
        forward = quat.rotate(g_rot[-1, j], np.array([0.0, 0.0, 1.0]))  # identity rest: the eye looks along +Z
        to_target = (target - g_pos[-1, j]) / np.linalg.norm(target - g_pos[-1, j])
        assert np.degrees(np.arccos(np.clip(forward @ to_target, -1, 1))) < 0.5


def test_clip_on_another_skeleton_is_retargeted_and_gazes_on_top():
    from infuse.mapping import map_skeleton
    from infuse_gaze import Gaze

    from corpus_data import corpus_file
    from runtime_characters import corpus_character

    bandai = infuse.load(corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"))
    walk = next(iter(bandai.motions.values()))
    rt = Runtime(fps=30)
    rt.add_character(corpus_character("xbot"), name="xbot")
    with pytest.raises(UsageError, match="retarget"):
        rt.activate("xbot", Clip(walk), 0.0)
    rt.activate("xbot", Clip(walk, source_mapping=map_skeleton(bandai)), 0.0)
    rt.activate("xbot", Gaze(lambda t: np.stack((np.sin(t), 1.5 + 0 * t, 2.0 + 1.2 * t), -1)), 0.0)
    rt.run(4.0)
    _, g_pos = infuse.motion_fk(rt.motion("xbot"))
    assert np.linalg.norm(g_pos[-1, 0, [0, 2]] - g_pos[0, 0, [0, 2]]) > 3.0  # it walked
    head = rt.rig("xbot").joint("skullbase")
    assert np.ptp(g_pos[:, head, 1]) < 0.2  # upright throughout


def test_evaluated_blocks_keep_their_arrays_not_their_pose_objects():
    """A runtime evaluating block after block (a live scene: blocks of one frame) keeps each block's arrays,
    not its per-character pose objects: what the garbage collector goes over grows by a few objects a block,
    not by one per character; the frames read back are the same."""
    import gc

    from infuse.runtime.pose import PoseBlock

    def alive() -> int:
        gc.collect()
        return sum(isinstance(o, PoseBlock) for o in gc.get_objects())

    rt = Runtime(fps=30)
    names = [rt.add_character(synthetic_character(f"c{k}"), position=(k, 0.0, 0.0)) for k in range(4)]
    for name in names:
        sk = rt.rig(name).skeleton
        turns = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.linspace(0.0, 1.0, 12))
        rotations = np.repeat(sk.rest_rotations[None], 12, axis=0)
        rotations[:, 0] = turns
        rt.activate(name, Clip(infuse.Motion(sk, 30.0, rotations, np.zeros((12, 3)), name="turn")), 0.0)
    before = alive()
    for _ in range(60):
        rt.step(1)
    assert alive() - before <= len(names)
    layout, rotations, roots, morphs = rt.cast_poses(60)
    assert rotations.shape[0] == 60
    for name in names:
        span = layout.joint_spans[layout.character_index[name]]
        assert np.array_equal(rotations[:, span[0]], rt.last_poses(name, 60)[0][:, 0])
