"""Draco-compressed characters (``KHR_draco_mesh_compression``) read like their uncompressed originals.

Corpus characters (Xbot, a Ready Player Me avatar with morph targets) are compressed here with a real
encoder, glTF Transform's CLI (``make setup`` installs it; the tests skip without it except under
``CI=true``), and read back: Draco may reorder and split vertices, so every decoded vertex must have an
original twin whose position, normal, texture colour and skin weights agree within the quantization
steps the encoder was given, and the other way round.
"""
from __future__ import annotations

import json
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree

import infuse
from corpus_data import UNDER_CI, corpus_file, require_corpus
from gltf_builder import mini_rig, world_matrices
from infuse import quaternions as quat
from infuse.cli import main
from infuse.errors import InputError
from infuse.kinematics import forward_kinematics
from infuse.mesh import SkinnedMesh
from infuse.render import Camera, Figure, Renderer, Style
from infuse_gltf import validate as validator

SOURCES = {"xbot": "runxaway-models/Xbot.glb", "avatar": "talkinghead/avatars/brunette-t.glb"}
WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
CLIP = "dataset-1_walk_normal_001"
DRACO = "KHR_draco_mesh_compression"
#: Quantization bits given to the encoder (its defaults, stated so the tolerances follow from them).
BITS = {"position": 14, "normal": 10, "texcoord": 12, "generic": 12, "color": 8}
BARE = Style(show_grid=False, show_shadow=False, show_trail=False)  # only the figure differs from the background


def gltf_transform() -> Path:
    """The glTF Transform CLI: the one setup installs beside the venv, else one on PATH."""
    local = Path(sys.prefix) / "tools" / "node_modules" / ".bin" / "gltf-transform"
    found = local if local.is_file() else shutil.which("gltf-transform")
    if found is None or shutil.which("node") is None:
        message = "glTF Transform's CLI is missing: run `make setup` (npm @gltf-transform/cli)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return Path(found)


def transform(*args) -> None:
    done = subprocess.run([str(gltf_transform()), *map(str, args)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]


def compress(source: Path, out: Path) -> Path:
    transform("draco", source, out, *(a for kind, bits in BITS.items() for a in (f"--quantize-{kind}", bits)))
    return out


def glb_parts(path: Path) -> tuple[dict, bytes]:
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20:20 + length]), data[28 + length:]


def write_glb(path: Path, doc: dict, body: bytes) -> Path:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body += b"\0" * (-len(body) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(body), 0x004E4942) + body
    path.write_bytes(b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks)
    return path


def draco_primitives(doc: dict) -> list[dict]:
    return [p for m in doc.get("meshes", []) for p in m["primitives"] if DRACO in p.get("extensions", {})]


def coloured_primitives(doc: dict) -> list[dict]:
    """The Draco primitives that compress COLOR_0 (the built sheet's)."""
    return [p for p in draco_primitives(doc) if "COLOR_0" in p["extensions"][DRACO]["attributes"]]


@pytest.fixture(scope="module")
def characters(tmp_path_factory) -> dict[str, tuple[infuse.Asset, infuse.Asset, Path]]:
    """name -> (original asset, Draco-compressed asset, compressed path)."""
    require_corpus()
    gltf_transform()
    out = tmp_path_factory.mktemp("draco")
    result = {}
    for name, rel in SOURCES.items():
        path = compress(corpus_file(rel), out / f"{name}_draco.glb")
        result[name] = (infuse.load(corpus_file(rel)), infuse.load(path), path)
    return result


# -- comparing two surfaces vertex by vertex ----------------------------------------------------------
def dense_weights(mesh: SkinnedMesh, joints: int) -> np.ndarray:
    """(V, J) weight of every vertex on every skeleton joint."""
    out = np.zeros((mesh.num_vertices, joints))
    rows = np.repeat(np.arange(mesh.num_vertices), mesh.joints.shape[1])
    np.add.at(out, (rows, mesh.bind_joints[mesh.joints].reshape(-1)), mesh.weights.reshape(-1))
    return out


def position_step(mesh: SkinnedMesh, bits: int) -> float:
    """Draco's quantization step for the positions of ``mesh``: its bounding box's largest side over 2^bits - 1."""
    return float(np.ptp(mesh.positions, axis=0).max()) / (2 ** bits - 1)


def twins(decoded: SkinnedMesh, original: SkinnedMesh, joints: int, tolerances: dict) -> tuple[np.ndarray, np.ndarray]:
    """For every vertex of ``decoded``: the original vertex that agrees best with it, and how well,
    as the largest of its differences (position, normal angle, colour, weights) over their tolerances.
    A vertex without an original within the position tolerance scores infinity."""
    k = min(32, original.num_vertices)  # copies of one point: UV and normal seams, the poles of a UV sphere
    distance, candidates = cKDTree(original.positions).query(decoded.positions, k=k, distance_upper_bound=tolerances["position"])
    found = np.isfinite(distance)
    candidates = np.where(found, candidates, 0)
    score = distance / tolerances["position"]
    dn, on = decoded.normals[:, None].astype(np.float64), original.normals[candidates].astype(np.float64)
    angle = np.arctan2(np.linalg.norm(np.cross(dn, on), axis=-1), (dn * on).sum(axis=-1))  # exact near 0, unlike arccos
    score = np.maximum(score, np.degrees(angle) / tolerances["normal_degrees"])
    if decoded.colors is not None or original.colors is not None:
        colour = np.abs(decoded.vertex_colors()[:, None] - original.vertex_colors()[candidates]).max(axis=-1)
        score = np.maximum(score, colour / tolerances["colour"])
    dw, ow = dense_weights(decoded, joints), dense_weights(original, joints)
    for rows in np.array_split(np.arange(len(dw)), max(1, len(dw) // 2048)):  # (rows, k, joints) at a time
        error = np.abs(dw[rows, None] - ow[candidates[rows]]).max(axis=-1)
        score[rows] = np.maximum(score[rows], error / tolerances["weight"])
    score = np.where(found, score, np.inf)
    best = np.argmin(score, axis=1)
    rows = np.arange(len(best))
    return candidates[rows, best], score[rows, best]


def tolerances(original: SkinnedMesh) -> dict:
    return {
        "position": position_step(original, BITS["position"]) + 1e-6,  # round-off is half a step per axis
        "normal_degrees": 1.0,  # octahedral normals, 10 bits: about 0.2 degrees
        # the texture sampled at UVs moved by up to half a 12-bit step: sharp edges (an iris) change by 0.1
        "colour": 0.15,
        "weight": 2.0 / (2 ** BITS["generic"] - 1) + 1e-6,
    }


def random_pose(sk: infuse.Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations and positions (1, J, ...) of the skeleton with every joint bent up to 0.6 rad."""
    rng = np.random.default_rng(5)
    axes = rng.normal(size=(sk.num_joints, 3))
    turn = quat.from_axis_angle(axes / np.linalg.norm(axes, axis=1, keepdims=True), rng.uniform(-0.6, 0.6, sk.num_joints))
    rot, pos = forward_kinematics(sk, quat.multiply(sk.rest_rotations, turn)[None], sk.rest_translations[:1])
    return rot, pos


# -- tests -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(SOURCES))
def test_compressed_copy_really_is_draco(characters, name):
    _, draco, path = characters[name]
    doc, _ = glb_parts(path)
    assert DRACO in doc["extensionsRequired"]
    prims = [p for m in doc["meshes"] for p in m["primitives"]]
    assert prims and all(DRACO in p.get("extensions", {}) for p in prims)
    used = {s for p in prims for s in p["extensions"][DRACO]["attributes"]}
    assert {"POSITION", "NORMAL", "TEXCOORD_0", "JOINTS_0", "WEIGHTS_0"} <= used
    assert all("bufferView" not in doc["accessors"][p["attributes"]["POSITION"]] for p in prims)  # only Draco holds them
    assert DRACO in draco.meta["compression"]
    assert not [w for w in draco.warnings if "not drawn" in w]


@pytest.mark.parametrize("name", list(SOURCES))
def test_every_vertex_has_an_original_twin_and_back(characters, name):
    original, draco, _ = characters[name]
    joints = original.skeleton.num_joints
    assert [m.name for m in draco.meshes] == [m.name for m in original.meshes]
    assert draco.skeleton.names == original.skeleton.names
    for dec, orig in zip(draco.meshes, original.meshes):
        assert dec.num_triangles == orig.num_triangles, dec.name
        # Draco splits a vertex where its attributes are not shared: a few more vertices, never fewer
        assert orig.num_vertices <= dec.num_vertices <= orig.num_vertices * 1.01, dec.name
        tol = tolerances(orig)
        _, score = twins(dec, orig, joints, tol)
        assert score.max() <= 1.0, (dec.name, float(score.max()))
        _, back = twins(orig, dec, joints, tol)
        assert back.max() <= 1.0, (dec.name, float(back.max()))
        assert np.allclose(dec.weights.sum(axis=1), 1.0, atol=1e-6)
        assert np.allclose(np.linalg.norm(dec.normals, axis=1), 1.0, atol=1e-4)
        assert np.array_equal(dec.bind_joints, orig.bind_joints)
        assert np.allclose(dec.inverse_bind, orig.inverse_bind, atol=1e-4)  # the encoder rewrites nodes as float32
        assert (dec.colors is None) == (orig.colors is None)


@pytest.mark.parametrize("name", list(SOURCES))
def test_triangles_cover_the_same_surface_wound_the_same_way(characters, name):
    original, draco, _ = characters[name]
    for dec, orig in zip(draco.meshes, original.meshes):
        tol = tolerances(orig)["position"]
        centres = [m.positions[m.triangles].mean(axis=1) for m in (dec, orig)]
        distance, match = cKDTree(centres[1]).query(centres[0])
        assert distance.max() <= tol, dec.name
        def face_normals(mesh):
            p = mesh.positions[mesh.triangles].astype(np.float64)
            return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        fd, fo = face_normals(dec), face_normals(orig)[match]
        big = np.linalg.norm(fo, axis=1) > (10 * tol) ** 2  # faces the quantization step cannot flip
        assert big.mean() > 0.9, dec.name
        assert np.all(np.einsum("tc,tc->t", fd[big], fo[big]) > 0), dec.name  # no face turned inside out


@pytest.mark.parametrize("name", list(SOURCES))
def test_skinned_in_a_pose_the_twins_stay_together(characters, name):
    original, draco, _ = characters[name]
    rot, pos = random_pose(original.skeleton)
    joints = original.skeleton.num_joints
    for dec, orig in zip(draco.meshes, original.meshes):
        tol = tolerances(orig)
        twin, _ = twins(dec, orig, joints, tol)
        posed_dec = dec.skin(rot, pos)[0][0]
        posed_orig = orig.skin(rot, pos)[0][0]
        reach = np.linalg.norm(posed_orig, axis=1).max()  # how far a weight error can throw a vertex
        gap = np.linalg.norm(posed_dec - posed_orig[twin], axis=1)
        assert gap.max() <= 2 * tol["position"] + 4 * tol["weight"] * reach, dec.name
        assert gap.max() < 0.002, dec.name  # under 2 mm on a human figure


def test_morph_offsets_follow_their_reordered_vertices(characters):
    """Morph targets stay plain accessors, written by the encoder in Draco's vertex order: each decoded
    vertex keeps its twin's offsets exactly."""
    original, draco, _ = characters["avatar"]
    joints = original.skeleton.num_joints
    morphed = [(d, o) for d, o in zip(draco.meshes, original.meshes) if o.morph_names]
    assert {d.name for d, _ in morphed} >= {"Wolf3D_Head", "Wolf3D_Teeth", "EyeLeft", "EyeRight"}
    reordered = 0
    for dec, orig in morphed:
        assert dec.morph_names == orig.morph_names
        twin, _ = twins(dec, orig, joints, tolerances(orig))
        assert np.array_equal(dec.morph_positions, orig.morph_positions[:, twin])
        reordered += int(np.any(twin != np.arange(len(twin))))
    assert reordered  # the encoder did move vertices: the offsets were not simply left in place
    dec, orig = next((d, o) for d, o in morphed if d.name == "Wolf3D_Head")
    weights = np.zeros((1, len(dec.morph_names)))
    weights[0, dec.morph_names.index("jawOpen")] = 1.0
    sk = draco.skeleton
    at_rest = (sk.rest_global_rotations[None], sk.rest_global_positions[None])
    opened = [m.skin(*at_rest, morph_weights=weights)[0][0] for m in (dec, orig)]
    twin, _ = twins(dec, orig, joints, tolerances(orig))
    assert np.abs(opened[0] - opened[1][twin]).max() <= 2 * tolerances(orig)["position"]
    assert np.abs(opened[1] - orig.positions).max() > 0.005  # the jaw did open


def test_quantized_attributes_decode_to_the_same_normalized_values(tmp_path):
    """KHR_mesh_quantization first (normalized shorts and bytes), then Draco: Draco keeps integers as they
    are, so the decoded surfaces equal the quantized file's, read through its plain accessors."""
    require_corpus()
    quantized = tmp_path / "quantized.glb"
    transform("quantize", corpus_file(SOURCES["avatar"]), quantized)
    both = compress(quantized, tmp_path / "quantized_draco.glb")
    doc, _ = glb_parts(both)
    normalized = {doc["accessors"][p["attributes"][s]]["componentType"] for p in draco_primitives(doc)
                  for s in ("POSITION", "NORMAL", "TEXCOORD_0", "WEIGHTS_0") if doc["accessors"][p["attributes"][s]].get("normalized")}
    assert normalized >= {5121, 5122}  # normalized bytes and shorts are decoded from Draco integers
    plain, draco = infuse.load(quantized), infuse.load(both)
    joints = plain.skeleton.num_joints
    exact = {"position": 1e-6, "normal_degrees": 0.01, "colour": 1e-6, "weight": 1e-6}  # float32 round-off only
    for dec, orig in zip(draco.meshes, plain.meshes):
        assert dec.num_triangles == orig.num_triangles
        _, score = twins(dec, orig, joints, exact)
        assert score.max() <= 1.0, (dec.name, float(score.max()))


def _coloured_sheet(tmp_path: Path) -> Path:
    """The test rig with a skinned 6x6 sheet: COLOR_0 as float RGB on one primitive and as normalized
    unsigned shorts (RGBA) on another, normalized byte weights, byte joints."""
    b, n = mini_rig(animated=False)
    u, v = np.meshgrid(np.linspace(-20.0, 20.0, 6), np.linspace(90.0, 150.0, 6))
    grid = np.stack([u.ravel(), np.zeros(u.size), v.ravel()], axis=1)  # in the Armature's XZ plane: cm, Z up
    quads = np.array([(r * 6 + c, r * 6 + c + 1, (r + 1) * 6 + c + 1, (r + 1) * 6 + c) for r in range(5) for c in range(5)])
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.uint16)
    # the mesh node sits at the scene root: the grid goes to the world through the Armature, where the joints are
    world = world_matrices(b.doc)[n["Armature"]]
    points = grid @ world[:3, :3].T + world[:3, 3]
    normal = world[:3, 1] / np.linalg.norm(world[:3, 1])  # the Armature's Y axis, across its XZ plane
    up = np.clip((grid[:, 2] - 90.0) / 60.0, 0.0, 1.0)
    joints = np.stack([np.zeros(36), np.ones(36), np.full(36, 2), np.zeros(36)], axis=1)  # hips, spine, head
    weights = np.stack([1.0 - up, up * 0.5, up * 0.5, np.zeros(36)], axis=1)
    rgb = np.stack([up, 1.0 - up, np.full(36, 0.25)], axis=1)
    prims = []
    for colour in (b.accessor(rgb), b.accessor(np.concatenate([rgb[:, ::-1], np.ones((36, 1))], axis=1), 5123, normalized=True)):
        prims.append({"attributes": {"POSITION": b.accessor(points, minmax=True), "NORMAL": b.accessor(np.tile(normal, (36, 1))),
                                     "COLOR_0": colour, "JOINTS_0": b.accessor(joints, 5121),
                                     "WEIGHTS_0": b.accessor(weights, 5121, normalized=True)},
                      "indices": b.accessor(tris.reshape(-1, 1), 5123), "mode": 4})
    b.doc["meshes"].append({"name": "sheet", "primitives": prims})
    sheet = b.node("sheet", mesh=1, skin=0)
    b.doc["scenes"][0]["nodes"].append(sheet)
    return b.write_glb(tmp_path / "sheet.glb")


@pytest.fixture(scope="module")
def sheet(tmp_path_factory) -> tuple[Path, Path]:
    """The built sheet (see :func:`_coloured_sheet`) and its Draco-compressed copy."""
    gltf_transform()
    out = tmp_path_factory.mktemp("sheet")
    plain = _coloured_sheet(out)
    return plain, compress(plain, out / "sheet_draco.glb")


def test_vertex_colours_and_normalized_integers_of_a_built_sheet(sheet):
    plain_path, draco_path = sheet
    doc, _ = glb_parts(draco_path)
    colour_types = [doc["accessors"][p["attributes"]["COLOR_0"]]["componentType"] for p in coloured_primitives(doc)]
    assert sorted(colour_types) == [5123, 5126]
    plain, draco = infuse.load(plain_path), infuse.load(draco_path)
    sheets = [(d, o) for d, o in zip(draco.meshes, plain.meshes) if d.name.startswith("sheet")]
    assert len(sheets) == 2
    for dec, orig in sheets:
        assert dec.colors is not None and dec.num_vertices == 36
        tol = dict(tolerances(orig), colour=1.0 / 255 + 1e-6)  # colours: 8 bits
        _, score = twins(dec, orig, plain.skeleton.num_joints, tol)
        assert score.max() <= 1.0, (dec.name, float(score.max()))
    assert sheets[0][0].colors[:, 0].max() > 0.9 > 0.1 > sheets[0][0].colors[:, 0].min()  # a red-to-green ramp


def test_written_back_the_draco_character_keeps_its_compressed_meshes(characters, tmp_path):
    """The glTF writer copies a glTF character: its Draco data, extensionsRequired and all, valid."""
    if not validator.available():
        pytest.fail("the Khronos glTF validator is missing: run `make setup`")
    _, draco, path = characters["avatar"]
    out = infuse.save(draco, tmp_path / "copy.glb")
    (doc, body), (src, src_body) = glb_parts(out), glb_parts(path)
    assert DRACO in doc["extensionsUsed"] and DRACO in doc["extensionsRequired"]
    for prim, src_prim in zip(draco_primitives(doc), draco_primitives(src)):
        assert prim["extensions"][DRACO] == src_prim["extensions"][DRACO]
        view, src_view = (d["bufferViews"][p["extensions"][DRACO]["bufferView"]] for d, p in ((doc, prim), (src, src_prim)))
        assert body[view.get("byteOffset", 0):][:view["byteLength"]] == src_body[src_view.get("byteOffset", 0):][:src_view["byteLength"]]
    assert validator.errors(validator.validate(out)) == []
    again = infuse.load(out)
    for a, b in zip(again.meshes, draco.meshes):
        assert np.array_equal(a.positions, b.positions) and np.array_equal(a.triangles, b.triangles)


def figure_mask(motion: infuse.Motion, meshes, frame: int) -> np.ndarray:
    """(H, W) bool: the pixels the skinned ``meshes`` playing ``motion`` cover in a plain render, cropped
    to their bounding box."""
    figure = Figure.from_motion(motion, meshes=meshes)
    renderer = Renderer([figure], np.array([frame / motion.fps]), size=(320, 400), style=BARE,
                        counter=False, camera=Camera(follow=False))
    rgb = np.asarray(renderer.image(0, labels=False).convert("RGB")).astype(int)
    mask = np.abs(rgb - np.array(BARE.background)).sum(axis=-1) > 12
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]


def test_a_walk_retargeted_onto_the_draco_character_renders_like_the_original(characters, tmp_path, capsys):
    """End to end: retarget a BVH walk onto the compressed Xbot (written back as Draco GLB), render it with
    the CLI, and draw it next to the uncompressed Xbot's surfaces playing the same walk: the figures
    match. (The renderer frames a figure from a sample of vertices taken by index, which Draco
    reorders: the figures are compared in their own bounding boxes.)"""
    require_corpus()
    original, _, draco_path = characters["xbot"]
    walk = tmp_path / "draco_walk.glb"
    assert main(["retarget", str(corpus_file(WALK)), "--to", str(draco_path), "-o", str(walk)]) == 0
    assert DRACO in glb_parts(walk)[0]["extensionsRequired"]
    png = tmp_path / "draco.png"
    code = main(["render", str(walk), "-o", str(png), "--style", "mesh", "--clip", CLIP, "--strip", "3"])
    assert code == 0, capsys.readouterr().err
    assert len(np.unique(np.asarray(Image.open(png).convert("RGB")).reshape(-1, 3), axis=0)) > 200  # shaded, not blank
    walker = infuse.load(walk)
    motion = walker.motions[CLIP]
    for frame in (0, 40, 90):
        plain, draco = figure_mask(motion, original.meshes, frame), figure_mask(motion, walker.meshes, frame)
        assert abs(plain.shape[0] - draco.shape[0]) <= 3 and abs(plain.shape[1] - draco.shape[1]) <= 3
        h, w = min(plain.shape[0], draco.shape[0]), min(plain.shape[1], draco.shape[1])
        plain, draco = plain[:h, :w], draco[:h, :w]
        assert plain.mean() > 0.2
        assert (plain & draco).sum() / (plain | draco).sum() > 0.9, frame


# -- what goes wrong ----------------------------------------------------------------------------------
def _broken(sheet, tmp_path, change) -> Path:
    """The compressed sheet with ``change(doc, body)`` made to its JSON (or its binary chunk, returned)."""
    doc, body = glb_parts(sheet[1])
    body = change(doc, body) or body
    return write_glb(tmp_path / "broken.glb", doc, body)


def _corrupt_payload(doc, body):
    view = doc["bufferViews"][coloured_primitives(doc)[0]["extensions"][DRACO]["bufferView"]]
    start = view.get("byteOffset", 0)
    return body[:start] + b"\xff" * view["byteLength"] + body[start + view["byteLength"]:]


@pytest.mark.parametrize("change, place, problem", [
    (_corrupt_payload, f"extensions.{DRACO}", "does not decode"),
    (lambda doc, body: coloured_primitives(doc)[0]["extensions"][DRACO]["attributes"].update(COLOR_0=41), "COLOR_0", "no attribute with id 41"),
    (lambda doc, body: doc["accessors"][coloured_primitives(doc)[0]["attributes"]["NORMAL"]].update(count=35), "accessors[", "count 35"),
    (lambda doc, body: doc["accessors"][coloured_primitives(doc)[0]["attributes"]["POSITION"]].update(type="VEC2"), "accessors[", "components"),
    (lambda doc, body: coloured_primitives(doc)[0]["extensions"][DRACO]["attributes"].update(TEXCOORD_3=0), "TEXCOORD_3", "does not have"),
    (lambda doc, body: coloured_primitives(doc)[0]["extensions"][DRACO].update(bufferView=999), "bufferView", "out of range"),
])
def test_malformed_draco_data_is_an_input_error_naming_the_place(sheet, tmp_path, change, place, problem):
    asset = infuse.load(_broken(sheet, tmp_path, change))
    with pytest.raises(InputError) as caught:
        asset.meshes
    assert place in caught.value.place and problem in caught.value.problem


def test_without_dracopy_the_surfaces_are_skipped_with_a_warning(sheet, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # as if the package were not installed
    asset = infuse.load(_broken(sheet, tmp_path, lambda doc, body: None))
    assert asset.meshes == ()  # every primitive is compressed, the morph triangle too
    (warning,) = [w for w in asset.warnings if "not drawn" in w]
    assert "DracoPy" in warning and "2 more primitives" in warning
    assert asset.skeleton.num_joints == 5  # the skeleton and clips never need the mesh data
