"""The glTF writer on assets that are not glTF copies but carry skinned meshes (COLLADA and FBX
characters, and glTF characters handed over as plain assets): the meshes are written (positions,
triangles, normals, skin weights, bones, inverse binds, colours, morph targets), pass the Khronos
validator and read back the same, posed or at rest, and morph-weight tracks drive them."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.kinematics import forward_kinematics, motion_fk
from infuse.mesh import SkinnedMesh, rigid_matrices
from infuse_gltf import validate as validator
from infuse_gltf.accessors import AccessorReader
from infuse_gltf.container import parse_file
from infuse_gltf.graph import global_matrices, node_graph, node_rest_trs, trs_matrices
from infuse_gltf.mesh_writer import color_factors, influence_sets

from corpus_data import corpus_file

SOURCES = {"xbot": "runxaway-models/Xbot.glb", "brunette": "talkinghead/avatars/brunette-t.glb",
           "rocketbox": "ubiq-rocketbox/Ubiq_Robot_Rocketbox.fbx", "mannequin": "ue4-mannequin/SK_Mannequin.FBX",
           "doctor": "smartbody/mesh/doctor/Doctor.dae"}
SUFFIXES = (".glb", ".gltf")
POSE_CLIP = "pose"


def _posing_clip(sk: infuse.Skeleton, frames: int = 6) -> infuse.Motion:
    """A short clip bending every joint a little differently and moving the root."""
    rng = np.random.default_rng(11)
    axes = rng.normal(size=(sk.num_joints, 3))
    angles = np.linspace(0.0, 1.0, frames)[:, None] * rng.uniform(-0.6, 0.6, size=sk.num_joints)
    turn = quat.from_axis_angle(np.broadcast_to(axes / np.linalg.norm(axes, axis=1, keepdims=True), angles.shape + (3,)), angles)
    rot = quat.multiply(sk.rest_rotations, turn)
    root = sk.rest_translations[0] + np.linspace(0.0, 0.3, frames)[:, None] * np.array([0.2, 0.0, 1.0])
    return infuse.Motion(sk, 30.0, rot, root, name=POSE_CLIP)


def _plain_asset(source: infuse.Asset, motions: dict) -> infuse.Asset:
    """An asset without a glTF payload, with the source's skeleton and meshes."""
    return infuse.Asset(path=None, format="test", skeleton=source.skeleton, motions=motions,
                        morph_targets=list(source.morph_targets), mesh_loader=lambda: source.meshes)


def _morph_clip(skeleton: infuse.Skeleton, name: str, weights: dict) -> infuse.Motion:
    """A clip of morph weights alone ({target: (F,)} at 30 fps): no joint animated."""
    frames = len(next(iter(weights.values())))
    return infuse.Motion.rest_pose(skeleton, frames, name=name).replace(
        morph_names=list(weights), morph_weights=np.stack(list(weights.values()), axis=1),
        animated_joints=np.zeros(skeleton.num_joints, dtype=bool))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """key -> (plain asset, {suffix: (written path, validator report, asset read back)})."""
    if not validator.available():
        pytest.fail("the Khronos glTF validator is missing: run `make setup`")
    out_dir = tmp_path_factory.mktemp("gltf_mesh_out")
    plain, paths = {}, []
    for key, rel in SOURCES.items():
        source = infuse.load(corpus_file(rel))
        plain[key] = _plain_asset(source, {POSE_CLIP: _posing_clip(source.skeleton)})
        for suffix in SUFFIXES:
            paths.append((key, suffix, infuse.save(plain[key], out_dir / f"{key}{suffix}")))
    reports = validator.validate_files([p for _, _, p in paths])
    out = {key: (asset, {}) for key, asset in plain.items()}
    for (key, suffix, path), report in zip(paths, reports):
        out[key][1][suffix] = (path, report, infuse.load(path))
    return out


CASES = [(k, s) for k in SOURCES for s in SUFFIXES]


def _weights_by_joint(mesh: SkinnedMesh, names: tuple[str, ...], order: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Every vertex's non-zero weight per joint, as sorted keys ``vertex * J + column`` (columns: joint
    names in ``order``) and their summed weights."""
    column = {n: i for i, n in enumerate(order)}
    bone_columns = np.array([column[names[j]] for j in mesh.bind_joints])
    rows = np.repeat(np.arange(mesh.num_vertices), mesh.joints.shape[1])
    keys = rows * len(order) + bone_columns[mesh.joints].reshape(-1)
    weights = mesh.weights.reshape(-1).astype(np.float64)
    keys, weights = keys[weights > 0], weights[weights > 0]
    unique, at = np.unique(keys, return_inverse=True)
    return unique, np.bincount(at, weights=weights)


def _assert_same_weights(a: SkinnedMesh, a_names, b: SkinnedMesh, b_names) -> None:
    order = list(a_names)
    keys_a, weights_a = _weights_by_joint(a, a_names, order)
    keys_b, weights_b = _weights_by_joint(b, b_names, order)
    np.testing.assert_array_equal(keys_b, keys_a)
    np.testing.assert_allclose(weights_b, weights_a, atol=1e-6)


@pytest.mark.parametrize("key,suffix", CASES)
def test_written_meshes_pass_the_validator(written, key, suffix):
    _, report, back = written[key][1][suffix]
    issues = report["issues"]
    assert issues["numErrors"] == 0, validator.errors(report)
    assert issues["numWarnings"] == 0, [m for m in issues["messages"] if m["severity"] == 1]
    assert back.warnings == []


@pytest.mark.parametrize("key,suffix", CASES)
def test_meshes_read_back_the_same(written, key, suffix):
    before, outputs = written[key]
    after = outputs[suffix][2]
    names_before, names_after = before.skeleton.names, after.skeleton.names
    assert sorted(names_after) == sorted(names_before)
    assert [m.name for m in after.meshes] == [m.name for m in before.meshes]
    for a, b in zip(before.meshes, after.meshes):
        # a reader keeps the vertices as the skin's root bone binds them: float32 bind matrices move them by µm
        np.testing.assert_allclose(b.positions, a.positions, atol=1e-5)
        np.testing.assert_array_equal(b.triangles, a.triangles)
        np.testing.assert_allclose(b.normals, a.normals, atol=1e-5)
        assert [names_after[j] for j in b.bind_joints] == [names_before[j] for j in a.bind_joints]
        np.testing.assert_allclose(b.inverse_bind, a.inverse_bind, atol=1e-5 * np.abs(a.inverse_bind).max())
        _assert_same_weights(a, names_before, b, names_after)
        assert (b.colors is None) == (a.colors is None)
        np.testing.assert_allclose(b.vertex_colors(), a.vertex_colors(), atol=1e-6)
        np.testing.assert_allclose(b.base_color, a.base_color, atol=1e-7)
        assert b.double_sided == a.double_sided
        assert b.morph_names == a.morph_names
        if a.morph_names:
            np.testing.assert_allclose(b.morph_positions, a.morph_positions, atol=1e-7)
    assert after.morph_targets == list(dict.fromkeys(n for m in before.meshes for n in m.morph_names))


@pytest.mark.parametrize("key", SOURCES)
def test_posed_meshes_skin_the_same(written, key):
    """The clip, skinned on the meshes read back, puts every vertex where the source meshes go."""
    before, outputs = written[key]
    after = outputs[".glb"][2]
    order = [after.skeleton.index[n] for n in before.skeleton.names]
    rot_a, pos_a = motion_fk(before.motions[POSE_CLIP])
    rot_b, pos_b = motion_fk(after.motions[POSE_CLIP])
    rot_b, pos_b = rot_b[:, order], pos_b[:, order]
    back_to_before = np.argsort(order)  # read-back joint index -> source joint index
    for a, b in zip(before.meshes, after.meshes):
        moved = SkinnedMesh(b.name, b.positions, b.normals, b.triangles, b.joints, b.weights,
                            back_to_before[b.bind_joints], b.inverse_bind)
        want, _ = a.skin(rot_a, pos_a)
        got, _ = moved.skin(rot_b, pos_b)
        assert np.abs(want - pos_a[:, :1]).max() > 0.05  # the clip does move the mesh
        np.testing.assert_allclose(got, want, atol=2e-5)


def test_joint_nodes_times_inverse_binds_keep_the_bind_pose(written):
    """In the written file itself, each joint node's world matrix times its inverse bind matrix is the
    core's ``G @ inverse_bind``; for Xbot, whose rest pose is its bind pose, that is the identity."""
    before, outputs = written["xbot"]
    path = outputs[".gltf"][0]
    doc = parse_file(path)
    nodes = doc.json["nodes"]
    world = global_matrices(node_graph(nodes, path), trs_matrices(*node_rest_trs(nodes, path)))
    accessors = AccessorReader(doc)
    sk = before.skeleton
    g = rigid_matrices(*forward_kinematics(sk, sk.rest_rotations[None], sk.rest_translations[:1]))[0]
    mesh_nodes = [n for n in nodes if "mesh" in n]
    assert [n["name"] for n in mesh_nodes] == [m.name for m in before.meshes]
    for node, mesh in zip(mesh_nodes, before.meshes):
        assert not {"translation", "rotation", "scale", "matrix"} & set(node)
        skin = doc.json["skins"][node["skin"]]
        ibm = np.swapaxes(accessors.read(skin["inverseBindMatrices"], "ibm"), 1, 2)
        skinning = world[skin["joints"]] @ ibm
        np.testing.assert_allclose(skinning, g[mesh.bind_joints] @ mesh.inverse_bind, atol=1e-5)
        used = np.unique(mesh.joints[mesh.weights > 0])
        np.testing.assert_allclose(skinning[used], np.broadcast_to(np.eye(4), (len(used), 4, 4)), atol=1e-5)
        primitive = doc.json["meshes"][node["mesh"]]["primitives"][0]
        position = doc.json["accessors"][primitive["attributes"]["POSITION"]]
        np.testing.assert_allclose(position["min"], mesh.positions.min(axis=0))
        np.testing.assert_allclose(position["max"], mesh.positions.max(axis=0))


def test_a_clips_morph_weights_drive_the_written_meshes(tmp_path):
    source = infuse.load(corpus_file(SOURCES["brunette"]))
    times = np.arange(16) / 30.0
    driven = {"viseme_aa": np.sin(times * 5) ** 2, "eyeBlinkLeft": np.linspace(0.0, 1.0, len(times))}
    asset = _plain_asset(source, {"talk": _morph_clip(source.skeleton, "talk", driven)})
    out = infuse.save(asset, tmp_path / "talk.glb")
    report = validator.validate(out)
    assert report["issues"]["numErrors"] == 0, validator.errors(report)
    back = infuse.load(out)
    clip = back.motions["talk"]
    np.testing.assert_allclose(clip.frame_times, times, atol=1e-6)
    for name, weights in driven.items():
        np.testing.assert_allclose(clip.morph_weight(name), weights, atol=1e-6)
    doc = parse_file(out).json
    assert {c["target"]["path"] for c in doc["animations"][0]["channels"]} == {"weights"}  # no joint moves
    animated = {c["target"]["node"] for c in doc["animations"][0]["channels"] if c["target"]["path"] == "weights"}
    target_names = [(m.get("extras") or {}).get("targetNames", []) for m in doc["meshes"]]
    with_targets = {i for i, n in enumerate(doc["nodes"]) if "mesh" in n and "viseme_aa" in target_names[n["mesh"]]}
    assert with_targets and animated == with_targets

    asset.motions["talk"] = _morph_clip(source.skeleton, "talk", {"noSuchShape": times})
    with pytest.raises(UsageError, match="noSuchShape"):
        infuse.save(asset, tmp_path / "bad.glb")


def test_tracks_need_morph_targets(tmp_path):
    source = infuse.load(corpus_file(SOURCES["xbot"]))
    talk = _morph_clip(source.skeleton, "talk", {"smile": np.zeros(3)})
    with pytest.raises(UsageError, match="morph targets"):
        infuse.save(_plain_asset(source, {"talk": talk}), tmp_path / "x.glb")
    assert not (tmp_path / "x.glb").exists()


# -- synthetic: what the corpus meshes do not exercise -----------------------------------------------
def _chain(joints: int) -> infuse.Skeleton:
    rng = np.random.default_rng(5)
    rest = quat.from_axis_angle(np.tile([0.0, 0.0, 1.0], (joints, 1)), rng.uniform(-0.05, 0.05, joints))
    trans = np.tile([0.0, 0.01, 0.0], (joints, 1))
    return infuse.Skeleton([f"bone{i}" for i in range(joints)], np.arange(joints) - 1, trans, rest)


def _big_mesh(sk: infuse.Skeleton) -> SkinnedMesh:
    """A ribbon of 2 x 33000 vertices along a 300-joint chain: 16-bit bones, 32-bit indices, 6 influences
    with repeats, colours brighter than the base colour, a zero normal, a bind pose off the rest pose."""
    rows = 33000
    v = 2 * rows
    along = np.repeat(np.linspace(0.0, 2.99, rows), 2)
    positions = np.stack([np.tile([-0.05, 0.05], rows), along, np.zeros(v)], axis=1)
    a = np.arange(rows - 1) * 2
    triangles = np.concatenate([np.stack([a, a + 1, a + 2], 1), np.stack([a + 1, a + 3, a + 2], 1)])
    normals = np.tile([0.0, 0.0, 1.0], (v, 1))
    normals[7] = 0.0
    nearest = np.minimum((along * 100).astype(int), sk.num_joints - 1)
    joints = np.stack([nearest, np.maximum(nearest - 1, 0), np.minimum(nearest + 1, sk.num_joints - 1),
                       nearest, np.zeros(v, int), np.maximum(nearest - 2, 0)], axis=1)
    weights = np.tile([0.35, 0.2, 0.2, 0.1, 0.05, 0.1], (v, 1))
    rng = np.random.default_rng(9)
    g = rigid_matrices(sk.rest_global_rotations, sk.rest_global_positions)
    offsets = rigid_matrices(quat.from_rotvec(rng.normal(scale=0.02, size=(sk.num_joints, 3))), np.zeros((sk.num_joints, 3)))
    offsets[0] = np.eye(4)
    inverse_bind = np.linalg.inv(g @ offsets)
    colors = np.column_stack([rng.uniform(0, 1, (v, 3)), np.ones(v)])
    morphs = np.stack([np.tile([0.0, 0.0, 0.01], (v, 1)), rng.normal(scale=0.001, size=(v, 3))])
    return SkinnedMesh("ribbon", positions, normals, triangles, joints, weights, np.arange(sk.num_joints), inverse_bind,
                       base_color=[0.5, 0.5, 0.5, 1.0], colors=colors, double_sided=True,
                       morph_names=("bulge", "noise"), morph_positions=morphs)


def test_large_synthetic_mesh_round_trips(tmp_path):
    sk = _chain(300)
    mesh = _big_mesh(sk)
    empty = SkinnedMesh("nothing", np.zeros((3, 3)), np.tile([0.0, 1.0, 0.0], (3, 1)), np.zeros((0, 3)),
                        np.zeros((3, 1)), np.ones((3, 1)), [0], np.eye(4)[None])
    asset = infuse.Asset(path=None, format="test", skeleton=sk, motions={POSE_CLIP: _posing_clip(sk, 3)},
                         mesh_loader=lambda: [mesh, empty])
    out = infuse.save(asset, tmp_path / "ribbon.glb")
    report = validator.validate(out)
    assert report["issues"]["numErrors"] == 0 and report["issues"]["numWarnings"] == 0, report["issues"]["messages"][:5]
    doc = parse_file(out).json
    primitive = doc["meshes"][0]["primitives"][0]
    kinds = {k: doc["accessors"][i]["componentType"] for k, i in primitive["attributes"].items()}
    assert kinds == {"POSITION": 5126, "NORMAL": 5126, "JOINTS_0": 5123, "WEIGHTS_0": 5126, "JOINTS_1": 5123,
                     "WEIGHTS_1": 5126, "COLOR_0": 5126}  # 5 different bones per vertex: two sets
    assert doc["accessors"][primitive["indices"]]["componentType"] == 5125
    assert len(doc["meshes"]) == 1  # the surface without triangles is left out
    (back,) = infuse.load(out).meshes
    np.testing.assert_allclose(back.positions, mesh.positions, atol=1e-6)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    expected_normals = np.array(mesh.normals)
    expected_normals[7] = [0.0, 1.0, 0.0]
    np.testing.assert_allclose(back.normals, expected_normals, atol=1e-6)
    _assert_same_weights(mesh, sk.names, back, sk.names)
    np.testing.assert_allclose(back.inverse_bind, mesh.inverse_bind, atol=1e-5)
    np.testing.assert_allclose(back.vertex_colors(), mesh.vertex_colors(), atol=1e-6)
    np.testing.assert_allclose(back.morph_positions, mesh.morph_positions, atol=1e-7)
    assert back.double_sided and back.morph_names == ("bulge", "noise")


def test_influences_follow_gltf_rules():
    joints = np.array([[3, 1, 3, 2, 5], [4, 4, 0, 0, 0], [2, 0, 0, 0, 0]])
    weights = np.array([[0.2, 0.3, 0.3, 0.0, 0.2], [0.5, 0.5, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0]])
    j, w = influence_sets(joints, weights)
    assert j.shape == w.shape == (3, 4) and w.dtype == np.float32
    np.testing.assert_array_equal(j, [[3, 1, 5, 0], [4, 0, 0, 0], [2, 0, 0, 0]])
    np.testing.assert_allclose(w, [[0.5, 0.3, 0.2, 0.0], [1.0, 0, 0, 0], [1.0, 0, 0, 0]], atol=1e-7)
    assert np.all(np.abs(w.astype(np.float64).sum(axis=1) - 1.0) < 1e-7)


def test_colour_factors_multiply_back_to_the_colours():
    base = [0.5, 0.25, 1.0, 1.0]
    mesh = SkinnedMesh("m", np.zeros((2, 3)), np.tile([0.0, 1.0, 0.0], (2, 1)), np.zeros((0, 3)), np.zeros((2, 1)),
                       np.ones((2, 1)), [0], np.eye(4)[None], base_color=base, colors=[[0.25, 0.2, 0.5, 1.0], [0, 0, 0, 0.5]])
    factor, per_vertex = color_factors(mesh)
    np.testing.assert_allclose(factor, base)
    np.testing.assert_allclose(factor * per_vertex, mesh.colors, atol=1e-7)
    brighter = SkinnedMesh("m", mesh.positions, mesh.normals, mesh.triangles, mesh.joints, mesh.weights, [0], np.eye(4)[None],
                           base_color=base, colors=[[0.9, 0.9, 0.9, 1.0], [0, 0, 0, 1.0]])
    factor, per_vertex = color_factors(brighter)
    np.testing.assert_allclose(factor, 1.0)
    np.testing.assert_allclose(per_vertex, brighter.colors)
    assert color_factors(SkinnedMesh("m", mesh.positions, mesh.normals, mesh.triangles, mesh.joints, mesh.weights, [0],
                                     np.eye(4)[None], base_color=base))[1] is None


def test_mesh_of_another_skeleton_is_refused(tmp_path):
    sk = _chain(3)
    stray = SkinnedMesh("stray", np.eye(3), np.tile([0.0, 1.0, 0.0], (3, 1)), [[0, 1, 2]], np.zeros((3, 1)), np.ones((3, 1)),
                        [5], np.eye(4)[None])
    asset = infuse.Asset(path=None, format="test", skeleton=sk, mesh_loader=lambda: [stray])
    with pytest.raises(UsageError, match="another skeleton"):
        infuse.save(asset, tmp_path / "stray.glb")
    assert not (tmp_path / "stray.glb").exists()
