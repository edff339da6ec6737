"""One clip model: a Motion carries joint tracks, morph weights and the mask of the joints it animates,
from the readers through the runtime to the writers."""
from __future__ import annotations

import json

import numpy as np
import pytest

import infuse
from corpus_data import corpus_file, require_corpus
from infuse import quaternions as quat
from infuse.errors import InputError
from infuse.mapping import animated_joint_names, map_skeleton
from infuse.runtime import Clip, Runtime
from infuse_gltf.container import parse_file

from runtime_characters import synthetic_character

ROBOT = "adibkn1-robot/RobotExpressive.glb"
REACH = "smartbody/behaviorsets/reaching/motions/ChrHarmony_Relax001_ArmReachClose_MiddleLow.skm"


def _chain() -> infuse.Skeleton:
    return infuse.Skeleton(["hips", "spine", "head"], [-1, 0, 1], np.array([[0, 1, 0], [0, 0.3, 0], [0, 0.3, 0.0]]),
                           np.tile(quat.IDENTITY, (3, 1)))


def _clip(frames: int = 5, **tracks) -> infuse.Motion:
    sk = _chain()
    return infuse.Motion(sk, 30.0, np.tile(quat.IDENTITY, (frames, 3, 1)), np.zeros((frames, 3)), name="clip", **tracks)


def test_morph_weights_are_frame_major_and_named():
    weights = np.linspace(0, 1, 10).reshape(5, 2)
    clip = _clip(morph_names=["smile", "blink"], morph_weights=weights)
    assert clip.morph_weights.shape == (5, 2) and not clip.morph_weights.flags.writeable
    assert np.array_equal(clip.morph_weight("blink"), weights[:, 1]) and clip.morph_weight("frown") is None
    assert np.allclose(clip.frame_times, np.arange(5) / 30.0)
    assert _clip().morph_weights.shape == (5, 0) and _clip().animated_mask.all()


@pytest.mark.parametrize("tracks, problem", [
    ({"morph_names": ["smile"], "morph_weights": np.zeros((4, 1))}, r"morph_weights has shape \(4, 1\), expected \(5, 1\)"),
    ({"morph_names": ["smile"]}, None),
    ({"morph_names": ["a", "a"], "morph_weights": np.zeros((5, 2))}, "morph target 'a' is named twice"),
    ({"morph_names": ["a"], "morph_weights": np.r_[0, 0, np.nan, 0, 0][:, None]}, "frame 2: morph weight is not finite"),
    ({"animated_joints": [True, False]}, r"animated_joints has shape \(2,\), expected \(3,\)"),
])
def test_tracks_that_do_not_fit_the_clip_are_input_errors(tracks, problem):
    if problem is None:  # names without weights: zero weights
        assert np.array_equal(_clip(**tracks).morph_weights, np.zeros((5, 1)))
        return
    with pytest.raises(InputError, match=problem):
        _clip(**tracks)


def test_replace_keeps_the_tracks_that_still_fit():
    clip = _clip(morph_names=["smile"], morph_weights=np.ones((5, 1)), animated_joints=[False, False, True])
    moved = clip.replace(root_translations=np.ones((5, 3)))
    assert moved.morph_names == ("smile",) and np.array_equal(moved.animated_joints, [False, False, True])
    first = clip.replace(local_rotations=clip.local_rotations[:1], root_translations=clip.root_translations[:1])
    assert first.num_frames == 1 and first.morph_names == () and first.morph_weights.shape == (1, 0)


def test_mapping_names_only_the_joints_a_motion_file_animates():
    require_corpus()
    asset = infuse.load(corpus_file(REACH))
    motion = next(iter(asset.motions.values()))
    animated = animated_joint_names(asset)
    assert animated is not None and 0 < len(animated) < asset.skeleton.num_joints
    assert animated == [n for n, a in zip(asset.skeleton.names, motion.animated_mask) if a]
    restricted, whole = map_skeleton(asset), map_skeleton(asset.skeleton, pose=motion)
    assert {j for j in restricted.joints.values() if j is not None} <= set(animated)
    dropped = [k for k, j in whole.joints.items() if j is not None and j not in animated]
    assert dropped and all(restricted.joints[k] is None for k in dropped)
    # A clip of morph weights alone says nothing about the skeleton: no restriction.
    sk = asset.skeleton
    face = infuse.Motion.rest_pose(sk, 3).replace(animated_joints=np.zeros(sk.num_joints, bool))
    assert animated_joint_names(infuse.Asset(None, "test", sk, {"face": face})) is None


def test_a_character_clip_plays_its_morph_weights_in_the_runtime(tmp_path):
    """The robot's Dance clip animates three morph targets (held at 0 in the file: given curves here):
    the runtime plays them with the joints, exports them on the clip, and the glTF writer writes them
    back as weights channels."""
    require_corpus()
    robot = infuse.load(corpus_file(ROBOT))
    dance = robot.motions["Dance"]
    assert set(dance.morph_names) == {"Angry", "Surprised", "Sad"} and dance.morph_weights.shape == (dance.num_frames, 3)
    phase = np.linspace(0.0, 2 * np.pi, dance.num_frames)[:, None] + np.array([0.0, 2.0, 4.0])
    dance = dance.replace(morph_weights=0.5 + 0.5 * np.sin(phase))
    runtime = Runtime(fps=dance.fps)
    name = runtime.add_character(infuse.Character("robot", robot, mapping=map_skeleton(robot)))
    runtime.activate(name, Clip(dance, loop=False), 0.0)
    runtime.run(dance.duration)  # the clip's frames but its last, where the activity ends
    played = runtime.motion(name)
    frames = dance.num_frames - 1
    assert played.num_frames == frames and set(played.morph_names) == set(dance.morph_names)
    for target in dance.morph_names:
        np.testing.assert_allclose(played.morph_weight(target), dance.morph_weight(target)[:frames], atol=1e-9)
    out = infuse.save(runtime.export(name, "danced", ground=False), tmp_path / "danced.glb")
    doc = parse_file(out).json
    animation = next(a for a in doc["animations"] if a["name"] == "danced")
    assert sum(c["target"]["path"] == "weights" for c in animation["channels"]) >= 1
    back = infuse.load(out).motions["danced"]
    for target in dance.morph_names:
        np.testing.assert_allclose(back.morph_weight(target), played.morph_weight(target), atol=1e-6)


def test_weights_a_character_lacks_are_reported_and_skipped():
    runtime = Runtime(fps=30)
    name = runtime.add_character(synthetic_character("face", morphs=("smile",)))
    sk = runtime.rig(name).skeleton
    clip = infuse.Motion.rest_pose(sk, 10).replace(morph_names=["smile", "frown"], morph_weights=np.full((10, 2), 0.4))
    runtime.activate(name, Clip(clip, loop=False), 0.0)
    runtime.run(0.3)
    assert np.allclose(runtime.motion(name).morph_weight("smile"), 0.4)
    assert any("no morph target 'frown'" in note for _, note in runtime.notes)


def test_a_clip_writes_channels_only_on_the_joints_it_animates(tmp_path):
    sk = _chain()
    frames = 6
    rotations = np.tile(quat.IDENTITY, (frames, 3, 1))
    rotations[:, 2] = quat.from_axis_angle(np.array([1.0, 0, 0]), np.linspace(0, 0.5, frames))
    nod = infuse.Motion(sk, 30.0, rotations, np.tile(sk.rest_translations[0], (frames, 1)), name="nod",
                        animated_joints=[False, False, True])
    out = infuse.save(infuse.Asset(None, "test", sk, {"nod": nod}), tmp_path / "nod.gltf")
    channels = json.loads(out.read_text())["animations"][0]["channels"]
    nodes = json.loads(out.read_text())["nodes"]
    assert [(nodes[c["target"]["node"]]["name"], c["target"]["path"]) for c in channels] == [("head", "rotation")]
    back = infuse.load(out).motions["nod"]
    np.testing.assert_allclose(infuse.motion_fk(back)[1], infuse.motion_fk(nod)[1], atol=1e-6)


def test_joints_a_clip_does_not_animate_keep_the_pose_below():
    """A clip on a higher layer that animates the head only (a SmartBody motion naming few joints, a
    face clip) leaves the rest of the body to the clip below; a clip of morph weights alone moves no joint."""
    from infuse.runtime import Layer

    runtime = Runtime(fps=30)
    name = runtime.add_character(synthetic_character("body", morphs=("smile",)))
    sk = runtime.rig(name).skeleton
    frames = 10
    lean = quat.from_axis_angle(np.array([1.0, 0, 0]), 0.4)
    body = infuse.Motion.rest_pose(sk, frames, name="lean")
    rotations = np.array(body.local_rotations)
    rotations[:, sk.index["spine1"]] = lean
    body = body.replace(local_rotations=rotations)
    turn = quat.from_axis_angle(np.array([0, 1.0, 0]), 0.6)
    head_rotations = np.array(body.local_rotations)
    head_rotations[:, :] = quat.IDENTITY
    head_rotations[:, sk.index["skullbase"]] = turn
    head = body.replace(local_rotations=head_rotations, name="look",
                        animated_joints=np.isin(sk.names, ["skullbase"]))
    smile = infuse.Motion.rest_pose(sk, frames, name="smile").replace(
        morph_names=["smile"], morph_weights=np.full((frames, 1), 0.7), animated_joints=np.zeros(sk.num_joints, bool))
    runtime.activate(name, Clip(body), 0.0)
    runtime.activate(name, Clip(head), 0.0, priority=1)
    clip = Clip(smile)
    clip.layer = Layer.FACE
    runtime.activate(name, clip, 0.0)
    runtime.run(0.2)
    played = runtime.motion(name)
    assert quat.angle_between(played.local_rotations[:, sk.index["spine1"]], lean).max() < 1e-9
    assert quat.angle_between(played.local_rotations[:, sk.index["skullbase"]], turn).max() < 1e-9
    assert np.allclose(played.morph_weight("smile"), 0.7)


def test_a_retargeted_clip_keeps_the_morph_weights_the_character_has(tmp_path):
    """A speaking clip of one avatar retargeted onto another with the same morph target names keeps
    its face; names the other character lacks are left out."""
    from infuse.cli import main
    from infuse.motion import carry_morph_weights

    require_corpus()
    rpm = infuse.load(corpus_file("talkinghead/avatars/brunette-t.glb"))
    frames = 45
    talk = infuse.Motion.rest_pose(rpm.skeleton, frames, name="talk").replace(
        morph_names=["viseme_aa", "noSuchShape"], morph_weights=np.stack(
            [0.5 + 0.5 * np.sin(np.linspace(0, 6, frames)), np.ones(frames)], axis=1))
    carried = carry_morph_weights(talk.replace(morph_names=(), morph_weights=np.zeros((0, 0))), talk, rpm.morph_targets)
    assert carried.morph_names == ("viseme_aa",) and np.allclose(carried.morph_weights[:, 0], talk.morph_weights[:, 0])
    source = tmp_path / "talk.glb"
    infuse.save(infuse.Asset(None, "test", rpm.skeleton, {"talk": talk.replace(morph_names=["viseme_aa"],
                                                                               morph_weights=talk.morph_weights[:, :1])},
                             morph_targets=list(rpm.morph_targets), mesh_loader=lambda: rpm.meshes), source)
    out = tmp_path / "onto.glb"
    assert main(["retarget", str(source), "--to", str(corpus_file("talkinghead/avatars/brunette-t.glb")),
                 "-o", str(out)]) == 0
    clip = infuse.load(out).motions["talk"]
    np.testing.assert_allclose(clip.morph_weight("viseme_aa"), talk.morph_weights[:, 0], atol=1e-6)


def test_a_clip_bound_again_to_a_character_binds_as_before_and_reports_the_same():
    """A clip played again on a character (a walk settling onto the idle it started with) takes the binding
    worked out the first time: the same values, the same reports, and the character keeps no clip alive."""
    import gc
    import weakref
    from dataclasses import fields

    runtime = Runtime(fps=30)
    name = runtime.add_character(synthetic_character("face", morphs=("smile",)))
    rig = runtime.rig(name)
    clip = infuse.Motion.rest_pose(rig.skeleton, 10).replace(morph_names=["smile", "frown"], morph_weights=np.full((10, 2), 0.4))
    first_reports: list[str] = []
    again_reports: list[str] = []
    first = Clip(clip, loop=True).bind(rig, first_reports.append)
    again = Clip(clip, loop=False, placement=(quat.IDENTITY, np.zeros(3))).bind(rig, again_reports.append)
    assert first_reports == again_reports and any("no morph target 'frown'" in r for r in again_reports)
    assert again.motion is clip
    for f in fields(first):
        a, b = getattr(first, f.name), getattr(again, f.name)
        assert (np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b), f.name
    other = infuse.Motion.rest_pose(rig.skeleton, 4)
    assert Clip(other).bind(rig, lambda message: None).motion is other
    gone = weakref.ref(other)
    del other
    gc.collect()
    assert gone() is None
