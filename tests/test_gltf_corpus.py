"""The glTF/VRM/VRMA plugin on the corpus: loading, labels, folding, an independent FK check, and
read -> add a clip -> write -> Khronos validator -> read back."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.cli.builtin import asset_summary
from infuse.kinematics import motion_fk
from infuse_gltf import validate as validator
from infuse_gltf.accessors import AccessorReader
from infuse_gltf.container import parse_file

from corpus_data import CORPUS, corpus_file, labels, require_corpus

GLTF_SUFFIXES = (".glb", ".gltf", ".vrm", ".vrma")
GLTF_LABELS = [doc for doc in labels() if doc["file"].lower().endswith(GLTF_SUFFIXES)]
INFUSE_CLI = Path(sys.executable).with_name("infuse")
NEW_CLIP = "infuse_added"


def _ids(docs):
    return [doc["file"].rsplit("/", 1)[-1] for doc in docs]


def _corpus_gltf_files() -> list[str]:
    """Every glTF-family file of the corpus (labelled or not), relative to the corpus root."""
    if not CORPUS.is_dir():
        return []
    return sorted(str(p.relative_to(CORPUS)) for p in CORPUS.rglob("*") if p.suffix.lower() in GLTF_SUFFIXES)


@pytest.fixture(scope="module")
def assets():
    require_corpus()
    return {rel: infuse.load(corpus_file(rel)) for rel in _corpus_gltf_files()}


def test_corpus_has_gltf_files():
    require_corpus()
    formats = {doc["meta"]["format"].split(" ")[0] for doc in GLTF_LABELS}
    assert len(GLTF_LABELS) >= 13 and {"glTF", "VRM"} <= formats
    assert {doc["file"] for doc in GLTF_LABELS} <= set(_corpus_gltf_files())


@pytest.mark.parametrize("doc", GLTF_LABELS, ids=_ids(GLTF_LABELS))
def test_joints_contain_every_mapped_name(assets, doc):
    asset = assets[doc["file"]]
    summary = asset_summary(asset)
    wanted = {name for name in doc["mapping"].values() if name is not None}
    assert wanted <= set(summary["joints"])
    assert summary["units"] == "m" and summary["up_axis"] == "Y" and summary["units_detected_by"] == "file"
    assert len(asset.motions) == doc["meta"]["animations"]
    json.dumps(summary)


def test_cli_info_json_on_a_vrm():
    doc = next(d for d in GLTF_LABELS if d["file"].endswith(".vrm"))
    run = subprocess.run([str(INFUSE_CLI), "info", "--json", str(corpus_file(doc["file"]))],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["format"] == "vrm" and summary["meta"]["vrm_version"] == "1.0"
    assert summary["humanoid"]["hips"] == "Hips" and summary["humanoid"]["leftHand"] == "Hand.L"
    # its two expressions bind no morph target (only materials): listed, but nothing can animate them
    assert summary["meta"]["vrm_expressions"] == ["happy", "blink"] and summary["morph_targets"] == []


def test_xbot_armature_scale_is_folded(assets):
    asset = assets["runxaway-models/Xbot.glb"]
    sk = asset.skeleton
    assert asset.meta["folded_nodes"] == ["Armature"]  # rotation +90° X and scale 0.01
    pos = sk.rest_global_positions
    head, hips = pos[sk.index["mixamorig:Head"]], pos[sk.index["mixamorig:Hips"]]
    assert 1.5 < head[1] < 1.8 and 0.9 < hips[1] < 1.2  # upright, in metres
    assert 1.6 < sk.height() < 2.0
    assert pos[sk.index["mixamorig:LeftHand"], 0] > 0.5  # faces +Z: the left hand is at +X
    assert asset.meta["bind_pose"]["checked"] and asset.meta["bind_pose"]["matches_rest"]


def test_corpus_facts(assets):
    robot = assets["adibkn1-robot/RobotExpressive.glb"]
    assert robot.morph_targets == ["Angry", "Surprised", "Sad"]
    assert len(robot.motions) == 14 and all(m.fps == 24 for m in robot.motions.values())
    dance = robot.motions["Dance"]
    assert set(dance.morph_names) == {"Angry", "Surprised", "Sad"} and robot.motions["Idle"].morph_names
    assert dance.morph_weights.shape == (dance.num_frames, 3) and dance.animated_joints is None
    assert not robot.meta["bind_pose"]["matches_rest"]  # its rest pose is not the bind pose
    brunette = assets["talkinghead/avatars/brunette-t.glb"]
    assert brunette.morph_targets[:2] == ["viseme_sil", "viseme_PP"] and len(brunette.morph_targets) == 67
    vroid = assets["talkinghead/avatars/vroid.glb"]
    assert "EXT_meshopt_compression" in vroid.meta["compression"]
    assert vroid.skeleton.num_joints == 244
    # Its inverse bind matrices are meshopt-compressed: decoded, they agree with the rest pose.
    assert vroid.meta["bind_pose"]["checked"] and vroid.meta["bind_pose"]["matches_rest"]
    assert vroid.meta["bind_pose"]["max_translation_deviation_m"] < 1e-4
    vrma = assets["three-vrm/packages/three-vrm-animation/examples/models/test.vrma"]
    assert vrma.format == "vrma" and vrma.humanoid["rightUpperArm"] == "rightUpperArm"
    assert {"happy", "lookAt"}.isdisjoint(vrma.skeleton.names)  # expression and gaze nodes are not joints
    happy = vrma.motions["animation0"].morph_weight("happy")
    assert happy.min() >= 0 and happy.max() > 0.5
    cesium = assets["chromedays-lab0/assets/CesiumMan.glb"]
    assert cesium.meta["folded_nodes"] == ["Z_UP", "Armature"]  # matrix nodes above the skeleton
    assert cesium.motions["animation0"].fps == 24
    fox = assets["projectlookingglass-glb/Fox.glb"]
    assert fox.motions["Armature|Take 001|BaseLayer"].fps == 25


def _first_key_world_positions(path: Path, anim_index: int, joint_nodes, last: bool) -> np.ndarray:
    """World positions of ``joint_nodes`` with every channel at its first (or last) key, computed with
    4x4 matrices straight from the file: an independent check of the reader's folding."""
    doc = parse_file(path)
    js = doc.json
    acc = AccessorReader(doc)
    local = {}
    for i, node in enumerate(js["nodes"]):
        if "matrix" in node:
            local[i] = np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
            continue
        local[i] = [np.array(node.get("translation", [0, 0, 0]), float), np.array(node.get("rotation", [0, 0, 0, 1]), float),
                    np.array(node.get("scale", [1, 1, 1]), float)]
    anim = js["animations"][anim_index]
    for ch in anim["channels"]:
        path_ = ch["target"]["path"]
        if path_ not in ("translation", "rotation", "scale"):
            continue
        spl = anim["samplers"][ch["sampler"]]
        out = np.asarray(acc.read(spl["output"]), dtype=np.float64)
        if spl.get("interpolation") == "CUBICSPLINE":
            out = out[1::3]
        local[ch["target"]["node"]][("translation", "rotation", "scale").index(path_)] = out[-1 if last else 0]
    mats = {}
    for i, v in local.items():
        if isinstance(v, list):
            m = np.eye(4)
            m[:3, :3] = quat.to_matrix(v[1] / np.linalg.norm(v[1])) * v[2]
            m[:3, 3] = v[0]
            v = m
        mats[i] = v
    parent = {c: i for i, n in enumerate(js["nodes"]) for c in n.get("children", [])}

    def world(i):
        return world(parent[i]) @ mats[i] if i in parent else mats[i]

    return np.array([world(n)[:3, 3] for n in joint_nodes])


ANIMATED = ["chromedays-lab0/assets/CesiumMan.glb", "runxaway-models/Xbot.glb", "adibkn1-robot/RobotExpressive.glb",
            "projectlookingglass-glb/Fox.glb", "chromedays-lab0/assets/godotman.glb", "colesam-uploads/Soldier.glb",
            "three-vrm/packages/three-vrm-animation/examples/models/test.vrma", "you-app-earth/Assets/Assets/Armature.glb"]


@pytest.mark.parametrize("rel", ANIMATED, ids=[r.rsplit("/", 1)[-1] for r in ANIMATED])
def test_first_and_last_frames_match_a_matrix_chain(assets, rel):
    asset = assets[rel]
    rig = asset.payload.rig
    for name, motion in list(asset.motions.items())[:3]:
        info = asset.meta["clips"][name]
        _, pos = motion_fk(motion)
        for frame, last in ((0, False), (-1, True)):
            expected = _first_key_world_positions(corpus_file(rel), info["animation"], rig.joint_nodes, last)
            assert np.abs(pos[frame] - expected).max() < 1e-5, (name, frame)


# -- read -> add a clip -> write -> validate -> read back ------------------------------------------
def _added_clip(asset) -> infuse.Motion:
    """A 2 s clip that turns the first joints and moves the root forward."""
    sk = asset.skeleton
    frames = 61
    rot = np.broadcast_to(sk.rest_rotations, (frames, sk.num_joints, 4)).copy()
    angle = np.linspace(0.0, 1.2, frames)
    for j, axis in zip(range(1, min(5, sk.num_joints)), np.eye(3)[[2, 0, 1, 2]]):
        rot[:, j] = quat.multiply(sk.rest_rotations[j], quat.from_axis_angle(axis, angle))
    root = sk.rest_translations[0] + np.linspace(0.0, 0.5, frames)[:, None] * np.array([0.0, 0.0, 1.0])
    return infuse.Motion(sk, 30.0, rot, root, name=NEW_CLIP)


def _drivable_target(asset) -> str | None:
    """The last name a morph-weight track can drive: a mesh morph target or a VRMA expression."""
    names = [n for group in asset.payload.target_names for n in group]
    if asset.format == "vrma":
        names += asset.meta["vrm_expressions"]
    return names[-1] if names else None


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Every corpus glb/vrm/vrma read, given a clip (with morph weights), written and validated once:
    relative path -> (asset with the clip, written path, validator report)."""
    require_corpus()
    if not validator.available():
        pytest.fail("the Khronos glTF validator is missing: run `make setup`")
    out_dir = tmp_path_factory.mktemp("gltf_out")
    out = {}
    for rel in _corpus_gltf_files():
        asset = infuse.load(corpus_file(rel))
        clip = _added_clip(asset)
        target_name = _drivable_target(asset)
        if target_name:
            clip = clip.replace(morph_names=[target_name], morph_weights=np.sin(clip.frame_times)[:, None] ** 2)
        asset.motions[NEW_CLIP] = clip
        target = out_dir / rel.replace("/", "__")
        infuse.save(asset, target)
        out[rel] = (asset, target)
    reports = validator.validate_files([path for _, path in out.values()])
    return {rel: (asset, path, report) for (rel, (asset, path)), report in zip(out.items(), reports)}


@pytest.mark.parametrize("rel", _corpus_gltf_files(), ids=[r.rsplit("/", 1)[-1] for r in _corpus_gltf_files()])
def test_written_copy_passes_validator_and_reads_back(written, rel):
    before, path, report = written[rel]
    assert report["issues"]["numErrors"] == 0, validator.errors(report)
    after = infuse.load(path)
    assert after.skeleton.names == before.skeleton.names
    assert np.abs(after.skeleton.rest_global_positions - before.skeleton.rest_global_positions).max() < 1e-6
    _, want = motion_fk(before.motions[NEW_CLIP])
    _, got = motion_fk(after.motions[NEW_CLIP])
    assert got.shape == want.shape and np.abs(got - want).max() < 1e-5
    assert set(after.motions) == set(before.motions)
    for name in set(before.motions) - {NEW_CLIP}:  # untouched clips keep their animation
        assert np.abs(after.motions[name].local_rotations - before.motions[name].local_rotations).max() < 1e-6
    assert after.morph_targets == before.morph_targets
    target_name = _drivable_target(before)
    if target_name:  # the weights come back on the clip's frames
        back = after.motions[NEW_CLIP].morph_weight(target_name)  # (the mesh's other targets at their defaults)
        assert np.abs(back - before.motions[NEW_CLIP].morph_weight(target_name)).max() < 1e-6
    source = parse_file(corpus_file(rel)).json
    copy = parse_file(path).json
    for key in ("meshes", "skins", "materials", "textures", "images", "extensionsUsed"):
        assert copy.get(key) == source.get(key), key
