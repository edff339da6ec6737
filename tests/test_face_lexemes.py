"""BML <faceLexeme>: BML 1.0's lexemes and the common expressions on faces of each style, measured on the
output: ARKit morph weights (the Ready Player Me avatar), VRM preset expressions (VRM 1.0 names and a VRoid
avatar's own), SmartBody face poses (Brad's brow and lip joints by FK); one-sided lexemes stay on their side;
an unknown lexeme warns at scheduling, naming the known ones."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import Character
from infuse.bml import Scheduler
from infuse.kinematics import forward_kinematics
from infuse.mapping import map_skeleton
from infuse.scene import Scene

from corpus_data import corpus_file
from runtime_characters import corpus_character, synthetic_character

FPS = 30.0
BML = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1" characterId="bob">{body}</bml>'
#: Seconds of each lexeme's window: in by 0.2 s, held 0.4 s, out by 0.2 s; sampled at its middle.
WINDOW = (0.5, 0.7, 1.1, 1.3)
SAMPLE_S = 0.9

#: Per lexeme, the ARKit shapes that must rise (to at least 0.3 at amount 1) and those that must stay at 0.
ARKIT = {
    "RAISE_BROWS": ({"browInnerUp", "browOuterUpLeft", "browOuterUpRight"}, set()),
    "RAISE_LEFT_BROW": ({"browOuterUpLeft"}, {"browOuterUpRight"}),
    "RAISE_RIGHT_BROW": ({"browOuterUpRight"}, {"browOuterUpLeft"}),
    "LOWER_BROWS": ({"browDownLeft", "browDownRight"}, set()),
    "LOWER_LEFT_BROW": ({"browDownLeft"}, {"browDownRight"}),
    "LOWER_RIGHT_BROW": ({"browDownRight"}, {"browDownLeft"}),
    "OBLIQUE_BROWS": ({"browInnerUp", "browDownLeft", "browDownRight"}, {"browOuterUpLeft"}),
    "WIDEN_EYES": ({"eyeWideLeft", "eyeWideRight"}, set()),
    "CLOSE_EYES": ({"eyeBlinkLeft", "eyeBlinkRight"}, set()),
    "SMILE": ({"mouthSmileLeft", "mouthSmileRight"}, set()),
    "RAISE_MOUTH_CORNERS": ({"mouthSmileLeft", "mouthSmileRight"}, set()),
    "RAISE_LEFT_MOUTH_CORNER": ({"mouthSmileLeft"}, {"mouthSmileRight"}),
    "RAISE_RIGHT_MOUTH_CORNER": ({"mouthSmileRight"}, {"mouthSmileLeft"}),
    "LOWER_MOUTH_CORNERS": ({"mouthFrownLeft", "mouthFrownRight"}, set()),
    "LOWER_LEFT_MOUTH_CORNER": ({"mouthFrownLeft"}, {"mouthFrownRight"}),
    "LOWER_RIGHT_MOUTH_CORNER": ({"mouthFrownRight"}, {"mouthFrownLeft"}),
    "OPEN_MOUTH": ({"jawOpen"}, set()),
    "OPEN_LIPS": ({"mouthLowerDownLeft", "mouthLowerDownRight"}, set()),
    "BARE_TEETH": ({"mouthUpperUpLeft", "mouthUpperUpRight"}, set()),
    "happy": ({"mouthSmileLeft", "cheekSquintLeft"}, {"mouthFrownLeft"}),
    "sad": ({"mouthFrownLeft", "browInnerUp"}, {"mouthSmileLeft"}),
    "angry": ({"browDownLeft", "eyeSquintLeft"}, {"browInnerUp"}),
    "surprised": ({"browOuterUpLeft", "eyeWideLeft", "jawOpen"}, {"browDownLeft"}),
    "fear": ({"browInnerUp", "eyeWideLeft", "mouthStretchLeft"}, {"mouthSmileLeft"}),
    "disgust": ({"noseSneerLeft", "mouthUpperUpLeft"}, {"mouthSmileLeft"}),
}
#: Per lexeme, the VRM preset expressions that must rise (to at least 0.2) and those that must stay at 0.
VRM = {
    "RAISE_BROWS": ({"surprised"}, {"angry"}), "RAISE_LEFT_BROW": ({"surprised"}, {"angry"}),
    "LOWER_BROWS": ({"angry"}, {"surprised"}), "OBLIQUE_BROWS": ({"sad"}, {"happy"}),
    "WIDEN_EYES": ({"surprised"}, {"blink"}), "CLOSE_EYES": ({"blink"}, {"surprised"}),
    "SMILE": ({"happy"}, {"sad"}), "RAISE_MOUTH_CORNERS": ({"happy"}, {"sad"}),
    "LOWER_MOUTH_CORNERS": ({"sad"}, {"happy"}), "OPEN_MOUTH": ({"aa"}, set()), "OPEN_LIPS": ({"aa"}, set()),
    "BARE_TEETH": ({"angry", "aa"}, {"happy"}),
    "happy": ({"happy"}, {"sad"}), "sad": ({"sad"}, {"happy"}), "angry": ({"angry"}, {"happy"}),
    "surprised": ({"surprised"}, {"angry"}), "fear": ({"surprised", "sad"}, {"happy"}),
    "disgust": ({"angry", "sad"}, {"happy"}),
}
VRM_PRESETS = ("happy", "angry", "sad", "relaxed", "surprised", "neutral", "blink", "blinkLeft", "blinkRight",
               "aa", "ih", "ou", "ee", "oh")


def play(character, lexemes) -> tuple[Scene, infuse.Motion]:
    """Each lexeme at amount 1 in its own window, one after the other; the scene and its motion."""
    scene = Scene(fps=FPS, tts=None, quiet=True, idle=False)
    scene.add_character(character, "bob")
    start, peak, relax, end = WINDOW
    scene.bml("bob", BML.format(body="".join(
        f'<faceLexeme id="f{k}" lexeme="{lexeme}" amount="1" start="{k + start}" attackPeak="{k + peak}" '
        f'relax="{k + relax}" end="{k + end}"/>' for k, lexeme in enumerate(lexemes))), at=0.0)
    assert not [e for e in scene.feedback.log if e.kind == "warningFeedback" and e.id.startswith("b1:")]
    scene.run(len(lexemes) + 0.5)
    return scene, scene.motion("bob")


def sampled_weights(scene, lexemes) -> dict[str, dict[str, float]]:
    """Lexeme -> morph target -> weight at the middle of its window."""
    weights = scene.runtime.morph_weights("bob")
    names = scene.runtime.rig("bob").morph_targets
    return {lexeme: dict(zip(names, weights[int(round((k + SAMPLE_S) * FPS))])) for k, lexeme in enumerate(lexemes)}


def test_arkit_faces_show_every_lexeme_on_its_shapes():
    character = corpus_character("rpm")
    scene, _ = play(character, list(ARKIT))
    for lexeme, weights in sampled_weights(scene, list(ARKIT)).items():
        rise, still = ARKIT[lexeme]
        assert all(weights[t] >= 0.3 for t in rise), (lexeme, {t: weights[t] for t in rise})
        assert all(weights[t] == 0.0 for t in still), (lexeme, {t: weights[t] for t in still})
    # Between windows the face is back at rest.
    rest = scene.runtime.morph_weights("bob")[int(round(0.3 * FPS))]
    assert not rest.any()


def _vroid_names() -> tuple[str, ...]:
    """The VRoid avatar's own expression and mouth shapes (its Fcl_ morph targets, without its ARKit set)."""
    return tuple(n for n in infuse.load(corpus_file("talkinghead/avatars/vroid.glb")).morph_targets if n.startswith("Fcl_"))


@pytest.mark.parametrize("style", ["vrm1", "vroid"])
def test_vrm_faces_show_every_lexeme_with_their_presets(style):
    from infuse_lipsync.channels import detect_face

    names = VRM_PRESETS if style == "vrm1" else _vroid_names()
    character = synthetic_character("vrm", morphs=names)
    face = detect_face(character.asset)
    bound = {channel: binds[0][0] for vocabulary in ("vrm_expressions", "vrm") for channel, binds in
             face.vocabularies[vocabulary].items()}
    scene, _ = play(character, list(VRM))
    for lexeme, weights in sampled_weights(scene, list(VRM)).items():
        rise, still = VRM[lexeme]
        assert all(weights[bound[c]] >= 0.2 for c in rise), (lexeme, {c: weights[bound[c]] for c in rise})
        assert all(weights[bound[c]] == 0.0 for c in still if c in bound), lexeme


def test_smartbody_face_poses_show_every_lexeme_on_brows_and_lips():
    asset = infuse.load(corpus_file("smartbody/ChrBrad/ChrBrad.sk"))
    character = Character("brad", asset, mapping=map_skeleton(asset))
    lexemes = ["RAISE_BROWS", "RAISE_LEFT_BROW", "RAISE_RIGHT_BROW", "LOWER_BROWS", "LOWER_LEFT_BROW", "OBLIQUE_BROWS",
               "SMILE", "RAISE_LEFT_MOUTH_CORNER", "LOWER_MOUTH_CORNERS", "OPEN_MOUTH", "BARE_TEETH", "CLOSE_EYES",
               "WIDEN_EYES", "happy", "sad", "angry", "surprised", "fear", "disgust"]
    scene, motion = play(character, lexemes)
    sk = motion.skeleton
    g_rot, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    up = g_pos[:, :, 1] - g_pos[0, :, 1]  # (F, J) how far each joint rose, metres (nothing else moves the head)
    rot = {n: np.degrees(2.0 * np.arccos(np.clip(np.abs(np.sum(motion.local_rotations[:, sk.index[n]] *
                                                               motion.local_rotations[0, sk.index[n]], axis=-1)), 0, 1)))
           for n in ("JtEyelidUpperLf", "JtJaw")}

    def at(k, name, table=up):
        f = int(round((k + SAMPLE_S) * FPS))
        return table[name][f] if isinstance(table, dict) else table[f, sk.index[name]]

    k = {lexeme: i for i, lexeme in enumerate(lexemes)}
    assert at(k["RAISE_BROWS"], "JtEyebrow01Lf") > 0.005 and at(k["RAISE_BROWS"], "JtEyebrow01Rt") > 0.005
    assert at(k["RAISE_LEFT_BROW"], "JtEyebrow01Lf") > 0.002 and abs(at(k["RAISE_LEFT_BROW"], "JtEyebrow01Rt")) < 1e-4
    assert at(k["RAISE_RIGHT_BROW"], "JtEyebrow01Rt") > 0.002 and abs(at(k["RAISE_RIGHT_BROW"], "JtEyebrow01Lf")) < 1e-4
    assert at(k["LOWER_BROWS"], "JtEyebrow03Lf") < -0.002 and at(k["LOWER_BROWS"], "JtEyebrow01Rt") < -0.002
    assert at(k["LOWER_LEFT_BROW"], "JtEyebrow01Lf") < -0.002 and abs(at(k["LOWER_LEFT_BROW"], "JtEyebrow01Rt")) < 1e-4
    assert at(k["OBLIQUE_BROWS"], "JtEyebrow01Lf") > 0.002 and at(k["OBLIQUE_BROWS"], "JtEyebrow03Lf") < 0.0
    assert at(k["SMILE"], "JtLipCornerLf") > 0.002 and at(k["sad"], "JtLipCornerLf") < -0.002
    assert at(k["RAISE_LEFT_MOUTH_CORNER"], "JtLipCornerLf") > 0.002
    assert abs(at(k["RAISE_LEFT_MOUTH_CORNER"], "JtLipCornerRt")) < 1e-4
    assert at(k["LOWER_MOUTH_CORNERS"], "JtLipCornerLf") < -0.001
    assert at(k["BARE_TEETH"], "JtLipUpperMid") > 0.001
    assert at(k["OPEN_MOUTH"], "JtJaw", rot) > 4.0 and at(k["surprised"], "JtJaw", rot) > 4.0
    assert at(k["CLOSE_EYES"], "JtEyelidUpperLf", rot) > 15.0 and at(k["WIDEN_EYES"], "JtEyelidUpperLf", rot) > 5.0
    assert at(k["angry"], "JtEyebrow01Lf") < -0.002 and at(k["surprised"], "JtEyebrow01Lf") > 0.002
    assert at(k["fear"], "JtEyebrow01Lf") > 0.002 and at(k["happy"], "JtLipCornerLf") != 0.0
    assert at(k["disgust"], "JtLipUpperMid") > 0.001


def test_unknown_lexemes_warn_at_scheduling_naming_the_known_ones():
    scheduler = Scheduler()
    warnings = []
    scheduler.feedback.subscribe(warnings.append, kinds=["warningFeedback"])
    (block,) = scheduler.submit(BML.format(body='<faceLexeme id="f1" lexeme="JUGGLE_EARS"/>'
                                                '<faceLexeme id="f2" lexeme="BARE_TEETH" start="1"/>'), at=0.0)
    assert [a.behaviour for a in block.activations] == ["f2"]
    (warning,) = warnings
    assert warning.id == "b1:f1" and "JUGGLE_EARS" in warning.description
    assert "RAISE_LEFT_BROW" in warning.description and "disgust" in warning.description
