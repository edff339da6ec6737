"""FBX meshes: the corpus characters' skinned surfaces, a synthetic skinned cube checked against explicit
matrices (binary and ASCII), and geometry that cannot be used."""
import base64
import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import infuse
from infuse.mesh import merge, rigid_matrices
from infuse.transforms import frame_change
from infuse_fbx import binary
from infuse_fbx.document import build

from affine import rotation as _R, translation as _T
from corpus_data import corpus_file
from test_fbx import C, P, fbx_bytes, fbx_text, model

CHARACTERS = ["ubiq-rocketbox/Ubiq_Robot_Rocketbox.fbx", "ue4-mannequin/SK_Mannequin.FBX"]


# -- the corpus characters --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def characters():
    out = {}
    for rel in CHARACTERS:
        path = corpus_file(rel)
        asset = infuse.load(path)
        version, root = binary.parse(path, path.read_bytes())
        out[rel] = (asset, build(path, version, root))
    return out


def _fbx_arrays(doc):
    geom = next(o for o in doc.objects.values() if o.kind == "Geometry" and o.subclass == "Mesh")
    return geom, geom.node.find("Vertices").props[0], geom.node.find("PolygonVertexIndex").props[0]


def _bind_pose(asset, doc):
    """Global rigid transforms (J, 4, 4), core frame, of the joints as the skin clusters bound them."""
    sk = asset.skeleton
    out = rigid_matrices(sk.rest_global_rotations, sk.rest_global_positions)
    scale = asset.meta["unit_scale_factor_cm"] * 0.01
    change = frame_change(scale, asset.source_up_axis)
    for cluster in (o for o in doc.objects.values() if o.subclass == "Cluster"):
        bone = [m for m, _ in doc.children_of(cluster.id, "Model")]
        link = cluster.node.find("TransformLink")
        if bone and link is not None and bone[0].name in sk.index:
            g = change @ link.props[0].reshape(4, 4).T
            g[:3, :3] /= np.linalg.norm(g[:3, :3], axis=0)  # the rigid part: unit columns
            out[sk.index[bone[0].name]] = g
    return out


def test_meshes_are_decoded_on_first_use(characters):
    for asset, _ in characters.values():
        assert asset.mesh_loader is not None
    path = corpus_file(CHARACTERS[0])
    fresh = infuse.load(path)
    assert "meshes" not in vars(fresh)  # not decoded by loading
    assert len(fresh.meshes) == 3 and "meshes" in vars(fresh)


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda r: Path(r).name)
def test_corpus_mesh_matches_the_file_arrays(characters, rel):
    asset, doc = characters[rel]
    _, vertices, index = _fbx_arrays(doc)
    ends = np.nonzero(index < 0)[0]
    sizes = np.diff(np.concatenate(([-1], ends)))
    meshes = asset.meshes
    assert meshes and not asset.warnings or all("texture" in w for w in asset.warnings)
    assert sum(m.num_triangles for m in meshes) == int(np.sum(sizes - 2))
    corners = np.where(index < 0, ~index, index)
    total = sum(m.num_vertices for m in meshes)
    assert len(np.unique(corners)) <= total <= len(index)
    assert len(vertices) // 3 >= len(np.unique(corners))
    materials = [m for m, _ in doc.children_of(next(o for o in doc.objects.values() if o.subclass == "Mesh" and o.kind == "Model").id,
                                               "Material")]
    assert sorted(m.name.split("/")[-1] for m in meshes) == sorted(m.name for m in materials)
    for m in meshes:
        assert m.weights.shape[1] <= 4 and np.all(m.weights >= 0)
        assert np.allclose(m.weights.sum(axis=1), 1.0, atol=1e-6)
        assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-5)


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda r: Path(r).name)
def test_skinning_the_bind_pose_gives_the_bind_positions(characters, rel):
    asset, doc = characters[rel]
    bind = _bind_pose(asset, doc)
    from infuse import quaternions as quat
    rotations = quat.from_matrix(bind[:, :3, :3])[None]
    for m in asset.meshes:
        posed, normals = m.skin(rotations, bind[None, :, :3, 3])
        assert np.abs(posed[0] - m.positions).max() < 1e-4
        assert np.einsum("vc,vc->v", normals[0], m.normals).min() > 0.999


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda r: Path(r).name)
def test_corpus_mesh_sits_on_the_skeleton(characters, rel):
    asset, _ = characters[rel]
    sk = asset.skeleton
    mesh = merge(asset.meshes)
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    joints = sk.rest_global_positions
    assert np.all(joints >= lo - 0.01) and np.all(joints <= hi + 0.01)
    assert abs(lo[1] - joints[:, 1].min()) < 0.03  # soles on the floor the root stands on
    assert np.all(np.abs(hi[[0, 2]] - joints[:, [0, 2]].max(axis=0)) < 0.06)  # fingertips, toes
    assert np.all(np.abs(lo[[0, 2]] - joints[:, [0, 2]].min(axis=0)) < 0.12)  # heels, the back
    assert 0.1 < hi[1] - joints[:, 1].max() < 0.3  # the crown of the head above the head joint
    main = mesh.bind_joints[mesh.joints[np.arange(mesh.num_vertices), mesh.weights.argmax(axis=1)]]
    assert np.linalg.norm(mesh.positions - joints[main], axis=1).max() < 0.6  # nothing far from its bone


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda r: Path(r).name)
def test_corpus_faces_point_outward(characters, rel):
    asset, _ = characters[rel]
    mesh = merge(asset.meshes)
    p = mesh.positions[mesh.triangles].astype(np.float64)
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    vertex = mesh.normals[mesh.triangles].sum(axis=1)
    agree = np.einsum("tc,tc->t", face, vertex) > 0
    assert agree.mean() > 0.97  # counter-clockwise, as the file's normals say


# -- a synthetic skinned cube -----------------------------------------------------------------------


ARMATURE = _R("z", 30) @ np.diag([2.0, 2.0, 2.0, 1.0])
HIPS = ARMATURE @ _T((0, 0, 40))
SPINE = HIPS @ _T((0, 0, 10)) @ _R("x", 20)
BODY = ARMATURE @ _T((5, 0, 0))
GEO = _T((0, 0, 3)) @ _R("z", 90) @ np.diag([1.5, 1.5, 1.5, 1.0])
SPINE_BIND = SPINE @ _R("x", 10)  # the skin was bound with the spine bent 10 degrees further
CORE = frame_change(0.0254, "Z")  # inches, Z up

CUBE = np.array([[x, y, z] for z in (40, 50) for y in (-5, 5) for x in (-5, 5)], dtype=np.float64)
TRIANGLE = np.array([[20, 0, 40], [25, 0, 40], [20, 0, 45]], dtype=np.float64)
POINTS = np.concatenate([CUBE, TRIANGLE])
# Quads wound counter-clockwise seen from outside: -z, +z, -y, +y, -x, +x; then a triangle facing -y.
QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
FACE_NORMALS = np.array([[0, 0, -1], [0, 0, 1], [0, -1, 0], [0, 1, 0], [-1, 0, 0], [1, 0, 0], [0, -1, 0]], dtype=np.float64)
POLYGONS = [list(q) for q in QUADS] + [[8, 9, 10]]
SLOTS = [0, 0, 0, 0, 1, 1, 0]
SMILE = {4: (0.0, 0.0, 1.0), 5: (0.0, 0.0, 2.0)}
# cluster id -> (bone model id, {point: weight}); point 0 has five influences, the triangle none.
CLUSTERS = {
    61: (11, {**{p: 1.0 for p in range(4)}, **{p: 0.25 for p in range(4, 8)}}),
    62: (12, {p: 0.5 for p in range(4, 8)}),
    63: (12, {0: 0.1}), 64: (11, {0: 0.2}), 65: (12, {0: 0.3}), 66: (11, {0: 0.4}),
}
ORANGE = (255, 128, 0)


def _index_array(polygons):
    flat = []
    for poly in polygons:
        flat += list(poly[:-1]) + [-1 - poly[-1]]
    return np.array(flat, dtype=np.int32)


def _geometry(oid, name, points=POINTS, polygons=POLYGONS, normals=True, extra=()):
    corners = [c for poly in polygons for c in poly]
    children = [
        ("Vertices", [np.asarray(points, dtype=np.float64).reshape(-1)], []),
        ("PolygonVertexIndex", [_index_array(polygons)], []),
        ("LayerElementMaterial", [0], [("MappingInformationType", ["ByPolygon"], []),
                                       ("ReferenceInformationType", ["IndexToDirect"], []),
                                       ("Materials", [np.array(SLOTS[:len(polygons)], dtype=np.int32)], [])]),
        ("LayerElementUV", [0], [("MappingInformationType", ["ByPolygonVertex"], []),
                                 ("ReferenceInformationType", ["Direct"], []),
                                 ("UV", [np.tile([0.25, 0.75], len(corners)).astype(np.float64)], [])]),
    ]
    if normals:
        children.append(("LayerElementNormal", [0], [
            ("MappingInformationType", ["ByPolygonVertex"], []), ("ReferenceInformationType", ["IndexToDirect"], []),
            ("Normals", [FACE_NORMALS.reshape(-1)], []),
            ("NormalsIndex", [np.array([f for f, poly in enumerate(polygons) for _ in poly], dtype=np.int32)], [])]))
    return ("Geometry", [oid, f"{name}\x00\x01Geometry", "Mesh"], children + list(extra))


def _matrix(m):
    return np.asarray(m, dtype=np.float64).T.reshape(-1)  # column by column


def _cluster(oid, bone, weights):
    link = {11: HIPS, 12: SPINE_BIND}[bone]
    return ("Deformer", [oid, "\x00\x01SubDeformer", "Cluster"], [
        ("Indexes", [np.array(list(weights), dtype=np.int32)], []),
        ("Weights", [np.array(list(weights.values()), dtype=np.float64)], []),
        ("Transform", [_matrix(np.linalg.inv(link) @ BODY)], []),
        ("TransformLink", [_matrix(link)], []),
    ])


def _png(color):
    buf = io.BytesIO()
    Image.new("RGB", (4, 4), color).save(buf, format="PNG")
    return buf.getvalue()


def cube_scene(geometry=None, video=None, extra_objects=(), extra_connections=()):
    """The skinned cube; ``video`` holds the textured material's Video records."""
    shape = ("Geometry", [72, "smile\x00\x01Geometry", "Shape"], [
        ("Indexes", [np.array(list(SMILE), dtype=np.int32)], []),
        ("Vertices", [np.array(list(SMILE.values()), dtype=np.float64).reshape(-1)], [])])
    objects = [
        model(10, "Armature", "Null", P("Lcl Scaling", 2.0, 2.0, 2.0), P("Lcl Rotation", 0.0, 0.0, 30.0)),
        model(11, "Hips", "LimbNode", P("Lcl Translation", 0.0, 0.0, 40.0)),
        model(12, "Spine", "LimbNode", P("Lcl Translation", 0.0, 0.0, 10.0), P("Lcl Rotation", 20.0, 0.0, 0.0)),
        model(13, "Body", "Mesh", P("Lcl Translation", 5.0, 0.0, 0.0), P("GeometricTranslation", 0.0, 0.0, 3.0),
              P("GeometricRotation", 0.0, 0.0, 90.0), P("GeometricScaling", 1.5, 1.5, 1.5)),
        geometry if geometry is not None else _geometry(50, "Cube"),
        ("Deformer", [60, "\x00\x01Deformer", "Skin"], []),
        *[_cluster(oid, bone, w) for oid, (bone, w) in CLUSTERS.items()],
        ("Deformer", [70, "Face\x00\x01Deformer", "BlendShape"], []),
        ("Deformer", [71, "smile\x00\x01SubDeformer", "BlendShapeChannel"], []),
        shape,
        ("Material", [80, "Red\x00\x01Material", ""], [("Properties70", [], [
            P("DiffuseColor", 1.0, 0.0, 0.0), P("DiffuseFactor", 0.5)])]),
        ("Material", [81, "Textured\x00\x01Material", ""], [("Properties70", [], [P("DiffuseColor", 0.0, 0.0, 1.0)])]),
        ("Texture", [82, "diffuse\x00\x01Texture", ""], [("RelativeFilename", ["C:\\art\\orange.png"], [])]),
        ("Video", [83, "orange.png\x00\x01Video", "Clip"], video or []),
        *extra_objects,
    ]
    connections = [
        C("OO", 10, 0), C("OO", 11, 10), C("OO", 12, 11), C("OO", 13, 10), C("OO", 50, 13), C("OO", 60, 50),
        *[C("OO", oid, 60) for oid in CLUSTERS], *[C("OO", bone, oid) for oid, (bone, _) in CLUSTERS.items()],
        C("OO", 70, 50), C("OO", 71, 70), C("OO", 72, 71),
        C("OO", 80, 13), C("OO", 81, 13), C("OP", 82, 81, "DiffuseColor"), C("OO", 83, 82),
        *extra_connections,
    ]
    return [
        ("GlobalSettings", [], [("Properties70", [], [P("UpAxis", 2), P("UpAxisSign", 1), P("UnitScaleFactor", 2.54)])]),
        ("Objects", [], objects),
        ("Connections", [], connections),
    ]


def _expected_rest(point):
    """Where the file's skin puts control point ``point`` at rest, core frame (metres)."""
    x = GEO @ np.append(POINTS[point], 1.0)
    links = {11: HIPS, 12: SPINE_BIND}
    worlds = {11: HIPS, 12: SPINE}
    influences = [(bone, w[point]) for bone, w in CLUSTERS.values() if point in w]
    influences = sorted(influences, key=lambda bw: -bw[1])[:4]
    if not influences:
        return (CORE @ BODY @ x)[:3]  # unweighted: where the mesh's model puts it
    total = sum(w for _, w in influences)
    return sum(w / total * (CORE @ worlds[b] @ np.linalg.inv(links[b]) @ BODY @ x)[:3] for b, w in influences)


def _write(tmp_path, encode, scene_records):
    path = tmp_path / ("cube.fbx" if encode is fbx_bytes else "cube-ascii.fbx")
    path.write_bytes(encode(scene_records))
    return path


@pytest.mark.parametrize("encode", [fbx_bytes, fbx_text], ids=["binary", "ascii"])
def test_synthetic_cube_matches_explicit_matrices(tmp_path, encode):
    if encode is fbx_bytes:  # the texture's image beside the file
        (tmp_path / "orange.png").write_bytes(_png(ORANGE))
        video = []
    else:  # embedded, base64 in an ASCII file
        video = [("Content", [base64.b64encode(_png(ORANGE)).decode()], [])]
    asset = infuse.load(_write(tmp_path, encode, cube_scene(video=video)))
    assert asset.warnings == []
    red, textured = sorted(asset.meshes, key=lambda m: m.name)
    assert (red.name, textured.name) == ("Body/Red", "Body/Textured")
    assert (red.num_triangles, textured.num_triangles) == (9, 4)  # 4 quads + the triangle, 2 quads
    assert (red.num_vertices, textured.num_vertices) == (19, 8)  # split where the face normals differ
    assert np.allclose(red.base_color, [0.5, 0.0, 0.0, 1.0]) and red.colors is None
    linear_orange = ((np.array(ORANGE) / 255 + 0.055) / 1.055) ** 2.4
    assert np.allclose(textured.colors[:, :3], linear_orange, atol=2e-3)

    bind_points = (CORE @ BODY @ GEO @ np.c_[POINTS, np.ones(len(POINTS))].T).T[:, :3]
    sk = asset.skeleton
    centre = bind_points[:8].mean(axis=0)
    for mesh in (red, textured):
        # Every vertex is a control point in the bind pose, and rest skinning puts it where the file does.
        dist = np.linalg.norm(mesh.positions[:, None] - bind_points[None], axis=2)
        point = dist.argmin(axis=1)
        assert dist.min(axis=1).max() < 1e-6
        posed, normals = mesh.skin(sk.rest_global_rotations, sk.rest_global_positions)
        assert np.allclose(posed[0], [_expected_rest(p) for p in point], atol=1e-6)
        assert np.allclose(mesh.weights.sum(axis=1), 1.0)
        # Normals point out of the cube; triangles wind counter-clockwise seen from outside.
        cube = point < 8
        assert np.all(np.einsum("vc,vc->v", mesh.normals[cube], mesh.positions[cube] - centre) > 0)
        p = mesh.positions[mesh.triangles].astype(np.float64)
        face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        assert np.all(np.einsum("tc,tc->t", face, mesh.normals[mesh.triangles[:, 0]]) > 0)
        # The smile offsets, in metres in the core frame.
        assert mesh.morph_names == ("smile",)
        want = np.array([SMILE.get(int(p), (0.0, 0.0, 0.0)) for p in point]) @ (CORE @ BODY @ GEO)[:3, :3].T
        assert np.allclose(mesh.morph_positions[0], want, atol=1e-9)
    assert asset.morph_targets == ["smile"]
    # Point 0 keeps its four largest of five weights: 1.0, 0.4, 0.3, 0.2 (not 0.1), renormalized.
    first = np.linalg.norm(red.positions - bind_points[0], axis=1).argmin()
    assert np.allclose(np.sort(red.weights[first])[::-1], np.array([1.0, 0.4, 0.3, 0.2]) / 1.9)


def test_units_override_moves_mesh_and_skeleton_together(tmp_path):
    path = _write(tmp_path, fbx_bytes, cube_scene())
    base, cm = infuse.load(path), infuse.load(path, units="cm")
    a, b = merge(base.meshes), merge(cm.meshes)
    assert np.allclose(b.positions * 2.54, a.positions, atol=1e-6)
    posed, _ = b.skin(cm.skeleton.rest_global_rotations, cm.skeleton.rest_global_positions)
    assert np.allclose(posed[0] * 2.54, a.skin(base.skeleton.rest_global_rotations, base.skeleton.rest_global_positions)[0][0],
                       atol=1e-6)


def test_smooth_normals_without_a_normal_layer(tmp_path):
    asset = infuse.load(_write(tmp_path, fbx_bytes, cube_scene(_geometry(50, "Cube", normals=False))))
    assert sorted(m.num_vertices for m in asset.meshes) == [8, 11]  # one vertex per control point of a surface
    mesh = merge(asset.meshes)
    bind_points = (CORE @ BODY @ GEO @ np.c_[CUBE, np.ones(8)].T).T[:, :3]
    cube = np.linalg.norm(mesh.positions[:, None] - bind_points[None], axis=2).min(axis=1) < 1e-6
    assert np.all(np.einsum("vc,vc->v", mesh.normals[cube], mesh.positions[cube] - bind_points.mean(axis=0)) > 0)


def test_ascii_embedded_content_after_a_leading_comma(tmp_path):
    video = [("Content", [base64.b64encode(_png(ORANGE)).decode()], [])]
    text = fbx_text(cube_scene(video=video)).replace(b'Content: "', b'Content: , "')
    path = tmp_path / "comma.fbx"
    path.write_bytes(text)
    textured = next(m for m in infuse.load(path).meshes if m.name.endswith("Textured"))
    assert textured.colors is not None and textured.colors[0, 0] > 0.9


def _malformed():
    bad = _geometry(51, "Broken")
    yield "vertices-not-triples", _replace_child(bad, "Vertices", np.arange(7, dtype=np.float64))
    yield "polygon-not-ended", _replace_child(bad, "PolygonVertexIndex", np.array([0, 1, 2], dtype=np.int32))
    yield "index-out-of-range", _replace_child(bad, "PolygonVertexIndex", np.array([0, 1, -100], dtype=np.int32))
    yield "no-polygons", ("Geometry", bad[1], [c for c in bad[2] if c[0] != "PolygonVertexIndex"])
    yield "material-layer-short", _replace_layer(bad, "LayerElementMaterial", "Materials", np.array([0, 1], dtype=np.int32))
    yield "nan-vertex", _replace_child(bad, "Vertices", np.where(POINTS == 5, np.nan, POINTS).reshape(-1))


def _replace_child(geom, name, value):
    return ("Geometry", geom[1], [(c[0], [value], c[2]) if c[0] == name else c for c in geom[2]])


def _replace_layer(geom, layer, name, value):
    children = []
    for c in geom[2]:
        if c[0] == layer:
            c = (c[0], c[1], [(k[0], [value], k[2]) if k[0] == name else k for k in c[2]])
        children.append(c)
    return ("Geometry", geom[1], children)


@pytest.mark.parametrize("case", list(_malformed()), ids=lambda c: c[0])
@pytest.mark.parametrize("encode", [fbx_bytes, fbx_text], ids=["binary", "ascii"])
def test_malformed_geometry_is_skipped_with_a_warning(tmp_path, encode, case):
    _, broken = case
    scene_records = cube_scene(extra_objects=[model(14, "Prop", "Mesh"), broken],
                               extra_connections=[C("OO", 14, 11), C("OO", 51, 14)])
    asset = infuse.load(_write(tmp_path, encode, scene_records))
    names = sorted(m.name for m in asset.meshes)
    assert names == ["Body/Red", "Body/Textured"]  # the good cube is still drawn
    assert any(w.startswith("mesh 'Prop' is not drawn") for w in asset.warnings), asset.warnings


def test_bad_normals_and_bad_clusters(tmp_path):
    geom = _replace_layer(_geometry(50, "Cube"), "LayerElementNormal", "NormalsIndex", np.array([0, 1], dtype=np.int32))
    asset = infuse.load(_write(tmp_path, fbx_bytes, cube_scene(geom)))
    assert len(asset.meshes) == 2 and any("smooth normals computed" in w for w in asset.warnings)
    records = cube_scene()
    objects = records[1][2]
    k = next(i for i, o in enumerate(objects) if o[0] == "Deformer" and o[1][0] == 62)
    objects[k] = ("Deformer", objects[k][1], [c for c in objects[k][2] if c[0] != "Weights"] +
                  [("Weights", [np.array([0.5], dtype=np.float64)], [])])
    asset = infuse.load(_write(tmp_path, fbx_bytes, records))
    assert asset.meshes == () and any("Indexes and Weights" in w for w in asset.warnings)


def test_unskinned_mesh_follows_its_joint_and_one_outside_is_left_out(tmp_path):
    prop = _geometry(52, "Stick", points=TRIANGLE, polygons=[[0, 1, 2]])
    loose = _geometry(53, "Loose", points=TRIANGLE, polygons=[[0, 1, 2]])
    records = cube_scene(extra_objects=[model(14, "Prop", "Mesh", P("Lcl Translation", 0.0, 1.0, 0.0)), prop,
                                        model(15, "Scenery", "Mesh"), loose],
                         extra_connections=[C("OO", 14, 12), C("OO", 52, 14), C("OO", 15, 0), C("OO", 53, 15)])
    asset = infuse.load(_write(tmp_path, fbx_bytes, records))
    stick = next(m for m in asset.meshes if m.name == "Prop")
    sk = asset.skeleton
    assert list(stick.bind_joints) == [sk.index["Spine"]]
    want = (CORE @ SPINE @ _T((0, 1, 0)) @ np.c_[TRIANGLE, np.ones(3)].T).T[:, :3]
    dist = np.linalg.norm(stick.positions[:, None] - want[None], axis=2)
    assert dist.min(axis=1).max() < 1e-6
    posed, _ = stick.skin(sk.rest_global_rotations, sk.rest_global_positions)
    assert np.allclose(posed[0], stick.positions, atol=1e-6)
    assert "Scenery" not in {m.name for m in asset.meshes}
    assert any("'Scenery' is not drawn" in w and "outside the skeleton" in w for w in asset.warnings)


def test_undecodable_texture_falls_back_to_the_colour(tmp_path):
    asset = infuse.load(_write(tmp_path, fbx_bytes, cube_scene(video=[("Content", [base64.b64encode(b"not an image").decode()], [])])))
    textured = next(m for m in asset.meshes if m.name.endswith("Textured"))
    assert textured.colors is None and np.allclose(textured.base_color, [0.0, 0.0, 1.0, 1.0])
    assert any("cannot be decoded" in w for w in asset.warnings), asset.warnings
