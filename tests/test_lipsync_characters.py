"""Lip sync on real characters: each drives its own face channels, and ``infuse speak`` end to end."""
from __future__ import annotations

import json
import wave

import numpy as np
import pytest

import infuse
from corpus_data import UNDER_CI, corpus_file
from espeak_support import require_espeak
from infuse import quaternions as quat
from infuse.cli import main
from infuse.errors import InputError, UnusableInputError
from infuse.speech import tts_engine
from infuse_lipsync.channels import detect_face
from infuse_lipsync.expressions import Expression, expression_targets
from infuse_lipsync.lipsync import LipSyncSettings, lipsync
from infuse_lipsync.tables import viseme_set

RPM = "talkinghead/avatars/brunette-t.glb"
VROID = "talkinghead/avatars/vroid.glb"
VRM1 = "vrm-specification/samples/VRMC_vrm_expressions_isBinary_Overrides/vrm/VRMC_vrm_expressions_isBinary_Overrides.vrm"
BRAD = "smartbody/ChrBrad/ChrBrad.sk"
TEXT = 'Bob met <sync id="pam"/>Pam at the map shop. Wow, five ships!'


@pytest.fixture(scope="module")
def utterance():
    require_espeak()
    return tts_engine("espeak").synthesize(TEXT)


@pytest.fixture(scope="module")
def rpm():
    return infuse.load(corpus_file(RPM))


@pytest.fixture(scope="module")
def brad():
    return infuse.load(corpus_file(BRAD))


def _closure_frames(utterance, times):
    """Frames at or within half a frame of each bilabial run."""
    frame = times[1] - times[0]
    return [(times >= s - frame / 2) & (times <= e + frame / 2) for s, e, p in utterance.phonemes if p in ("p", "b", "m")]


def test_rpm_avatar_drives_its_own_visemes(rpm, utterance):
    face = detect_face(rpm)
    assert face.viseme_sets()[:2] == ["oculus", "arkit"]
    assert face.vocabularies["oculus"]["ih"] == [("viseme_I", 1.0)]  # Ready Player Me's names
    result = lipsync(utterance, face, skeleton=rpm.skeleton)
    assert set(result.morph_weights) == {f"viseme_{v}" for v in
                                         ("sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa", "E", "I", "O", "U")}
    assert set(result.morph_weights) <= set(rpm.morph_targets)
    pp, sil = result.morph_weights["viseme_PP"], result.morph_weights["viseme_sil"]
    for near in _closure_frames(utterance, result.times):
        assert pp[near].max() == pytest.approx(1.0)
    others = np.array([w for name, w in result.morph_weights.items() if name != "viseme_sil"])
    assert sil[0] == sil[-1] == 1.0 and np.all(others[:, [0, -1]] == 0.0)
    arkit = lipsync(utterance, face, "arkit", skeleton=rpm.skeleton)
    assert arkit.morph_weights["jawOpen"].max() > 0.3 and set(arkit.morph_weights) <= set(rpm.morph_targets)


def test_rpm_expressions_on_arkit(rpm):
    face = detect_face(rpm)
    assert expression_targets("smile", face) == {"cheekSquintLeft": 0.5, "cheekSquintRight": 0.5,
                                                 "mouthSmileLeft": 1.0, "mouthSmileRight": 1.0}
    assert expression_targets("blink", face, 0.5) == {"eyeBlinkLeft": 0.5, "eyeBlinkRight": 0.5}
    assert set(expression_targets("raised_brows", face)) == {"browInnerUp", "browOuterUpLeft", "browOuterUpRight"}


def test_vroid_drives_its_vrm_mouth_shapes(utterance):
    asset = infuse.load(corpus_file(VROID))
    face = detect_face(asset)
    assert "vrm" in face.viseme_sets()
    assert {c: b[0][0] for c, b in face.vocabularies["vrm"].items()} == {
        "aa": "Fcl_MTH_A", "ih": "Fcl_MTH_I", "ou": "Fcl_MTH_U", "ee": "Fcl_MTH_E", "oh": "Fcl_MTH_O"}
    result = lipsync(utterance, face, "vrm", skeleton=asset.skeleton, expressions=[Expression("smile", 0.5)])
    assert {"Fcl_MTH_A", "Fcl_MTH_E", "Fcl_MTH_I", "Fcl_MTH_U"} <= {t for t, w in result.morph_weights.items() if w.max() > 0.3}
    assert result.morph_weights["Fcl_ALL_Joy"].max() == pytest.approx(0.5)  # the VRoid "happy" expression
    mouth = np.array([result.morph_weights[f"Fcl_MTH_{v}"] for v in "AIUEO"])
    for near in _closure_frames(utterance, result.times):  # closed lips: every mouth shape at 0
        assert np.any(np.all(mouth[:, near] == 0.0, axis=0))


def test_vrm_sample_without_morphs_is_a_clear_error(utterance, tmp_path, capsys):
    asset = infuse.load(corpus_file(VRM1))
    face = detect_face(asset)
    assert face.viseme_sets() == [] and "happy, blink" in face.notes[0]
    with pytest.raises(UnusableInputError, match="no mouth channels.*happy, blink"):
        lipsync(utterance, face, skeleton=asset.skeleton)
    assert main(["speak", str(corpus_file(VRM1)), "hello", "-o", str(tmp_path / "vrm.glb")]) == 3
    assert "no mouth channels" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_smartbody_face_poses_move_the_jaw_and_close_the_lips(brad, utterance):
    face = detect_face(brad)
    assert face.viseme_sets() == ["smartbody_diphone", "jaw"] and face.jaw == "JtJaw"
    assert face.kinds["smartbody_diphone"] == "pose" and "face_neutral" in face.poses
    result = lipsync(utterance, face, skeleton=brad.skeleton)
    motion = result.motion(brad.skeleton)
    jaw = brad.skeleton.index["JtJaw"]
    opening = np.degrees(quat.angle_between(motion.local_rotations[:, jaw], brad.skeleton.rest_rotations[jaw]))
    assert opening.max() > 5.0 and opening[0] < 0.5
    # at full closure the lip joints hold SmartBody's own PBM pose
    pbm = next(iter(infuse.load(face.poses["PBM"]).motions.values()))
    lips = [brad.skeleton.index[n] for n in ("JtLipUpperMid", "JtLipLowerMid", "JtLipCornerLf")]
    vs = viseme_set("smartbody_diphone")
    closed = np.all(np.abs(result.channel_weights - vs.closure) < 1e-9, axis=1)
    assert closed.any()
    k = int(np.flatnonzero(closed)[0])
    assert np.degrees(quat.angle_between(motion.local_rotations[k, lips], pbm.local_rotations[-1, lips])).max() < 0.01


def test_plain_jaw_opens_like_the_open_pose(brad, utterance):
    face = detect_face(brad)
    result = lipsync(utterance, face, "jaw", skeleton=brad.skeleton)
    motion = result.motion(brad.skeleton)
    jaw = brad.skeleton.index["JtJaw"]
    k = int(np.argmax(result.channel_weights[:, 0]))
    ours = quat.to_rotvec(quat.multiply(quat.conjugate(brad.skeleton.rest_rotations[jaw]), motion.local_rotations[k, jaw]))
    open_pose = next(iter(infuse.load(face.poses["open"]).motions.values()))
    theirs = quat.to_rotvec(quat.multiply(quat.conjugate(brad.skeleton.rest_rotations[jaw]), open_pose.local_rotations[-1, jaw]))
    cosine = np.dot(ours, theirs) / (np.linalg.norm(ours) * np.linalg.norm(theirs))
    assert cosine > 0.9  # the same direction as SmartBody's own "open" pose
    expected = LipSyncSettings().jaw_max_angle_deg * result.channel_weights[k, 0]
    assert np.degrees(np.linalg.norm(ours)) == pytest.approx(expected, rel=1e-6) and expected > 6.0


def test_map_file_declares_face_channels(rpm, utterance, tmp_path):
    doc = {"face": {"vocabularies": {"vrm": {"aa": "jawOpen", "ou": [["mouthPucker", 1.0], ["mouthFunnel", 0.5]],
                                             "ih": "mouthSmileLeft", "ee": "mouthStretchLeft", "oh": "mouthFunnel"}},
                    "viseme_set": "vrm"}}
    path = tmp_path / "brunette.map.json"
    path.write_text(json.dumps(doc))
    face = detect_face(rpm, path)
    assert face.viseme_sets()[0] == "vrm" and face.declared == ("vrm",)
    result = lipsync(utterance, face, skeleton=rpm.skeleton)
    assert result.viseme_set == "vrm" and result.morph_weights["jawOpen"].max() > 0.5
    bad = dict(doc, face={"vocabularies": {"vrm": {"aa": "NoSuchShape"}}})
    with pytest.raises(InputError, match="NoSuchShape"):
        detect_face(rpm, bad)
    with pytest.raises(InputError, match="not a vrm channel"):
        detect_face(rpm, {"face": {"vocabularies": {"vrm": {"zz": "jawOpen"}}}})


def _glb_animation_end(path) -> float:
    import struct
    data = path.read_bytes()
    doc = json.loads(data[20:20 + struct.unpack("<I", data[12:16])[0]])
    inputs = {s["input"] for a in doc["animations"] for s in a["samplers"]}
    return max(doc["accessors"][i]["max"][0] for i in inputs)


def test_speak_command_writes_animation_wav_and_timeline(tmp_path, utterance, capsys):
    out = tmp_path / "out.glb"
    assert main(["speak", str(corpus_file(RPM)), TEXT, "-o", str(out), "--expression", "smile:0.3"]) == 0
    wav, timeline = tmp_path / "out.wav", tmp_path / "out.timeline.json"
    assert out.is_file() and wav.is_file() and timeline.is_file()
    with wave.open(str(wav), "rb") as f:
        audio_s = f.getnframes() / f.getframerate()
    doc = json.loads(timeline.read_text())
    assert doc["viseme_set"] == "oculus" and doc["wav"] == "out.wav" and set(doc["marks"]) == {"pam"}
    assert doc["duration_s"] == pytest.approx(audio_s, abs=1e-4)
    end = _glb_animation_end(out)
    assert audio_s <= end + 1e-6 < audio_s + 1 / 30  # audio and animation agree within one frame
    reread = infuse.load(out)
    speech = reread.motions["speech"]
    assert speech.morph_weight("viseme_PP").max() == pytest.approx(1.0, abs=1e-6)
    assert speech.morph_weight("mouthSmileLeft").max() == pytest.approx(0.3, abs=1e-6)
    from infuse_gltf import validate as validator
    try:
        report = validator.validate(out)
    except infuse.MissingFeatureError as exc:
        if UNDER_CI:
            raise
        pytest.skip(str(exc))
    assert report["issues"]["numErrors"] == 0, validator.errors(report)


def test_speak_joint_face_clip(tmp_path, utterance, brad):
    out = tmp_path / "brad.glb"
    assert main(["speak", str(corpus_file(BRAD)), "Open wide, papa.", "-o", str(out), "--fps", "25"]) == 0
    clip = infuse.load(out).motions["speech"]
    jaw = clip.skeleton.index["JtJaw"]
    assert np.degrees(quat.angle_between(clip.local_rotations[:, jaw], clip.local_rotations[0, jaw])).max() > 5.0
    assert json.loads((tmp_path / "brad.timeline.json").read_text())["joints"]



def test_speak_face_only_joint_clip_animates_the_face_joints_alone(tmp_path, utterance, brad):
    """The speech clip's animated joints are the face joints: the glb has channels on those nodes only,
    and every other joint reads back at rest."""
    from infuse_gltf.container import parse_file

    out = tmp_path / "face.glb"
    assert main(["speak", str(corpus_file(BRAD)), "Open wide, papa.", "-o", str(out), "--face-only"]) == 0
    face_joints = set(json.loads((tmp_path / "face.timeline.json").read_text())["joints"])
    doc = parse_file(out).json
    moved = {doc["nodes"][c["target"]["node"]]["name"] for c in doc["animations"][0]["channels"]}
    assert face_joints and moved == face_joints
    clip = infuse.load(out).motions["speech"]
    others = [j for j, n in enumerate(clip.skeleton.names) if n not in face_joints]
    rest = clip.skeleton.rest_rotations[others]
    assert np.degrees(quat.angle_between(clip.local_rotations[:, others], rest)).max() < 1e-3

def test_speak_errors(tmp_path, utterance, capsys, monkeypatch):
    rpm_path = str(corpus_file(RPM))
    assert main(["speak", rpm_path, "", "-o", str(tmp_path / "a.glb")]) == 2
    assert "empty text" in capsys.readouterr().err
    assert main(["speak", rpm_path, "bad \ue000 char", "-o", str(tmp_path / "b.glb")]) == 2
    assert "U+E000" in capsys.readouterr().err
    assert main(["speak", rpm_path, "hello", "-o", str(tmp_path / "b.bvh")]) == 2
    assert "only glTF" in capsys.readouterr().err
    monkeypatch.setenv("INFUSE_ESPEAK_LIBRARY", str(tmp_path / "missing" / "libespeak-ng.so.1"))
    assert main(["speak", rpm_path, "hello", "-o", str(tmp_path / "c.glb")]) == 3
    assert "apt-get install espeak-ng libespeak-ng1" in capsys.readouterr().err
    assert not any(tmp_path.glob("*.glb")) and not any(tmp_path.glob("*.wav"))


def test_speak_with_a_recorded_voice(tmp_path, capsys):
    rate = 16000
    t = np.arange(rate) / rate
    with wave.open(str(tmp_path / "voice.wav"), "wb") as f:
        f.setnchannels(1)
        f.setsampwidth(2)
        f.setframerate(rate)
        f.writeframes((2000 * np.sin(2 * np.pi * 150 * t)).astype("<i2").tobytes())
    (tmp_path / "voice.tsv").write_text("0.2\t0.3\tM\n0.3\t0.5\tAA1\n0.5\t0.6\tP\n")
    out = tmp_path / "rec.glb"
    assert main(["speak", str(corpus_file(RPM)), "-o", str(out), "--tts", "file", "--audio", str(tmp_path / "voice.wav"),
                 "--timing", str(tmp_path / "voice.tsv")]) == 0
    doc = json.loads((tmp_path / "rec.timeline.json").read_text())
    assert [v["viseme"] for v in doc["visemes"]] == ["sil", "PP", "aa", "PP", "sil"]
    assert (tmp_path / "rec.wav").read_bytes() == (tmp_path / "voice.wav").read_bytes()


def test_lipsync_plays_in_the_controller_runtime(rpm, utterance):
    from infuse.runtime import Runtime

    result = lipsync(utterance, detect_face(rpm), skeleton=rpm.skeleton)
    runtime = Runtime(fps=30)
    name = runtime.add_character(rpm)
    runtime.activate(name, result.controller(), start_s=0.0)
    runtime.run(utterance.duration_s)
    played = runtime.motion(name)
    assert set(played.morph_names) == set(result.morph_weights)
    times = played.frame_times
    inside = (times > 0.15) & (times < utterance.duration_s - 0.15)  # past the blend in and out
    for target, weights in zip(played.morph_names, played.morph_weights.T):
        expected = np.interp(times[inside], result.times, result.morph_weights[target])
        np.testing.assert_allclose(weights[inside], expected, atol=1e-9)


def test_one_speech_on_two_characters_drives_each_own_face(rpm, utterance):
    """A speech controller bound to a character with visemes and to one without face channels: the first
    speaks with its own lip sync (whatever is bound after it), the second without moving, reported."""
    from infuse.runtime import Runtime
    from infuse_lipsync.controllers import Speech

    from runtime_characters import synthetic_character

    rt = Runtime(fps=30.0, report=lambda character, message: reports.append((character, message)))
    reports: list = []
    rt.add_character(rpm, "ann")
    rt.add_character(synthetic_character("mute"), "mute")  # no morph targets, no jaw
    speech = Speech(utterance)
    for name in ("ann", "mute"):
        rt.activate(name, speech, 0.0)
    rt.run(utterance.duration_s)
    ann, mute = rt.motion("ann"), rt.motion("mute")
    alone = lipsync(utterance, detect_face(rpm), skeleton=rpm.skeleton)
    frames = np.arange(ann.num_frames) / 30.0
    for name, weights in alone.morph_weights.items():
        assert np.allclose(ann.morph_weight(name), np.interp(frames, alone.times, weights), atol=1e-9), name
    assert mute.morph_weights.size == 0
    assert np.allclose(mute.local_rotations, mute.skeleton.rest_rotations)
    assert any(c == "mute" and "without moving its mouth" in m for c, m in reports)


def test_a_lip_sync_prepared_ahead_is_used_only_from_the_same_inputs(rpm, utterance, monkeypatch):
    """Speech.prepare works a character's lip sync out ahead (a live scene does, on the caller's thread).
    Binding the same utterance to the same character with the same settings takes it, once, and reports
    what binding reports (a character without a mouth); another viseme set, frame rate or utterance is
    worked out again. Every binding is that of a speech nothing prepared, to the bit."""
    from infuse.runtime import Runtime
    from infuse_lipsync import controllers
    from infuse_lipsync.controllers import Speech

    from runtime_characters import synthetic_character

    worked_out = []
    real = controllers.lipsync
    monkeypatch.setattr(controllers, "lipsync", lambda *args, **kwargs: worked_out.append(args[0]) or real(*args, **kwargs))
    rt = Runtime(fps=30.0)
    rt.add_character(rpm, "ann")
    rt.add_character(synthetic_character("mute"), "mute")  # no morph targets, no jaw
    later = tts_engine("espeak").synthesize("Five ships.")
    variants = {"same": Speech(utterance), "set": Speech(utterance, viseme_set="arkit"),
                "fps": Speech(utterance, fps=60.0), "utterance": Speech(later)}
    fresh = {}  # (character, variant) -> (binding, notes) of a speech nothing prepared
    for name, what in [("ann", what) for what in variants] + [("mute", "same")]:
        notes: list[str] = []
        fresh[name, what] = variants[what].bind(rt.rig(name), notes.append), notes
    assert any("without moving its mouth" in note for note in fresh["mute", "same"][1])

    def check(name, what, calls):
        notes: list[str] = []
        bound = variants[what].bind(rt.rig(name), notes.append)
        expected, expected_notes = fresh[name, what]
        for field in ("times", "joints", "rotations", "columns", "morphs"):
            assert np.array_equal(getattr(bound, field), getattr(expected, field)), (name, what, field)
        assert notes == expected_notes
        assert len(worked_out) == calls, (name, what)

    for name in ("ann", "mute"):
        worked_out.clear()
        Speech(utterance).prepare(rt.rig(name))
        assert len(worked_out) == 1
        check(name, "same", 1)  # taken from what was prepared
        check(name, "same", 2)  # taken once: worked out again
    for what in ("set", "fps", "utterance"):
        worked_out.clear()
        Speech(utterance).prepare(rt.rig("ann"))
        check("ann", what, 2)  # other inputs: worked out again
