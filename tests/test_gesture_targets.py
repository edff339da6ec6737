"""Gestures with a target, measured by FK on the written motion: an offer, a wave and "this big" aimed at a
character or an object face it at the stroke (the hand's facing axis within 15 degrees of the line from
the wrist to the target), played by the hand on the target's side when the BML leaves the hand free; a
deictic gesture points (the ray from the shoulder through the index fingertip within 5 cm of the
target); on X Bot, the Ready Player Me avatar and the SmartBody utah skeleton."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.bml.model import NO_SUCH_TARGET
from infuse.scene import Scene

from corpus_data import require_corpus
from runtime_characters import corpus_character

FPS = 30.0
LAMP = (-1.3, 1.7, 1.6)
BML = """<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">
  <gesture id="g1" lexeme="OFFER" target="ann" stroke="1.2"/>
  <gesture id="g2" lexeme="WAVE" target="ann" stroke="3.6"/>
  <gesture id="g3" lexeme="THIS_BIG" target="lamp" stroke="6.2"/>
  <gesture id="g4" lexeme="DEICTIC" target="lamp" stroke="8.8"/>
  <gesture id="g5" lexeme="OFFER" mode="RIGHT_HAND" target="ann" stroke="11.2"/>
</bml>"""


@pytest.fixture(scope="module", params=["xbot", "rpm", "utah"])
def aimed(request, tmp_path_factory):
    require_corpus()
    scene = Scene(fps=FPS, tts=None, idle=False, quiet=True, pack_cache=tmp_path_factory.mktemp("infusions"))
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character(request.param), name="bob", packs=("locomotion-male",))
    scene.add_character(corpus_character("rpm"), name="ann", position=(1.6, 0.0, 2.2), facing="bob")
    scene.add_object("lamp", LAMP)
    scene.bml("bob", BML, at=0.0)
    scene.run(13.0)
    rig = scene.runtime.rig("bob")
    ann = scene.runtime.rig("ann")
    _, g_pos = infuse.motion_fk(scene.motion("bob"))
    _, ann_pos = infuse.motion_fk(scene.motion("ann"))
    return {"scene": scene, "warnings": warnings, "rig": rig, "g_pos": g_pos, "ann_pos": ann_pos,
            "ann_ix": ann.mapping.indices(ann.skeleton), "ix": rig.mapping.indices(rig.skeleton)}


def _target(p, behaviour: str, frame: int) -> np.ndarray:
    if behaviour in ("g3", "g4"):
        return np.array(LAMP)
    return p["ann_pos"][frame, [p["ann_ix"]["eyeball_left"], p["ann_ix"]["eyeball_right"]]].mean(axis=0)


def _facing_angle_deg(p, behaviour: str) -> tuple[float, str]:
    """Degrees between the aimed hand's facing axis and the line from its wrist to the target at the
    stroke, and the hand."""
    activity = p["scene"].activities[("b1", behaviour)]
    frame = int(round(activity.source.time("stroke") * FPS))
    (arm,) = activity.binding.aimed
    (hand,) = activity.controller.hands
    s, pos, ix = hand[0], p["g_pos"][frame], p["ix"]
    fingers = pos[ix[f"{s}_middle1"]] - pos[ix[f"{s}_wrist"]]
    axis = fingers
    if arm.palm:
        axis = (1.0 if s == "r" else -1.0) * np.cross(fingers, pos[ix[f"{s}_pinky1"]] - pos[ix[f"{s}_index1"]])
    to_target = _target(p, behaviour, frame) - pos[ix[f"{s}_wrist"]]
    cos = axis @ to_target / np.linalg.norm(axis) / np.linalg.norm(to_target)
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))), hand


def test_aimed_gestures_face_their_target_at_the_stroke(aimed):
    angles = {b: _facing_angle_deg(aimed, b) for b in ("g1", "g2", "g3", "g5")}
    print({b: round(a, 2) for b, (a, _) in angles.items()})
    assert max(a for a, _ in angles.values()) < 15.0, angles
    # The hand on the target's side when the BML leaves it free (ann to bob's left, the lamp to his right).
    assert {b: h for b, (_, h) in angles.items()} == {"g1": "left", "g2": "left", "g3": "right", "g5": "right"}
    # An offer faces with its fingers, a wave with its palm.
    assert not aimed["scene"].activities[("b1", "g1")].binding.aimed[0].palm
    assert aimed["scene"].activities[("b1", "g2")].binding.aimed[0].palm


def test_a_deictic_gesture_points_at_its_target(aimed):
    activity = aimed["scene"].activities[("b1", "g4")]
    assert activity.controller.kind == "pointing"
    frame = int(round(activity.source.time("stroke") * FPS))
    pos, ix = aimed["g_pos"][frame], aimed["ix"]
    shoulder, tip = pos[ix["r_shoulder"]], pos[ix["r_index4"]] if "r_index4" in ix else pos[ix["r_index3"]]
    u = (tip - shoulder) / np.linalg.norm(tip - shoulder)
    d = np.array(LAMP) - shoulder
    assert d @ u > 0 and np.linalg.norm(d - (d @ u) * u) < 0.05


def test_no_warnings_and_an_unknown_target_is_named(aimed):
    assert not aimed["warnings"], [w.description for w in aimed["warnings"]]
    scene = Scene(fps=FPS, tts=None, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob")
    scene.bml("bob", '<bml id="b2"><gesture id="g" lexeme="OFFER" target="nobody" stroke="1"/></bml>', at=0.0)
    scene.run(2.0)
    said = [w for w in warnings if w.id == "b2:g"]
    assert said and said[0].type == NO_SUCH_TARGET and "nobody" in said[0].description
