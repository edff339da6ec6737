"""The scene API on real characters: placement and facing, BML and the builder realized through the
runtime, feedback in order, gaze at the other character measured on the output with FK, speech audio
against the clip, expressions, interruptions, export and preview."""
from __future__ import annotations

import wave

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.bml.feedback import BlockProgress, SyncPointProgress
from infuse.errors import InputError, UsageError
from infuse.scene import Scene

from runtime_characters import body_axes, corpus_character

BML = 'xmlns="http://www.bml-initiative.org/bml/bml-1.0"'


def two_characters(**options) -> Scene:
    """Bob (the Xbot, no eyes or face) at the origin and Ann (the RPM avatar) 2.2 m in front of him, facing
    each other."""
    scene = Scene(fps=30, quiet=True, **options)
    scene.add_character(corpus_character("xbot"), "bob", position=(0.0, 0.0, 0.0), facing=(0.5, 0.0, 2.2))
    scene.add_character(corpus_character("rpm"), "ann", position=(0.5, 0.0, 2.2), facing="bob")
    return scene


@pytest.fixture(scope="module")
def conversation():
    """Both gaze at each other, Bob nods, Ann speaks with a mark, smiles and looks at a cup on the mark."""
    scene = two_characters()
    scene.add_object("cup", (0.2, 1.0, 1.6), size=0.08)
    events = []
    scene.on(None, events.append)
    ids = {"gaze_bob": scene.gaze("bob", "ann", at=0.0), "gaze_ann": scene.gaze("ann", "bob", at=0.0),
           "nod": scene.nod("bob", at=2.5, repeats=2)}
    ids["talk"] = scene.bml("ann", f'''<bml {BML} id="talk">
        <speech id="s1"><text>Hello Bob, would you hand me <sync id="m1"/>that cup, please?</text></speech>
        <faceLexeme id="f1" lexeme="smile" amount="0.8" start="s1:start" end="s1:end"/>
        <gaze id="g2" target="cup" influence="EYES" start="s1:m1" end="s1:m1+0.8"/>
    </bml>''', at=2.0)
    scene.run()
    return scene, events, ids


def test_characters_face_each_other():
    scene = two_characters()
    scene.step()
    for name, other in (("bob", "ann"), ("ann", "bob")):
        rig = scene.runtime.rig(name)
        character = corpus_character("xbot" if name == "bob" else "rpm")
        _, _, forward = body_axes(character)
        world_forward = quat.rotate(rig.rotation, forward) * np.array([1.0, 0.0, 1.0])  # on the ground
        to_other = (scene.runtime.rig(other).position - rig.position) * np.array([1.0, 0.0, 1.0])
        cosine = world_forward @ to_other / np.linalg.norm(to_other) / np.linalg.norm(world_forward)
        assert np.degrees(np.arccos(min(cosine, 1.0))) < 0.01


def test_builder_and_bml_return_block_ids(conversation):
    scene, _, ids = conversation
    assert ids["talk"] == "talk"
    assert ids["gaze_bob"] != ids["gaze_ann"] and ids["nod"].startswith("head")
    assert set(ids.values()) <= set(scene.scheduler.blocks)
    assert scene.bml("bob", '<act><bml id="x1"><head id="h" type="NOD"/></bml></act>') == "x1"
    many = scene.bml("bob", '<act><bml id="y1"><head id="h" type="NOD"/></bml><bml id="y2"><head id="h" type="SHAKE"/></bml></act>')
    assert many == ["y1", "y2"]  # a document of several blocks gives their ids
    assert all(scene.scheduler.blocks[b].character == "bob" for b in many)


def test_feedback_events_come_in_order(conversation):
    scene, events, _ = conversation
    progress = [e for e in events if isinstance(e, (BlockProgress, SyncPointProgress))]
    times = [e.global_time for e in progress]
    assert times == sorted(times) and len(progress) > 20
    for block in ("talk",):
        mine = [e for e in progress if e.block == block]
        assert isinstance(mine[0], BlockProgress) and mine[0].sync == "start"
        assert isinstance(mine[-1], BlockProgress) and mine[-1].sync == "end"
        speech = [e.sync for e in mine if isinstance(e, SyncPointProgress) and e.behaviour == "s1"]
        assert speech[0] == "start" and speech[-1] == "end" and "m1" in speech
    nod = [e.sync for e in progress if isinstance(e, SyncPointProgress) and e.block.startswith("head")]
    assert nod.index("start") < nod.index("stroke") < nod.index("stroke:2") < nod.index("end")
    # predictions and warnings come when blocks are submitted, before any progress
    first_progress = events.index(progress[0])
    assert all(e.kind in ("blockPrediction", "warningFeedback") for e in events[:first_progress])
    # Bob has no eyes: his gaze is reported as degraded, naming the behaviour
    assert any(e.kind == "warningFeedback" and e.id.endswith(":g1") and "no eyes" in e.description for e in events)


def test_speech_mark_is_a_sync_point(conversation):
    scene, _, _ = conversation
    record = scene.scheduler.blocks["talk"]
    speech, look = record.activation("s1"), record.activation("g2")
    assert 2.0 < speech.time("m1") < speech.end
    assert look.start == pytest.approx(speech.time("m1"))
    utterance = scene.speech.utterance(speech.parameters)
    assert speech.time("m1") - speech.start == pytest.approx(utterance.marks["m1"])
    assert speech.end - speech.start == pytest.approx(utterance.duration_s)


def _eye_error_deg(scene, name, other, frames):
    """Angle (F,) between the character's eye (else head) forward on the output and the direction to the
    other character's face, in degrees."""
    character = corpus_character("xbot" if name == "bob" else "rpm")
    sk, m = character.skeleton, character.mapping
    _, _, forward = body_axes(character)
    joints = [sk.index[m[j]] for j in ("eyeball_left", "eyeball_right")] if m["eyeball_left"] else [sk.index[m["skullbase"]]]
    forward_local = quat.rotate(quat.conjugate(sk.rest_global_rotations[joints]), forward)
    g_rot, g_pos = infuse.motion_fk(scene.motion(name))
    o_character = corpus_character("xbot" if other == "bob" else "rpm")
    osk, om = o_character.skeleton, o_character.mapping
    face = [osk.index[om[j]] for j in ("eyeball_left", "eyeball_right")] if om["eyeball_left"] else [osk.index[om["skullbase"]]]
    _, o_pos = infuse.motion_fk(scene.motion(other))
    target = o_pos[frames][:, face].mean(axis=1)
    errors = []
    for k, j in enumerate(joints):
        look = quat.rotate(g_rot[frames, j], np.broadcast_to(forward_local[k], (len(frames), 3)))
        to = target - g_pos[frames, j]
        cosine = np.einsum("fi,fi->f", look, to) / np.linalg.norm(to, axis=1)
        errors.append(np.degrees(np.arccos(np.clip(cosine, -1, 1))))
    return np.max(errors, axis=0)


def test_gaze_at_the_other_character_measured_on_output(conversation):
    scene, _, _ = conversation
    settled = np.arange(45, 60)  # after 1.5 s, before Bob's nod moves his head (his gaze rides on it)
    assert _eye_error_deg(scene, "ann", "bob", settled).max() < 2.0
    assert _eye_error_deg(scene, "bob", "ann", settled).max() < 2.0
    late = np.arange(scene.runtime.frame - 10, scene.runtime.frame)  # Ann back on Bob after the cup
    assert _eye_error_deg(scene, "ann", "bob", late).max() < 2.0


def test_speech_audio_matches_the_clip(conversation, tmp_path):
    scene, _, _ = conversation
    written = scene.export("ann", tmp_path / "ann.glb")
    assert [p.name for p in written] == ["ann.glb", "ann.wav"]
    with wave.open(str(tmp_path / "ann.wav")) as f:
        rate, n = f.getframerate(), f.getnframes()
        samples = np.frombuffer(f.readframes(n), dtype="<i2")
    frames = scene.runtime.frame
    assert abs(n / rate - frames / scene.fps) <= 1.0 / scene.fps
    speech = scene.scheduler.blocks["talk"].activation("s1")
    utterance = scene.speech.utterance(speech.parameters)
    first = int(round(speech.start * rate))
    assert not samples[:first].any()  # silence until she speaks
    assert np.array_equal(samples[first:first + len(utterance.samples)], utterance.samples)  # then her utterance
    assert not samples[first + len(utterance.samples):].any()
    back = infuse.load(tmp_path / "ann.glb")
    assert list(back.motions) == ["scene"] and back.motions["scene"].num_frames == frames
    tracks = dict(zip(back.motions["scene"].morph_names, back.motions["scene"].morph_weights.T))
    during = slice(int(speech.start * 30) + 3, int(speech.end * 30) - 3)
    visemes = np.stack([w for k, w in tracks.items() if k.startswith("viseme_") and k != "viseme_sil"])
    assert visemes[:, during].max() > 0.5 and visemes[:, :int(speech.start * 30)].max() < 1e-6
    smile = scene.scheduler.blocks["talk"].activation("f1")
    held = slice(int(np.ceil(smile.time("attackPeak") * 30)), int(smile.time("relax") * 30) + 1)
    assert np.allclose(tracks["mouthSmileLeft"][held], 0.8)  # the smile, held at its amount between peak and relax
    assert tracks["mouthSmileLeft"][: int(speech.start * 30)].max() < 1e-6
    assert back.skeleton.names == corpus_character("rpm").skeleton.names and back.morph_targets
    from infuse_gltf import validate as validator  # the file plays in three.js and Blender: valid glTF

    report = validator.validate(tmp_path / "ann.glb")
    assert report["issues"]["numErrors"] == 0, validator.errors(report)


def test_saccades_pause_while_speaking(conversation):
    scene, _, _ = conversation
    speech = scene.scheduler.blocks["talk"].activation("s1")
    spans = scene.runtime.speech_intervals("ann")
    assert any(abs(s - speech.start) < 1e-9 and abs(e - speech.end) < 0.05 for s, e in spans)


def test_export_bvh_and_render(conversation, tmp_path):
    scene, _, _ = conversation
    (bvh,) = scene.export("bob", tmp_path / "bob.bvh")
    back = infuse.load(bvh)
    motion = next(iter(back.motions.values()))
    assert motion.num_frames == scene.runtime.frame
    expected = infuse.motion_fk(scene.motion("bob"))[1]
    assert np.abs(infuse.motion_fk(motion)[1] - expected).max() < 1e-3
    png = scene.render(tmp_path / "strip.png", strip=3)
    from PIL import Image

    image = Image.open(png)
    assert image.size[0] > image.size[1] > 100


def test_step_gives_the_frames_run_gives():
    a, b = two_characters(seed=3), two_characters(seed=3)
    for scene in (a, b):
        scene.gaze("bob", "ann", at=0.1)
        scene.nod("ann", at=0.2)
    a.run(1.0)
    for _ in range(30):
        b.step()
    for name in ("ann", "bob"):  # the same frames, to rounding (blocks of other sizes sum in other orders)
        assert np.abs(a.motion(name).local_rotations - b.motion(name).local_rotations).max() < 1e-12
    assert a.feedback.log == b.feedback.log


def test_replace_interrupts_the_running_block():
    scene = two_characters()
    scene.bml("ann", f'<bml {BML} id="long"><gaze id="g" target="bob" start="0" end="8"/></bml>', at=0.0)
    gaze = scene.activities[("long", "g")]
    scene.run(1.0)
    scene.bml("ann", f'<bml {BML} id="now" composition="REPLACE"><head id="h" lexeme="SHAKE"/></bml>')
    assert gaze.end_s is not None and gaze.end_s < 2.0  # stopped at 1 s, blending out
    assert scene.scheduler.blocks["now"].start_s == pytest.approx(1.0)
    scene.run(2.0)
    ends = [e for e in scene.feedback.log if isinstance(e, BlockProgress) and e.block == "long" and e.sync == "end"]
    assert len(ends) == 1 and ends[0].global_time == pytest.approx(1.0, abs=1e-6)


def test_behaviours_without_their_controller_are_reported():
    scene = two_characters()
    scene.walk_to("bob", (0.0, 1.0))
    scene.bml("ann", f'<bml {BML} id="g"><gesture id="beat" lexeme="JUGGLE"/></bml>')  # no pack has it
    scene.gaze("ann", "nobody_here")
    warnings = {e.id: e for e in scene.feedback.log if e.kind == "warningFeedback"}
    walk = next(e for k, e in warnings.items() if k.startswith("walk"))
    assert walk.type == "CANNOT_CREATE_BEHAVIOR" and "no locomotion pack infused" in walk.description
    assert warnings["g:beat"].type == "CANNOT_CREATE_BEHAVIOR" and "JUGGLE" in warnings["g:beat"].description
    missing = next(e for k, e in warnings.items() if k.startswith("gaze"))
    assert missing.type == "NO_SUCH_TARGET" and "nobody_here" in missing.description
    scene.run(1.0)  # the rest plays


def test_expressions_on_the_face():
    scene = Scene(fps=30, quiet=True, idle=False)
    scene.add_character(corpus_character("rpm"), "ann")
    scene.expression("ann", "RAISE_LEFT_BROW", at=0.0, amount=1.0, duration=1.0)
    scene.bml("ann", f'<bml {BML} id="au"><faceFacs id="f" au="12" side="RIGHT" amount="0.5" start="1" end="2"/></bml>')
    scene.run(2.5)
    played = scene.runtime.motion("ann")
    tracks = dict(zip(played.morph_names, played.morph_weights.T))
    assert tracks["browOuterUpLeft"][15] == pytest.approx(1.0) and "browOuterUpRight" not in tracks
    assert tracks["browInnerUp"][15] == pytest.approx(1.0)  # inner brows are one shape on this avatar
    assert tracks["mouthSmileRight"][45] == pytest.approx(0.5) and "mouthSmileLeft" not in tracks
    assert tracks["browOuterUpLeft"][35] == 0.0 and tracks["mouthSmileRight"][70] == 0.0


def test_bad_calls_raise_clear_errors():
    scene = two_characters()
    with pytest.raises(UsageError, match="no character 'carl'"):
        scene.say("carl", "hi")
    with pytest.raises(InputError):
        scene.bml("ann", "<bml id='x'><head id='h'></bml>")
    with pytest.raises(UsageError, match="already has"):
        scene.add_object("ann", (0, 1, 0))
    with pytest.raises(UsageError, match="':'"):
        scene.add_object("a:b", (0, 1, 0))
    with pytest.raises(UsageError):
        scene.add_object("cup", (0, float("nan"), 0))
    with pytest.raises(UsageError, match="names no character"):
        scene.bml(None, f'<bml {BML} id="z"><head id="h" lexeme="NOD"/></bml>')
    scene.add_character(corpus_character("rpm"), "eve", facing="nowhere")  # "nowhere" may still be added
    with pytest.raises(UsageError, match="facing 'nowhere'"):
        scene.step()
