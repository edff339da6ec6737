"""``infuse speak`` gives the body a living idle: it stands in a pack's idle on both feet, breathes,
blinks, moves its eyes and nods on the beats, while the mouth speaks; ``--face-only`` moves the face only."""
from __future__ import annotations

import json
import struct

import numpy as np
import pytest

import infuse
from corpus_data import corpus_file, require_corpus
from espeak_support import require_espeak
from infuse import quaternions as quat
from infuse.cli import main
from infuse.contacts import feet, lowest_points
from infuse.grounding import foot_height
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse_gltf.container import parse_file
from infuse_lipsync.body import beats, idle_body, with_face

RPM = "talkinghead/avatars/brunette-t.glb"
VROID = "talkinghead/avatars/vroid.glb"
TEXT = "Hello, I am infused. It is good to meet you all here today."


@pytest.fixture(scope="module")
def espeak():
    require_espeak()


def _speak(tmp_path, rel: str, *options) -> infuse.Asset:
    require_corpus()
    out = tmp_path / "out.glb"
    assert main(["speak", str(corpus_file(rel)), TEXT, "-o", str(out), *options]) == 0
    assert [a["name"] for a in parse_file(out).json["animations"]] == ["speech"]  # the first, and only, animation
    return infuse.load(out)


def _turns_deg(asset: infuse.Asset, names) -> dict[str, float]:
    """Largest turn (degrees) of each joint's global rotation from its first frame."""
    g, _ = motion_fk(asset.motions["speech"])
    return {n: float(np.degrees(quat.angle_between(g[:, asset.skeleton.index[n]], g[:1, asset.skeleton.index[n]])).max())
            for n in names}


def test_beats_fall_on_words_at_least_a_gap_apart():
    words = [(0.1, 0.4, "hello"), (0.5, 0.9, "i"), (1.7, 2.0, "am"), (2.1, 2.5, "here"), (3.3, 3.6, "now")]
    assert beats(words, gap_s=1.5) == [0.1, 1.7, 3.3]
    assert beats([]) == []


@pytest.mark.parametrize("rel", [RPM, VROID], ids=["ready-player-me", "vroid"])
def test_the_body_lives_while_the_mouth_speaks(espeak, tmp_path, rel):
    asset = _speak(tmp_path, rel)
    motion = asset.motions["speech"]
    mapping = map_skeleton(asset)
    weights = dict(zip(asset.motions["speech"].morph_names, asset.motions["speech"].morph_weights.T))
    assert max(np.max(weights[k]) for k in weights if k.startswith("viseme_")) > 0.5  # the mouth speaks
    assert max(np.max(weights[k]) for k in weights if "blink" in k.lower()) > 0.5  # the eyes blink
    turns = _turns_deg(asset, [mapping.joints[n] for n in ("spine3", "skullbase", "eyeball_left")])
    assert all(turns[mapping.joints[n]] > 0.5 for n in ("spine3", "skullbase", "eyeball_left")), turns  # breath, nods, saccades
    # out of its T-pose: the hands hang below the shoulders; both feet on the ground throughout
    _, p = motion_fk(motion)
    j = mapping.indices(asset.skeleton)
    assert np.all(p[:, j["l_shoulder"], 1] - p[:, j["l_wrist"], 1] > 0.3)
    low = lowest_points(asset.skeleton, feet(asset.skeleton, mapping), *motion_fk(motion))  # (F, 2) joints
    assert abs(foot_height(asset, mapping, motion)) < 1e-4  # the soles touch y = 0
    assert np.all(low - low.min(axis=0) < 0.01)  # neither foot lifts: weight on both


def test_face_only_leaves_the_body_at_rest(espeak, tmp_path):
    asset = _speak(tmp_path, VROID, "--face-only")
    weights = dict(zip(asset.motions["speech"].morph_names, asset.motions["speech"].morph_weights.T))
    assert all(np.max(weights[k]) == 0.0 for k in weights if "blink" in k.lower())
    rotations = asset.motions["speech"].local_rotations  # a morph face: every joint holds its rest
    assert np.all(quat.angle_between(rotations, asset.skeleton.rest_rotations[None]) < 1e-6)


def test_a_character_that_is_not_a_humanoid_keeps_only_its_face():
    require_corpus()
    fox = infuse.load(corpus_file("projectlookingglass-glb/Fox.glb"))
    idle, body = idle_body(fox, 30, 30.0)
    assert idle is None and body.startswith("face only (")


def test_the_speech_laid_over_the_idle_keeps_the_blinks_and_the_body():
    sk = infuse.Skeleton(["hips", "head", "jaw"], [-1, 0, 1], np.array([[0, 1, 0], [0, 0.5, 0], [0, 0.1, 0.0]]),
                         np.tile(quat.IDENTITY, (3, 1)))
    nod = quat.from_axis_angle([1, 0, 0], np.linspace(0.0, 0.3, 5))
    body_rot = np.tile(quat.IDENTITY, (5, 3, 1))
    body_rot[:, 1] = nod
    idle = infuse.Motion(sk, 30.0, body_rot, np.zeros((5, 3)), name="speech", morph_names=["eyeBlinkLeft"],
                         morph_weights=np.array([[0.0], [1.0], [0.2], [0.0], [0.0]]))
    jaw = quat.from_axis_angle([1, 0, 0], np.array([0.0, 0.1, 0.2, 0.1]))
    face_rot = np.tile(quat.IDENTITY, (4, 3, 1))
    face_rot[:, 2] = jaw
    speech = infuse.Motion(sk, 30.0, face_rot, np.zeros((4, 3)), name="speech", animated_joints=[False, False, True],
                           morph_names=["eyeBlinkLeft", "viseme_aa"],
                           morph_weights=np.array([[0.0, 0.0], [0.0, 0.5], [0.0, 0.9], [0.0, 0.1]]))
    merged = with_face(idle, speech)
    assert merged.num_frames == 4 and merged.morph_names == ("eyeBlinkLeft", "viseme_aa")
    assert merged.morph_weight("eyeBlinkLeft").tolist() == [0.0, 1.0, 0.2, 0.0]  # the blink is not held open
    assert merged.morph_weight("viseme_aa").tolist() == [0.0, 0.5, 0.9, 0.1]
    assert np.allclose(merged.local_rotations[:, 2], jaw) and np.allclose(merged.local_rotations[:, 1], nod[:4])
    assert with_face(idle, None) is idle


def _as_vrm(source, target):
    """``source`` (a glb) written as a VRM 1.0 file: humanoid bones from the mapper, expressions bound to its
    mouth and eyelid morph targets (VRoid's ``Fcl_`` set), the binary chunk unchanged."""
    data = source.read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    doc, rest = json.loads(data[20:20 + n]), data[20 + n:]
    mapping = map_skeleton(infuse.load(source))
    nodes = {nd.get("name"): i for i, nd in enumerate(doc["nodes"])}
    canonical = {"hips": "base", "spine": "spine1", "chest": "spine3", "neck": "spine4", "head": "skullbase"}
    for side, s in (("left", "l"), ("right", "r")):
        canonical.update({side + "UpperLeg": s + "_hip", side + "LowerLeg": s + "_knee", side + "Foot": s + "_ankle",
                          side + "UpperArm": s + "_shoulder", side + "LowerArm": s + "_elbow", side + "Hand": s + "_wrist"})
    face = next(i for i, nd in enumerate(doc["nodes"]) if "mesh" in nd
                and doc["meshes"][nd["mesh"]].get("extras", {}).get("targetNames"))
    targets = doc["meshes"][doc["nodes"][face]["mesh"]]["extras"]["targetNames"]
    bind = lambda name: {"morphTargetBinds": [{"node": face, "index": targets.index(name), "weight": 1.0}]}  # noqa: E731
    doc.setdefault("extensionsUsed", []).append("VRMC_vrm")
    doc.setdefault("extensions", {})["VRMC_vrm"] = {
        "specVersion": "1.0", "meta": {"name": "vrm", "authors": ["infuse tests"], "licenseUrl": "https://vrm.dev/licenses/1.0/"},
        "humanoid": {"humanBones": {bone: {"node": nodes[mapping.joints[c]]} for bone, c in canonical.items()}},
        "expressions": {"preset": {"aa": bind("Fcl_MTH_A"), "ih": bind("Fcl_MTH_I"), "ou": bind("Fcl_MTH_U"),
                                   "ee": bind("Fcl_MTH_E"), "oh": bind("Fcl_MTH_O"), "blink": bind("Fcl_EYE_Close")}}}
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    target.write_bytes(struct.pack("<III", 0x46546C67, 2, 20 + len(text) + len(rest))
                       + struct.pack("<II", len(text), 0x4E4F534A) + text + rest)
    return target


def test_a_vrm_character_speaks_breathes_and_blinks(espeak, tmp_path):
    require_corpus()
    vrm = _as_vrm(corpus_file(VROID), tmp_path / "avatar.vrm")
    assert infuse.load(vrm).meta["vrm_version"] == "1.0"
    out = tmp_path / "out.glb"
    assert main(["speak", str(vrm), TEXT, "-o", str(out)]) == 0
    asset = infuse.load(out)
    weights = dict(zip(asset.motions["speech"].morph_names, asset.motions["speech"].morph_weights.T))
    assert max(np.max(weights[k]) for k in ("Fcl_MTH_A", "Fcl_MTH_O")) > 0.5  # the VRM mouth speaks
    assert max(np.max(weights[k]) for k in weights if "blink" in k.lower()) > 0.5  # the eyes blink
    mapping = map_skeleton(asset)
    turns = _turns_deg(asset, [mapping.joints[n] for n in ("spine3", "skullbase")])
    assert all(t > 0.5 for t in turns.values()), turns  # it breathes and nods
