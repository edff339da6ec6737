"""The glTF plugin on documents built in the tests: containers, accessors, interpolation, folding,
overrides, VRM, compression, and the writer on assets with and without a glTF source."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.errors import InputError, MissingFeatureError, UsageError
from infuse.kinematics import motion_fk
from infuse_gltf import validate as validator
from infuse_gltf.accessors import AccessorReader
from infuse_gltf.container import parse_bytes
from infuse_gltf.sampling import detect_fps

import gltf_builder as gb
from gltf_builder import ARMATURE_ROTATION, GltfBuilder, mini_rig, world_matrices

INFUSE_CLI = Path(sys.executable).with_name("infuse")
Y = np.array([0.0, 1.0, 0.0])


@pytest.fixture
def mini_glb(tmp_path) -> Path:
    b, _ = mini_rig()
    return b.write_glb(tmp_path / "mini.glb")


def test_rest_pose_folds_the_armature(mini_glb):
    asset = infuse.load(mini_glb)
    sk = asset.skeleton
    assert sk.names == ("hips", "spine", "head", "arm.L", "arm.R")
    assert asset.meta["folded_nodes"] == ["Armature"] and asset.warnings == []
    pos = sk.rest_global_positions
    np.testing.assert_allclose(pos[sk.index["hips"]], [0, 1.0, 0], atol=1e-9)
    np.testing.assert_allclose(pos[sk.index["head"]], [0, 1.5, 0], atol=1e-9)
    np.testing.assert_allclose(pos[sk.index["arm.L"]], [0.15, 1.45, 0], atol=1e-9)
    np.testing.assert_allclose(sk.rest_translations[sk.index["spine"]], [0, 0, 0.2], atol=1e-12)  # scale folded
    assert asset.meta["bind_pose"]["matches_rest"]
    assert asset.morph_targets == ["smile", "blink"]


def test_containers_agree(tmp_path, mini_glb):
    b, _ = mini_rig()
    reference = infuse.load(mini_glb)
    for path in (b.write_gltf(tmp_path / "ext.gltf", external=True), b.write_gltf(tmp_path / "embedded.gltf", external=False)):
        asset = infuse.load(path)
        assert asset.meta["container"] == "gltf"
        assert asset.skeleton.names == reference.skeleton.names
        np.testing.assert_allclose(asset.motions["wave"].local_rotations, reference.motions["wave"].local_rotations)


def test_animation_folds_parents_and_interpolates(mini_glb):
    asset = infuse.load(mini_glb)
    motion = asset.motions["wave"]
    assert motion.fps == 30 and motion.num_frames == 31  # two keys only: the default rate
    assert asset.meta["clips"]["wave"]["interpolations"] == ["LINEAR", "STEP"]
    _, pos = motion_fk(motion)
    sk = asset.skeleton
    hips, spine, arm = sk.index["hips"], sk.index["spine"], sk.index["arm.L"]
    # Frame 15 (t = 0.5 s): the Armature has turned 45° about +Y (slerp); the hips key (0, 10, 90) cm in
    # the Z-up armature is (0, 0.9, -0.1) m in glTF's Y-up frame.
    turn = quat.from_axis_angle(Y, np.pi / 4)
    np.testing.assert_allclose(pos[15, hips], quat.rotate(turn, [0, 0.9, -0.1]), atol=1e-9)
    # The spine bent half way (0.3 rad about the hips' x axis, which the Armature maps to world x, turned).
    expected_spine = quat.multiply(quat.multiply(turn, ARMATURE_ROTATION), quat.from_axis_angle(np.array([1.0, 0, 0]), 0.3))
    assert quat.angle_between(motion_fk(motion)[0][15, spine], expected_spine) < 1e-9
    # STEP holds the first key until t = 0.5 s exactly.
    rot = motion.local_rotations[:, arm]
    assert quat.angle_between(rot[14], quat.IDENTITY) < 1e-12 and quat.angle_between(rot[15], quat.IDENTITY) > 0.5
    # Last frame: every channel at its last key, against a matrix chain over the file's nodes.
    b, n = mini_rig()
    turned = b.doc["nodes"]
    turned[n["Armature"]]["rotation"] = list(quat.multiply(quat.from_axis_angle(Y, np.pi / 2), ARMATURE_ROTATION))
    turned[n["hips"]]["translation"] = [0, 20, 100]
    turned[n["spine"]]["rotation"] = list(quat.from_axis_angle(np.array([1.0, 0, 0]), 0.6))
    world = world_matrices(b.doc)
    np.testing.assert_allclose(pos[-1], world[[n[k] for k in sk.names], :3, 3], atol=1e-9)
    wave = asset.motions["wave"]
    np.testing.assert_allclose(wave.morph_weight("smile")[[0, 15, 30]], [0, 0.5, 1.0], atol=1e-7)
    np.testing.assert_allclose(wave.morph_weight("blink")[[0, 30]], [0, 0.5], atol=1e-7)


def test_cubic_spline_follows_the_hermite_form(tmp_path):
    b = GltfBuilder()
    root = b.node("root")
    # keys (in-tangent, value, out-tangent) at t = 0 and 2 s
    keys = np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 2, 0], [1, 1, 0], [0, 0, 0]], dtype=np.float64)
    b.animation("cubic", [(root, "translation", [0.0, 2.0], keys, "CUBICSPLINE")])
    motion = infuse.load(b.write_glb(tmp_path / "c.glb")).motions["cubic"]
    t = np.arange(motion.num_frames) / motion.fps
    u, dt = t / 2.0, 2.0
    v0, b0, a1, v1 = keys[1], keys[2], keys[3], keys[4]
    expected = ((2 * u**3 - 3 * u**2 + 1)[:, None] * v0 + dt * (u**3 - 2 * u**2 + u)[:, None] * b0
                + (-2 * u**3 + 3 * u**2)[:, None] * v1 + dt * (u**3 - u**2)[:, None] * a1)
    np.testing.assert_allclose(motion.root_translations, expected, atol=1e-9)


def test_keyframe_rate_detection():
    assert detect_fps([np.arange(49, dtype=np.float32) / np.float32(24.0)]) == (24.0, "keyframes")
    assert detect_fps([np.array([0.0, 0.3, 0.71, 1.4])]) == (30.0, "default")  # irregular keys
    assert detect_fps([np.array([0.0, 0.5, 1.0, 1.5])]) == (30.0, "default")  # 2 fps is a sparse pose list
    rate, how = detect_fps([np.arange(100) / 30.00003, np.arange(0, 100, 7) / 30.00003])
    assert how == "keyframes" and abs(rate - 30.00003) < 1e-6  # an off-integer source keeps its rate


def test_quantized_sparse_and_strided_accessors(tmp_path):
    b = GltfBuilder()
    root = b.node("root")
    joint = b.node("joint", root, translation=[0, 1, 0])
    angles = np.linspace(0, 1.0, 5)
    rots = quat.from_axis_angle(np.tile([0.0, 0.0, 1.0], (5, 1)), angles)
    b.animation("q", [(joint, "rotation", np.arange(5) / 4.0, rots, "LINEAR", 5122, True)])  # normalized shorts
    # Sparse: zeros everywhere but element 3, stored as (indices, values).
    idx_view = b.view(np.array([3], dtype="<u2").tobytes() + b"\0\0")
    val_view = b.view(np.array([1.5, -2.0, 0.25], dtype="<f4").tobytes())
    b.doc["accessors"].append({"componentType": 5126, "count": 5, "type": "VEC3",
                               "sparse": {"count": 1, "indices": {"bufferView": idx_view, "componentType": 5123},
                                          "values": {"bufferView": val_view}}})
    # Interleaved: VEC3 floats every 16 bytes.
    inter = np.zeros((4, 4), dtype="<f4")
    inter[:, :3] = np.arange(12).reshape(4, 3)
    strided_view = b.view(inter.tobytes(), stride=16)
    b.doc["accessors"].append({"bufferView": strided_view, "componentType": 5126, "count": 4, "type": "VEC3"})
    path = b.write_glb(tmp_path / "acc.glb")
    asset = infuse.load(path)
    assert asset.skeleton.names == ("joint",) and asset.meta["folded_nodes"] == ["root"]  # no skin: the animated node
    got = asset.motions["q"].local_rotations[:, 0]
    frames = np.arange(len(got)) / 30.0
    want = quat.from_axis_angle(np.tile([0.0, 0.0, 1.0], (len(got), 1)), np.clip(frames, 0, 1))
    assert np.max(quat.angle_between(got, want)) < 1e-4  # 16-bit quantization
    doc = parse_bytes(path.read_bytes(), path)
    reader = AccessorReader(doc)
    sparse = reader.read(len(doc.json["accessors"]) - 2)
    np.testing.assert_array_equal(sparse, [[0, 0, 0]] * 3 + [[1.5, -2.0, 0.25], [0, 0, 0]])
    np.testing.assert_array_equal(reader.read(len(doc.json["accessors"]) - 1), np.arange(12).reshape(4, 3))


def test_matrix_parent_equals_trs_parent(tmp_path, mini_glb):
    b, n = mini_rig()
    armature = b.doc["nodes"][n["Armature"]]
    m = np.eye(4)
    m[:3, :3] = quat.to_matrix(ARMATURE_ROTATION) * 0.01
    del armature["rotation"], armature["scale"]
    armature["matrix"] = list(m.T.reshape(-1))
    del b.doc["animations"]
    asset = infuse.load(b.write_glb(tmp_path / "matrix.glb"))
    reference = infuse.load(mini_glb).skeleton
    np.testing.assert_allclose(asset.skeleton.rest_global_positions, reference.rest_global_positions, atol=1e-12)


def test_non_uniform_scale_is_approximated_with_a_warning(tmp_path):
    b, n = mini_rig(animated=False)
    b.doc["nodes"][n["Armature"]]["scale"] = [0.01, 0.01, 0.02]
    asset = infuse.load(b.write_glb(tmp_path / "uneven.glb"))
    assert any("non-uniform scale" in w and "Armature" in w for w in asset.warnings)
    assert asset.skeleton.rest_translations[1, 2] == pytest.approx(20 * (0.04 / 3))


def test_joint_selection_unions_skins_fills_gaps_and_keeps_bone_tips(tmp_path):
    b = GltfBuilder()
    top = b.node("top")
    a = b.node("a", top)
    gap = b.node("gap", a, translation=[0, 1, 0])
    c = b.node("c", gap, translation=[0, 1, 0])
    b.node("c_end", c, translation=[0, 0.5, 0])  # an empty bone tip: a joint
    b.node("prop", c, mesh=0)
    other = b.node("ik_target", top, translation=[1, 0, 0])
    pos = b.accessor(np.eye(3), minmax=True)
    b.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}}]}]
    b.doc["skins"] = [{"joints": [a, c]}, {"joints": [other]}]
    asset = infuse.load(b.write_glb(tmp_path / "sel.glb"))
    assert asset.skeleton.names == ("a", "gap", "c", "c_end", "ik_target")  # largest tree first
    assert list(asset.skeleton.parents) == [-1, 0, 1, 2, -1]
    assert asset.meta["folded_nodes"] == ["top"]


def test_unit_and_axis_overrides_round_trip(tmp_path, mini_glb):
    asset = infuse.load(mini_glb, units="cm", up_axis="Z")
    assert asset.units_detected_by == "override" and asset.source_units == "cm" and asset.source_up_axis == "Z"
    plain = infuse.load(mini_glb)
    rz = infuse.conventions.UP_AXIS_ROTATIONS["Z"]
    np.testing.assert_allclose(asset.skeleton.rest_global_positions,
                               quat.rotate(rz, plain.skeleton.rest_global_positions) * 0.01, atol=1e-12)
    out = tmp_path / "override.glb"
    infuse.save(asset, out)
    again = infuse.load(out, units="cm", up_axis="Z")
    np.testing.assert_allclose(motion_fk(again.motions["wave"])[1], motion_fk(asset.motions["wave"])[1], atol=1e-8)


def _vrm0(tmp_path) -> Path:
    """A VRM 0.x humanoid facing -Z (its left arm at -X), as UniVRM exports them."""
    b = GltfBuilder()
    hips = b.node("Hips", translation=[0, 1, 0])
    spine = b.node("Spine", hips, translation=[0, 0.3, 0])
    left = b.node("LeftArm", spine, translation=[-0.2, 0.2, 0])
    right = b.node("RightArm", spine, translation=[0.2, 0.2, 0])
    pos = b.accessor(np.eye(3), minmax=True)
    t1 = b.accessor(np.eye(3) * 0.01, minmax=True)
    b.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}, "targets": [{"POSITION": t1}]}]}]
    b.node("Face", hips, mesh=0)
    bones = [{"bone": "hips", "node": hips}, {"bone": "spine", "node": spine},
             {"bone": "leftUpperArm", "node": left}, {"bone": "rightUpperArm", "node": right}]
    groups = [{"name": "A", "presetName": "a", "binds": [{"mesh": 0, "index": 0, "weight": 100}]},
              {"name": "Joy", "presetName": "joy", "binds": []}]
    b.doc["extensions"] = {"VRM": {"specVersion": "0.0", "humanoid": {"humanBones": bones},
                                   "blendShapeMaster": {"blendShapeGroups": groups}}}
    b.doc["extensionsUsed"] = ["VRM"]
    return b.write_glb(tmp_path / "old.vrm")


def test_vrm0_faces_minus_z_and_is_turned(tmp_path):
    path = _vrm0(tmp_path)
    asset = infuse.load(path)
    assert asset.format == "vrm" and asset.meta["vrm_version"] == "0.x"
    assert asset.meta["facing"] == "-Z" and asset.facing_turned and asset.meta["facing_detected_by"] == "humanoid arms"
    sk = asset.skeleton
    assert sk.rest_global_positions[sk.index["LeftArm"], 0] == pytest.approx(0.2)  # left at +X in the core
    assert asset.humanoid == {"hips": "Hips", "spine": "Spine", "leftUpperArm": "LeftArm", "rightUpperArm": "RightArm"}
    assert asset.morph_targets == ["mesh0.0", "a"]  # "joy" binds no morph target: nothing to animate
    assert asset.meta["vrm_expressions"] == ["a", "joy"]
    kept = infuse.load(path, facing="+Z")
    assert kept.skeleton.rest_global_positions[sk.index["LeftArm"], 0] == pytest.approx(-0.2)
    # A new clip written back lands in the file's -Z frame and reads back the same.
    turn = quat.from_axis_angle(np.tile(Y, (20, 1)), np.linspace(0, 1, 20))
    rots = np.broadcast_to(sk.rest_rotations, (20, sk.num_joints, 4)).copy()
    rots[:, 0] = quat.multiply(turn, sk.rest_rotations[0])
    asset.motions["turn"] = infuse.Motion(sk, 30, rots, np.tile(sk.rest_translations[0], (20, 1)), name="turn",
                                          morph_names=["a"], morph_weights=np.linspace(0, 1, 20)[:, None])
    out = tmp_path / "out.vrm"
    infuse.save(asset, out)
    back = infuse.load(out)
    np.testing.assert_allclose(motion_fk(back.motions["turn"])[1], motion_fk(asset.motions["turn"])[1], atol=1e-6)
    np.testing.assert_allclose(back.motions["turn"].morph_weight("mesh0.0"), np.linspace(0, 1, 20), atol=1e-6)
    assert json.loads(json.dumps(parse_bytes(out.read_bytes()).json["nodes"])) == parse_bytes(path.read_bytes()).json["nodes"]
    with pytest.raises(UsageError, match="without morph target binds"):
        asset.motions["turn"] = asset.motions["turn"].replace(morph_names=["joy"])
        infuse.save(asset, tmp_path / "bad.vrm")


def test_untouched_clips_keep_their_animation_and_dropped_clips_go(tmp_path, mini_glb):
    asset = infuse.load(mini_glb)
    out = tmp_path / "copy.gltf"
    infuse.save(asset, out)
    source = parse_bytes(mini_glb.read_bytes()).json
    copy = json.loads(out.read_text())
    assert copy["animations"] == source["animations"]
    assert copy["buffers"][0]["uri"].startswith("data:")
    wave = asset.motions.pop("wave")
    infuse.save(asset, out)
    assert "animations" not in json.loads(out.read_text())
    # A clip of morph weights alone is an animation of weights channels only.
    talk = infuse.Motion.rest_pose(asset.skeleton, frames=2, name="talk").replace(
        morph_names=["smile"], morph_weights=[[0.0], [1.0]], animated_joints=np.zeros(asset.skeleton.num_joints, bool))
    asset.motions["talk"] = talk
    infuse.save(asset, out)
    channels = json.loads(out.read_text())["animations"][0]["channels"]
    assert [c["target"]["path"] for c in channels] == ["weights"]
    back = infuse.load(out).motions["talk"]
    assert not back.animated_mask.any() and np.allclose(back.morph_weight("smile"), [0.0, 1.0])
    with pytest.raises(UsageError, match="does not have: frown"):
        asset.motions["talk"] = talk.replace(morph_names=["frown"])
        infuse.save(asset, out)
    assert wave.morph_names


def _meshopt_clip(tmp_path, filters: dict | None = None) -> tuple[Path, np.ndarray, np.ndarray]:
    """A rig whose clip (times, QUATERNION-filtered rotations, EXPONENTIAL-filtered translations) sits in
    meshopt-compressed views of a fallback buffer; returns the file and the rotations and translations."""
    b = GltfBuilder()
    joint = b.node("joint", translation=[0, 1, 0])
    keys = 300  # more than one 256-element block
    times = np.arange(keys, dtype=np.float32) / np.float32(30.0)
    rng = np.random.default_rng(5)
    rots = quat.normalize(quat.from_rotvec(np.cumsum(rng.normal(scale=0.05, size=(keys, 3)), axis=0)))
    trans = np.cumsum(rng.normal(scale=0.01, size=(keys, 3)), axis=0) + [0, 1, 0]
    b.doc["buffers"] = [{"byteLength": 0, "extensions": {"EXT_meshopt_compression": {"fallback": True}}}]
    fallback_length = 0
    streams = [(times.view(np.uint8).reshape(keys, 4), "NONE", 5126, "SCALAR", False),
               (gb.quaternion_filter(rots), "QUATERNION", 5122, "VEC4", True),
               (gb.exponential_filter(trans.astype(np.float32)), "EXPONENTIAL", 5126, "VEC3", False)]
    accessors = []
    for elements, flt, ctype, kind, normalized in streams:
        flt = (filters or {}).get(flt, flt)
        encoded = gb.meshopt_encode(elements)
        b.bin += b"\0" * ((-len(b.bin)) % 4)
        ext = {"buffer": 0, "byteOffset": len(b.bin), "byteLength": len(encoded), "byteStride": elements.shape[1],
               "count": keys, "mode": "ATTRIBUTES", "filter": flt}
        b.bin += encoded
        view = {"buffer": 1, "byteOffset": fallback_length, "byteLength": elements.size, "extensions": {"EXT_meshopt_compression": ext}}
        fallback_length += elements.size
        b.doc["bufferViews"].append(view)
        acc = {"bufferView": len(b.doc["bufferViews"]) - 1, "componentType": ctype, "count": keys, "type": kind}
        if normalized:
            acc["normalized"] = True
        if kind == "SCALAR":
            acc["min"], acc["max"] = [0.0], [float(times[-1])]
        b.doc["accessors"].append(acc)
        accessors.append(len(b.doc["accessors"]) - 1)
    b.doc["buffers"][0]["byteLength"] = fallback_length
    b.doc["animations"] = [{"name": "packed", "samplers": [{"input": accessors[0], "output": accessors[1]},
                                                           {"input": accessors[0], "output": accessors[2]}],
                            "channels": [{"sampler": 0, "target": {"node": joint, "path": "rotation"}},
                                         {"sampler": 1, "target": {"node": joint, "path": "translation"}}]}]
    b.doc["extensionsUsed"] = b.doc["extensionsRequired"] = ["EXT_meshopt_compression"]
    return b.write_glb(tmp_path / "packed.glb"), rots, trans


def test_meshopt_compressed_clip_is_decoded(tmp_path):
    path, rots, trans = _meshopt_clip(tmp_path)
    asset = infuse.load(path)
    motion = asset.motions["packed"]
    assert motion.fps == 30 and motion.num_frames == len(rots)
    assert np.max(quat.angle_between(motion.local_rotations[:, 0], rots)) < 1e-3  # 12-bit quaternion components
    np.testing.assert_allclose(motion.root_translations, trans, atol=2e-5)  # 2^-15 m steps
    assert asset.meta["compression"] == ["EXT_meshopt_compression"]


def test_undecodable_or_damaged_compression_is_refused_clearly(tmp_path):
    path, _, _ = _meshopt_clip(tmp_path, filters={"QUATERNION": "OCTAHEDRAL"})
    with pytest.raises(MissingFeatureError, match="EXT_meshopt_compression"):
        infuse.load(path)
    run = subprocess.run([str(INFUSE_CLI), "info", str(path)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 3 and "EXT_meshopt_compression" in run.stderr and "Traceback" not in run.stderr
    b, _ = mini_rig()
    anim_view = b.doc["accessors"][b.doc["animations"][0]["samplers"][0]["output"]]["bufferView"]
    b.doc["bufferViews"][anim_view]["extensions"] = {"EXT_meshopt_compression": {
        "buffer": 0, "byteOffset": 0, "byteLength": 40, "byteStride": 16, "count": 2, "mode": "ATTRIBUTES"}}
    with pytest.raises(InputError, match="EXT_meshopt_compression"):
        infuse.load(b.write_glb(tmp_path / "garbled.glb"))


def _bvh_like_skeleton() -> infuse.Skeleton:
    names = ["root", "spine", "head", "l_arm", "r_arm", "prop"]
    parents = [-1, 0, 1, 1, 1, -1]
    trans = [[0, 1, 0], [0, 0.2, 0], [0, 0.3, 0], [0.2, 0.25, 0], [-0.2, 0.25, 0], [1, 0, 0]]
    rots = quat.from_axis_angle(np.tile([0.0, 0.0, 1.0], (6, 1)), np.array([0, 0.1, 0, 0.2, -0.2, 0]))
    return infuse.Skeleton(names, parents, trans, rots, [2, 3], [[0, 0.1, 0], [0.1, 0, 0]])


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_skeleton_only_asset_is_written_as_a_valid_gltf(tmp_path, suffix):
    sk = _bvh_like_skeleton()
    frames = 40
    rng = np.random.default_rng(3)
    rots = quat.normalize(sk.rest_rotations + 0.1 * rng.normal(size=(frames, sk.num_joints, 4)))
    jt = np.broadcast_to(sk.rest_translations, (frames, sk.num_joints, 3)).copy()
    jt[:, 5] += np.linspace(0, 1, frames)[:, None]  # the second root moves
    motion = infuse.Motion(sk, 60.0, rots, jt[:, 0] + [0, 0, 0.01], jt, name="jitter")
    asset = infuse.Asset(path=None, format="bvh", skeleton=sk, motions={"jitter": motion})
    out = infuse.save(asset, tmp_path / f"skeleton{suffix}")
    report = validator.validate(out)
    assert report["issues"]["numErrors"] == 0, validator.errors(report)
    back = infuse.load(out)
    assert back.skeleton.names == sk.names and list(back.skeleton.parents) == list(sk.parents)
    np.testing.assert_allclose(back.skeleton.end_site_offsets, sk.end_site_offsets, atol=1e-7)
    np.testing.assert_allclose(back.skeleton.rest_global_positions, sk.rest_global_positions, atol=1e-7)
    got = back.motions["jitter"]
    assert got.fps == 60 and got.num_frames == frames
    np.testing.assert_allclose(motion_fk(got)[1], motion_fk(motion)[1], atol=1e-6)


def test_vrma_output_carries_the_humanoid_map(tmp_path):
    sk = _bvh_like_skeleton()
    motion = infuse.Motion.rest_pose(sk, frames=10, name="still")
    asset = infuse.Asset(path=None, format="bvh", skeleton=sk, motions={"still": motion},
                         humanoid={"hips": "root", "spine": "spine", "head": "head"})
    out = infuse.save(asset, tmp_path / "clip.vrma")
    assert validator.validate(out)["issues"]["numErrors"] == 0
    back = infuse.load(out)
    assert back.format == "vrma" and back.humanoid == {"hips": "root", "spine": "spine", "head": "head"}
    asset.humanoid = {}
    with pytest.raises(UsageError, match="humanoid"):
        infuse.save(asset, tmp_path / "nomap.vrma")


def test_bad_option_values_are_usage_errors(mini_glb):
    for options in ({"units": "furlong"}, {"up_axis": "W"}, {"facing": "up"}, {"fps": -1}):
        with pytest.raises((UsageError, InputError)):
            infuse.load(mini_glb, **options)


def _png_1x1() -> bytes:
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\0\xff\x00\x00")) + chunk(b"IEND", b"")


def test_gltf_with_external_files_is_written_standalone(tmp_path):
    b, n = mini_rig()
    (tmp_path / "skin.png").write_bytes(_png_1x1())
    b.doc["images"] = [{"uri": "skin.png"}]
    b.doc["textures"] = [{"source": 0}]
    b.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    b.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = b.accessor(np.zeros((3, 2)))
    source = b.write_gltf(tmp_path / "model.gltf", external=True)
    asset = infuse.load(source)
    out_dir = tmp_path / "elsewhere"
    written = [infuse.save(asset, out_dir / "copy.glb"), infuse.save(asset, out_dir / "copy.gltf")]
    for path, report in zip(written, validator.validate_files(written)):
        assert report["issues"]["numErrors"] == 0, validator.errors(report)
        doc = parse_bytes(path.read_bytes(), path).json
        assert doc["images"][0]["uri"].startswith("data:image/png;base64,")
        back = infuse.load(path)
        np.testing.assert_allclose(back.motions["wave"].local_rotations, asset.motions["wave"].local_rotations, atol=1e-7)


def test_validate_command(tmp_path, mini_glb):
    b, _ = mini_rig()
    time_accessor = b.doc["accessors"][b.doc["animations"][0]["samplers"][0]["input"]]
    del time_accessor["min"], time_accessor["max"]  # the spec requires bounds on animation inputs
    bad = b.write_glb(tmp_path / "unbounded.glb")
    run = subprocess.run([str(INFUSE_CLI), "validate-gltf", str(mini_glb), str(bad)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0].startswith(f"{mini_glb}: 0 errors") and f"{bad}: " in run.stdout and "error ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS" in run.stdout
    missing = subprocess.run([str(INFUSE_CLI), "validate-gltf", str(tmp_path / "nothing.glb")], capture_output=True, text=True, timeout=120)
    assert missing.returncode == 2 and "file not found" in missing.stderr


def test_vrm_character_clip_exported_as_vrma(tmp_path):
    asset = infuse.load(_vrm0(tmp_path))
    sk = asset.skeleton
    frames = 30
    rots = np.broadcast_to(sk.rest_rotations, (frames, sk.num_joints, 4)).copy()
    rots[:, 1] = quat.multiply(sk.rest_rotations[1], quat.from_axis_angle(np.tile(Y, (frames, 1)), np.linspace(0, 0.8, frames)))
    weights = {"aa": np.linspace(0, 1, frames), "a": np.linspace(1, 0, frames)}
    asset.motions = {"nod": infuse.Motion(sk, 30, rots, np.tile(sk.rest_translations[0], (frames, 1)), name="nod",
                                          morph_names=list(weights), morph_weights=np.stack(list(weights.values()), axis=1))}
    out = infuse.save(asset, tmp_path / "nod.vrma")
    report = validator.validate(out)
    assert report["issues"]["numErrors"] == 0, validator.errors(report)
    back = infuse.load(out)
    assert back.format == "vrma" and back.humanoid == asset.humanoid
    assert back.skeleton.names == sk.names and back.morph_targets == ["aa", "a"]
    ext = parse_bytes(out.read_bytes()).json["extensions"]["VRMC_vrm_animation"]
    assert set(ext["expressions"]["preset"]) == {"aa"} and set(ext["expressions"]["custom"]) == {"a"}
    np.testing.assert_allclose(motion_fk(back.motions["nod"])[1], motion_fk(asset.motions["nod"])[1], atol=1e-6)
    for name, w in weights.items():
        np.testing.assert_allclose(back.motions["nod"].morph_weight(name), w, atol=1e-6)
    with pytest.raises(UsageError, match=".vrm output needs a VRM character"):
        infuse.save(infuse.load(out), tmp_path / "not_a_character.vrm")
