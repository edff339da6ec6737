"""The nonverbal generator in a scene, measured on the output by FK: the Ready Player Me avatar explains
something to X Bot with espeak-ng speech; its generated gestures are on its arms at their words, its head
looks away from X Bot at the start and back at the end, and X Bot nods on the phrase ends."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.bml import Scheduler
from infuse.kinematics import forward_kinematics
from infuse.scene import Scene
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file

from corpus_data import REPO, require_corpus
from espeak_support import require_espeak
from runtime_characters import body_axes, corpus_character

FPS = 30.0
TEXT = ("Well, the thing about this old machine is that nobody really remembers how it was built. "
        "So we have to take it apart, piece by piece, and draw every part before we start.")
BML = ('<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:infuse="urn:infuse:bml" id="talk" '
       'infuse:nonverbal="true" infuse:seed="{seed}"><speech id="s1"><text>' + TEXT + '</text></speech></bml>')
LOOK = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="{id}"><gazeShift id="g" target="{target}" influence="HEAD"/></bml>'


def seed_with_aversion_and_look_back() -> int:
    """The first seed whose draws give this utterance both a gaze aversion and a look back (scheduling only)."""
    for seed in range(100):
        scheduler = Scheduler(names=lambda: {"ann": "character", "bob": "character"})
        elements = {a.element for a in scheduler.submit(BML.format(seed=seed).replace('id="talk"', 'id="talk" characterId="ann"'))[0].activations}
        if {"gaze", "gazeShift"} <= elements:
            return seed
    raise AssertionError("no seed draws both")


@pytest.fixture(scope="module")
def conversation(tmp_path_factory):
    require_espeak()
    scene = Scene(fps=FPS, quiet=True, idle=False, pack_cache=tmp_path_factory.mktemp("infusions"))
    scene.add_character(corpus_character("rpm"), "ann", position=(0.0, 0.0, 1.3), facing="bob",
                        packs=("locomotion-female",))
    scene.add_character(corpus_character("xbot"), "bob", position=(0.0, 0.0, 0.0), facing="ann",
                        packs=("locomotion-male",))
    scene.bml("ann", LOOK.format(id="ann_look", target="bob"), at=0.0)
    scene.bml("bob", LOOK.format(id="bob_look", target="ann"), at=0.0)
    scene.bml("ann", BML.format(seed=seed_with_aversion_and_look_back()), at=0.5)
    scene.run(scene.end_time + 0.5)
    return scene


def generated(scene, character):
    return [a for r in scene.scheduler.blocks.values() for a in r.activations
            if a.character == character and a.behaviour.startswith("nv")]


def frame(t: float) -> int:
    return int(round(t * FPS))


def test_every_generated_behaviour_plays(conversation):
    for name in ("ann", "bob"):
        made = generated(conversation, name)
        assert made and all((a.block, a.behaviour) in conversation.activities for a in made), name
    assert not [e for e in conversation.feedback.log if e.kind == "warningFeedback" and e.id.startswith("talk")]


def test_every_word_mark_is_timed_in_the_order_of_its_words(conversation):
    speech = next(a for a in conversation.scheduler.activations("ann") if a.controller == "speech")
    block = conversation.scheduler.blocks["talk"].block
    offsets = dict(next(b for b in block.behaviours if b.id == "s1").marks)
    times = [speech.parameters["marks_s"][m] for m in sorted(offsets, key=lambda m: (offsets[m], m.startswith("nvw")))]
    assert len(times) >= 6 and all(b > a for a, b in zip(times, times[1:])), times


def test_hand_gestures_are_on_the_arms_at_their_words(conversation):
    motion = conversation.motion("ann")
    rig = conversation.runtime.rig("ann")
    sk = motion.skeleton
    _, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    chest = {side: sk.parents[rig.joint(f"{side}_shoulder")] for side in ("l", "r")}
    wrist = {side: g_pos[:, rig.joint(f"{side}_wrist")] - g_pos[:, chest[side]] for side in ("l", "r")}
    speech = next(a for a in conversation.scheduler.activations("ann") if a.controller == "speech")
    marks = {m: speech.start + t for m, t in speech.parameters["marks_s"].items()}
    gestures = [a for a in generated(conversation, "ann") if a.controller in ("gesture", "pointing")]
    assert len(gestures) >= 3
    for a in gestures:
        stroke = frame(a.time("stroke"))
        assert any(abs(a.time("stroke") - t) < 1e-9 for t in marks.values())  # on a word the TTS timed
        moved = max(np.linalg.norm(wrist[s][stroke] - wrist[s][0]) for s in ("l", "r"))
        assert moved > 0.05, (a.parameters, moved)


def head_off_target_deg(scene, name, target) -> np.ndarray:
    """(F,) degrees between the way the head of ``name`` faces and the direction to the head of ``target``."""
    motion, other = scene.motion(name), scene.motion(target)
    rig = scene.runtime.rig(name)
    g_rot, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations,
                                      motion.joint_translations)
    _, o_pos = forward_kinematics(other.skeleton, other.local_rotations, other.root_translations, other.joint_translations)
    head = rig.joint("skullbase")
    rest = motion.skeleton.rest_global_rotations[head]
    forward = body_axes(corpus_character("rpm" if name == "ann" else "xbot"))[2]
    facing = quat.rotate(quat.multiply(g_rot[:, head], quat.conjugate(rest)), forward)
    to = o_pos[:, scene.runtime.rig(target).joint("skullbase")] - g_pos[:, head]
    to /= np.linalg.norm(to, axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.sum(facing * to, axis=1), -1.0, 1.0)))


def test_the_speaker_looks_away_at_the_start_and_back_at_the_end(conversation):
    off = head_off_target_deg(conversation, "ann", "bob")
    made = {a.element: a for a in generated(conversation, "ann")}
    aversion, back = made["gaze"], made["gazeShift"]
    before = off[frame(0.4)]
    away = off[frame(aversion.time("ready")):frame(aversion.time("relax")) + 1].max()
    after = off[frame(back.end) + 10:].mean()
    assert away > before + 8.0 and after < away - 8.0, (before, away, after)


def test_the_listener_nods_on_the_phrase_ends(conversation):
    motion = conversation.motion("bob")
    rig = conversation.runtime.rig("bob")
    g_rot, _ = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    head = rig.joint("skullbase")
    up = body_axes(corpus_character("xbot"))[1]
    tilt = quat.rotate(quat.multiply(g_rot[:, head], quat.conjugate(motion.skeleton.rest_global_rotations[head])), up)
    nods = [a for a in generated(conversation, "bob") if a.controller == "head"]
    assert nods
    for a in nods:
        window = tilt[frame(a.start):frame(a.end) + 1]
        swing = np.degrees(np.arccos(np.clip(window @ window[0], -1.0, 1.0))).max()
        assert swing > 3.0, (a.sync_times, swing)


def test_the_conversation_example_points_at_the_lamp_and_bob_listens_with_his_arms_crossed(monkeypatch):
    """``examples/scenes/conversation.toml`` (the demo's): Ann's index ray passes within 5 cm of the lamp at
    her pointing's stroke; Bob's right wrist is by his left elbow while he listens, away once he answers."""
    require_espeak()
    monkeypatch.setenv("INFUSE_CORPUS", str(require_corpus()))
    spec = read_scene_file(REPO / "examples" / "scenes" / "conversation.toml")
    scene = build_scene(spec)
    scene.run()
    made = [a for a in scene.scheduler.activations() if a.behaviour.startswith("nv")]
    assert made and all((a.block, a.behaviour) in scene.activities for a in made)
    (pointing,) = [a for a in made if a.element == "pointing" and a.parameters["target"] == "lamp"]
    ann, rig = scene.motion("ann"), scene.runtime.rig("ann")
    _, pos = forward_kinematics(ann.skeleton, ann.local_rotations, ann.root_translations, ann.joint_translations)
    at = frame(pointing.time("stroke"))
    lamp = np.asarray(scene.objects["lamp"].position)
    misses = []
    for side in ("l", "r"):
        wrist, tip = pos[at, rig.joint(f"{side}_wrist")], pos[at, rig.joint(f"{side}_index3")]
        ray = (tip - wrist) / np.linalg.norm(tip - wrist)
        misses.append(np.linalg.norm((lamp - wrist) - ray * max(np.dot(lamp - wrist, ray), 0.0)))
    assert min(misses) < 0.05, misses
    bob, rig = scene.motion("bob"), scene.runtime.rig("bob")
    _, pos = forward_kinematics(bob.skeleton, bob.local_rotations, bob.root_translations, bob.joint_translations)
    gap = np.linalg.norm(pos[:, rig.joint("r_wrist")] - pos[:, rig.joint("l_elbow")], axis=1)
    answer = scene.scheduler.blocks["bob_answer"]
    speech = answer.activation("s1")
    assert gap[frame(2.0):frame(answer.start_s)].max() < 0.15
    assert gap[frame(speech.end):].min() > 0.3, gap[frame(speech.end):].min()
