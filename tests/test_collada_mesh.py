"""COLLADA meshes: the SmartBody characters' skinned surfaces checked against the files' own arrays
(read here independently), and synthetic scenes for polygons, rigid parts, colours, morphs and
malformed geometry."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from scipy.spatial import cKDTree

import infuse
from infuse import quaternions as quat
from infuse.cli import main
from infuse.errors import InputError
from infuse.kinematics import forward_kinematics
from infuse.mesh import rigid_matrices

from cli_errors import assert_one_error_line, write_case
from corpus_data import corpus_file

CHARACTERS = ["smartbody/mesh/brad/Brad.dae", "smartbody/mesh/doctor/Doctor.dae", "smartbody/mesh/elder/Elder.dae"]
UTAH = "smartbody/mesh/utah/Utah.dae"


# -- the files' own arrays, read with plain lxml -------------------------------------------------------

def _plain(path: Path):
    root = etree.parse(str(path), etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)).getroot()
    for el in root.iter():
        if isinstance(el.tag, str) and "}" in el.tag:
            el.tag = el.tag.split("}", 1)[1]
    return root, {el.get("id"): el for el in root.iter() if isinstance(el.tag, str) and el.get("id")}


def _numbers(el, dtype=float):
    return np.array((el.text or "").split(), dtype=dtype)


def _source(ids, url):
    src = ids[url.lstrip("#")]
    accessor = src.find("technique_common/accessor")
    return _numbers(src.find("float_array")).reshape(int(accessor.get("count")), int(accessor.get("stride", "1")))


def file_skins(path: Path) -> list[dict]:
    """Every skinned instance of the scene in document order: bind shape matrix, joint names,
    inverse bind matrices, each position's top-4 influences (a plain loop), the positions, and per
    primitive its triangle count and (position, normal) index of each corner."""
    root, ids = _plain(path)
    out = []
    for inst in root.find("library_visual_scenes").iter("instance_controller"):
        skin = ids[inst.get("url").lstrip("#")].find("skin")
        geometry = ids[skin.get("source").lstrip("#")]
        mesh = geometry.find("mesh")
        positions = _source(ids, mesh.find("vertices/input[@semantic='POSITION']").get("source"))
        names = skin.find("source/Name_array").text.split()
        ibm = _source(ids, skin.find("joints/input[@semantic='INV_BIND_MATRIX']").get("source")).reshape(-1, 4, 4)
        vw = skin.find("vertex_weights")
        weights = _source(ids, vw.find("input[@semantic='WEIGHT']").get("source"))[:, 0]
        counts, pairs = _numbers(vw.find("vcount"), int), _numbers(vw.find("v"), int).reshape(-1, 2).tolist()
        influences, k = [], 0
        for c in counts:
            found = sorted(((weights[w], j) for j, w in pairs[k:k + c]), key=lambda item: -item[0])[:4]
            total = sum(w for w, _ in found)
            influences.append([(j, w / total) for w, j in found])
            k += c
        primitives = []
        for prim in mesh:
            if prim.tag not in ("triangles", "polylist"):
                continue
            inputs = {i.get("semantic"): int(i.get("offset")) for i in prim.findall("input")}
            stride = max(inputs.values()) + 1
            corners = _numbers(prim.find("p"), int).reshape(-1, stride)
            sizes = _numbers(prim.find("vcount"), int) if prim.tag == "polylist" else np.full(len(corners) // 3, 3)
            primitives.append({"triangles": int(np.sum(sizes - 2)), "position": corners[:, inputs["VERTEX"]],
                               "normal": corners[:, inputs["NORMAL"]]})
        bsm = _numbers(skin.find("bind_shape_matrix")).reshape(4, 4)
        out.append({"name": geometry.get("name"), "positions": positions, "bind_shape": bsm, "names": names,
                    "inverse_bind": ibm, "influences": influences, "primitives": primitives})
    return out


@pytest.fixture(scope="module")
def characters():
    out = {}
    for rel in CHARACTERS:
        path = corpus_file(rel)
        asset = infuse.load(path)
        out[rel] = (asset, file_skins(path), asset.meta["unit_meter"])
    return out


def _surfaces_by_instance(asset, skins):
    """The asset's surfaces grouped like the file's instances (document order, one per primitive)."""
    meshes = list(asset.meshes)
    groups = []
    for skin in skins:
        groups.append(meshes[:len(skin["primitives"])])
        meshes = meshes[len(skin["primitives"]):]
    assert not meshes
    return groups


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda rel: Path(rel).name)
def test_surfaces_hold_the_files_triangles_and_bind_shape_positions(rel, characters):
    asset, skins, unit = characters[rel]
    for skin, surfaces in zip(skins, _surfaces_by_instance(asset, skins)):
        bind_shape = (skin["positions"] @ skin["bind_shape"][:3, :3].T + skin["bind_shape"][:3, 3]) * unit  # Y up
        for prim, mesh in zip(skin["primitives"], surfaces):
            assert mesh.name.startswith(skin["name"])
            assert mesh.num_triangles == prim["triangles"]
            corners = np.stack([prim["position"], prim["normal"]], axis=1)
            assert mesh.num_vertices == len(np.unique(corners, axis=0))  # one vertex per (position, normal)
            used = bind_shape[np.unique(prim["position"])]
            distance, _ = cKDTree(used).query(mesh.positions)
            assert distance.max() < 1e-5
            distance, _ = cKDTree(mesh.positions).query(used)
            assert distance.max() < 1e-5
            assert np.all(np.abs(np.linalg.norm(mesh.normals, axis=1) - 1.0) < 1e-5)
    # The corpus has no texture images: the surfaces are drawn in plain colour, and it says so.
    assert asset.warnings == [w for w in asset.warnings if w.startswith("texture images not found")]
    assert len(asset.warnings) == 1 and all(m.colors is None for m in asset.meshes)


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda rel: Path(rel).name)
def test_weights_are_the_four_strongest_summing_to_one(rel, characters):
    asset, skins, _ = characters[rel]
    for mesh in asset.meshes:
        assert mesh.weights.shape[1] <= 4 and np.all(mesh.weights >= 0)
        assert np.allclose(mesh.weights.sum(axis=1), 1.0, atol=1e-6)
        assert np.all(mesh.bind_joints < asset.skeleton.num_joints)
    # Elder's one skin gives some positions more than 4 influences: they were cut to 4.
    assert max(len(i) for skin in skins for i in skin["influences"]) == 4


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda rel: Path(rel).name)
def test_skinning_reproduces_the_files_skinning_at_rest_and_in_a_random_pose(rel, characters):
    asset, skins, unit = characters[rel]
    sk = asset.skeleton
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(sk.num_joints, 3))
    local = quat.multiply(sk.rest_rotations, quat.from_axis_angle(axes / np.linalg.norm(axes, axis=1, keepdims=True),
                                                                  rng.uniform(-0.5, 0.5, sk.num_joints)))
    posed = forward_kinematics(sk, local[None], np.array([[0.1, -0.05, 0.2]]))
    rest = (sk.rest_global_rotations[None], sk.rest_global_positions[None])
    for skin, surfaces in zip(skins, _surfaces_by_instance(asset, skins)):
        joints = np.array([sk.index[n] for n in skin["names"]])  # SmartBody joint names are their sids
        for pose in (rest, posed):
            # COLLADA: sum of w · W_j · IBM_j · BSM · v, with W_j = G_j scaled to file units (no scaled nodes here).
            g = rigid_matrices(pose[0][0, joints], pose[1][0, joints]) @ np.diag([unit, unit, unit, 1.0])
            per_bone = g @ skin["inverse_bind"] @ skin["bind_shape"]
            homogeneous = np.concatenate([skin["positions"], np.ones((len(skin["positions"]), 1))], axis=1)
            expected = np.array([sum(w * (per_bone[j] @ v)[:3] for j, w in infl)
                                 for infl, v in zip(skin["influences"], homogeneous)])
            at_rest = (skin["positions"] @ skin["bind_shape"][:3, :3].T + skin["bind_shape"][:3, 3]) * unit
            tree = cKDTree(at_rest)
            for mesh in surfaces:
                got = mesh.skin(*pose)[0][0]
                if pose is rest:
                    assert np.abs(got - mesh.positions).max() < 1e-4  # the bind pose is the rest pose
                candidates = tree.query_ball_point(mesh.positions, 1e-5)
                error = [min(np.abs(expected[c] - p).max() for c in cs) for cs, p in zip(candidates, got)]
                assert max(error) < 1e-4, mesh.name


@pytest.mark.parametrize("rel", CHARACTERS, ids=lambda rel: Path(rel).name)
def test_the_body_stands_on_the_skeleton(rel, characters):
    asset, _, _ = characters[rel]
    sk = asset.skeleton
    points = np.concatenate([m.positions for m in asset.meshes])
    joints = sk.rest_global_positions
    assert abs(np.ptp(points[:, 1]) - sk.height()) < 0.05
    assert 0.0 <= joints[:, 1].min() - points[:, 1].min() < 0.05  # soles just under the lowest joint
    assert 0.0 <= points[:, 1].max() - joints[:, 1].max() < 0.15  # the skull over the top joint
    assert abs(np.ptp(points[:, 0]) - np.ptp(joints[:, 0])) < 0.05  # arm span: finger tips
    for mesh in asset.meshes:  # the file's normals agree with the winding: triangles are counter-clockwise
        p = mesh.positions[mesh.triangles]
        face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        agree = np.einsum("ij,ij->i", face, mesh.normals[mesh.triangles].sum(axis=1)) > 0
        assert agree.mean() > 0.98, mesh.name


def test_meshes_are_decoded_on_first_use():
    asset = infuse.load(corpus_file(CHARACTERS[0]))
    assert asset.mesh_loader is not None and "meshes" not in vars(asset)
    assert len(asset.meshes) == 13 and "meshes" in vars(asset)


def test_utah_names_geometry_the_file_does_not_hold():
    path = corpus_file(UTAH)
    asset = infuse.load(path)
    assert asset.meshes == ()
    instances = len(_plain(path)[0].findall(".//instance_controller"))
    assert instances == 18
    assert asset.warnings == [f"line 2527 <instance_controller> and {instances - 1} more: not drawn: "
                                      "the geometry its skin names is not in the file"]


# -- synthetic scenes ------------------------------------------------------------------------------------

def _matrix(m: np.ndarray) -> str:
    return " ".join(f"{v:.9g}" for v in np.asarray(m).reshape(-1))


def _translate(x, y, z) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


SCALE = np.diag([2.0, 2.0, 2.0, 1.0])
HIPS_WORLD = SCALE @ _translate(0, 0, 50)
SPINE_WORLD = HIPS_WORLD @ _translate(0, 0, 20)
BIND_SHAPE = _translate(0, 0, 10)
# Mesh-space positions; the bind shape puts them 10 cm higher (Z up, cm).
BODY = np.array([[-10, 0, 90], [10, 0, 90], [10, 0, 110], [-10, 0, 110], [0, 0, 130], [-10, 0, 125], [10, 0, 125.0]])
BUMP = BODY + np.array([[0, 0, 0]] * 4 + [[0, 0, 5]] + [[0, 0, 0]] * 2)
# (joint, weight index) per position: 0 hips, 1 spine, -1 the bind shape; weights below.
WEIGHTS = [1.0, 0.5, 0.1, 0.2, 0.4, 0.25, 0.05]
INFLUENCES = [[(0, 0)], [(0, 1), (1, 1)], [(0, 2), (1, 3), (0, 4), (1, 5), (0, 6)], [(1, 1), (-1, 1)],
              [(1, 0)], [(1, 0)], [(1, 0)]]
BOX = np.array([[0, 0, 0], [4, 0, 0], [0, 0, 4.0]])


def _float_source(ident: str, values: np.ndarray, stride: int) -> str:
    values = np.asarray(values, dtype=float).reshape(-1)
    return (f'<source id="{ident}"><float_array id="{ident}-a" count="{values.size}">{_matrix(values)}</float_array>'
            f'<technique_common><accessor source="#{ident}-a" count="{values.size // stride}" stride="{stride}"/>'
            f'</technique_common></source>')


def scene(*, body_positions: str | None = None, body_p: str = "0 1 2 3 3 2 4", skin_source: str = "#body-mesh",
          vcount: str | None = None, loose: bool = True, prop: bool = True, morph: bool = False) -> str:
    positions = body_positions or _matrix(BODY)
    uv0 = [[0.75, 0.75]] * 7
    uv1 = [[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75], [0.25, 0.25], [0.75, 0.25], [0.75, 0.75]]
    counts = vcount or " ".join(str(len(i)) for i in INFLUENCES)
    v = " ".join(f"{j} {w}" for infl in INFLUENCES for j, w in infl)
    morph_controller = ""
    if morph:
        morph_controller = (
            '<controller id="bumps"><morph source="#body-mesh" method="NORMALIZED">'
            '<source id="bumps-t"><IDREF_array id="bumps-t-a" count="1">bump-geo</IDREF_array>'
            '<technique_common><accessor source="#bumps-t-a" count="1" stride="1"/></technique_common></source>'
            '<targets><input semantic="MORPH_TARGET" source="#bumps-t"/></targets></morph></controller>')
        skin_source = "#bumps"
    nodes = ('<node id="prop" name="Prop"><translate>5 0 0</translate><instance_geometry url="#box-mesh"/></node>'
             if prop else "")
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_images><image id="checker"><init_from>file:///C:/art/textures/checker.png</init_from></image></library_images>
  <library_materials><material id="red"><instance_effect url="#red-fx"/></material>
    <material id="tex"><instance_effect url="#tex-fx"/></material></library_materials>
  <library_effects>
    <effect id="red-fx"><profile_COMMON><technique sid="common"><lambert>
      <diffuse><color>0.6 0.1 0.05 1</color></diffuse></lambert></technique></profile_COMMON></effect>
    <effect id="tex-fx"><profile_COMMON>
      <newparam sid="checker-surface"><surface type="2D"><init_from>checker</init_from></surface></newparam>
      <newparam sid="checker-sampler"><sampler2D><source>checker-surface</source></sampler2D></newparam>
      <technique sid="common"><phong><diffuse><texture texture="checker-sampler" texcoord="UV0"/></diffuse></phong></technique>
    </profile_COMMON></effect>
  </library_effects>
  <library_geometries>
    <geometry id="body-mesh" name="body"><mesh>
      <source id="body-pos"><float_array id="body-pos-a" count="21">{positions}</float_array>
        <technique_common><accessor source="#body-pos-a" count="7" stride="3"/></technique_common></source>
      {_float_source("body-uv0", uv0, 2)}{_float_source("body-uv1", uv1, 2)}
      <vertices id="body-vtx"><input semantic="POSITION" source="#body-pos"/></vertices>
      <polylist material="m1" count="2"><input semantic="VERTEX" source="#body-vtx" offset="0"/>
        <vcount>4 3</vcount><p>{body_p}</p></polylist>
      <polygons material="m2" count="1"><input semantic="VERTEX" source="#body-vtx" offset="0"/>
        <input semantic="TEXCOORD" source="#body-uv0" offset="1" set="0"/>
        <input semantic="TEXCOORD" source="#body-uv1" offset="2" set="1"/>
        <ph><p>3 3 3 2 2 2 6 6 6 4 4 4 5 5 5</p><h>4 4 4 5 5 5 6 6 6</h></ph></polygons>
    </mesh></geometry>
    <geometry id="bump-geo" name="bump"><mesh>{_float_source("bump-pos", BUMP, 3)}
      <vertices id="bump-vtx"><input semantic="POSITION" source="#bump-pos"/></vertices></mesh></geometry>
    <geometry id="box-mesh" name="box"><mesh>{_float_source("box-pos", BOX, 3)}
      <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_controllers>{morph_controller}
    <controller id="skin"><skin source="{skin_source}">
      <bind_shape_matrix>{_matrix(BIND_SHAPE)}</bind_shape_matrix>
      <source id="skin-joints"><IDREF_array id="skin-joints-a" count="2">hips spine</IDREF_array>
        <technique_common><accessor source="#skin-joints-a" count="2" stride="1"/></technique_common></source>
      {_float_source("skin-ibm", np.linalg.inv([HIPS_WORLD, SPINE_WORLD]), 16)}
      {_float_source("skin-w", WEIGHTS, 1)}
      <joints><input semantic="JOINT" source="#skin-joints"/><input semantic="INV_BIND_MATRIX" source="#skin-ibm"/></joints>
      <vertex_weights count="7"><input semantic="JOINT" source="#skin-joints" offset="0"/>
        <input semantic="WEIGHT" source="#skin-w" offset="1"/><vcount>{counts}</vcount><v>{v}</v></vertex_weights>
    </skin></controller>
  </library_controllers>
  <library_visual_scenes><visual_scene id="scene">
    <node id="arm" name="Armature"><scale>2 2 2</scale>
      <node id="hips" name="Hips" sid="hips" type="JOINT"><translate>0 0 50</translate>
        <node id="spine" name="Spine" sid="spine" type="JOINT"><translate>0 0 20</translate>{nodes}</node>
      </node>
    </node>
    <node id="body" name="Body"><translate>300 0 0</translate>
      <instance_controller url="#skin"><skeleton>#hips</skeleton><bind_material><technique_common>
        <instance_material symbol="m1" target="#red"/>
        <instance_material symbol="m2" target="#tex"><bind_vertex_input semantic="UV0" input_semantic="TEXCOORD" input_set="1"/></instance_material>
      </technique_common></bind_material></instance_controller></node>
    {'<node id="loose" name="Loose"><instance_geometry url="#box-mesh"/></node>' if loose else ''}
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def _core(points) -> np.ndarray:
    """File points (Z up, cm) in the core frame (Y up, m)."""
    p = np.asarray(points, dtype=float)
    return 0.01 * np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)


def _checker(folder: Path) -> np.ndarray:
    """A 2x2 image beside the scene; returns its pixels (rows top to bottom) as sRGB bytes."""
    from PIL import Image

    pixels = np.array([[[255, 0, 0, 255], [0, 255, 0, 255]], [[0, 0, 255, 255], [255, 255, 255, 255]]], dtype=np.uint8)
    Image.fromarray(pixels, "RGBA").save(folder / "checker.png")
    return pixels


def _vertex(mesh, core_point) -> int:
    distance = np.linalg.norm(mesh.positions - core_point, axis=1)
    assert distance.min() < 1e-6
    return int(np.argmin(distance))


def test_synthetic_skin_polygons_weights_and_colours(tmp_path):
    pixels = _checker(tmp_path)
    asset = infuse.load(write_case(tmp_path, "body", scene(), ".dae"))
    sk = asset.skeleton
    box, quad, pentagon = asset.meshes  # scene order: the prop sits in the skeleton, before the body
    [warning] = asset.warnings
    assert re.fullmatch(r"line \d+ <instance_geometry> in node 'Loose': not drawn: it has no skin and no joint above it", warning)
    assert (quad.name, quad.num_triangles, quad.num_vertices) == ("body.m1", 3, 5)
    assert (pentagon.name, pentagon.num_triangles, pentagon.num_vertices) == ("body.m2", 3, 5)  # the hole stays open
    bind = _core(BODY + BIND_SHAPE[:3, 3])
    # The bind shape lies where the skeleton is: position 4 is at the spine joint, whatever the units and axes.
    assert np.allclose(bind[4], sk.rest_global_positions[sk.index["Spine"]], atol=1e-9)
    assert np.allclose(np.sort(quad.positions, axis=0), np.sort(bind[:5], axis=0), atol=1e-6)
    # Flat, no normals in the file: smooth normals face +Z (the front), the way the polygons turn.
    assert np.allclose(quad.normals, [0, 0, 1], atol=1e-6) and np.allclose(pentagon.normals, [0, 0, 1], atol=1e-6)
    p = quad.positions[quad.triangles]
    assert np.all(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2] > 0)
    hips, spine = sk.index["Hips"], sk.index["Spine"]

    def weight(mesh, k):
        """Skeleton joint -> summed weight of the vertex at bind-shape position ``k``."""
        out: dict[int, float] = {}
        v = _vertex(mesh, bind[k])
        for j, w in zip(mesh.joints[v], mesh.weights[v]):
            if w > 0:
                out[int(mesh.bind_joints[j])] = out.get(int(mesh.bind_joints[j]), 0.0) + float(w)
        return out

    assert weight(quad, 0) == {hips: 1.0}
    assert weight(quad, 1) == pytest.approx({hips: 0.5, spine: 0.5})
    assert weight(quad, 2) == pytest.approx({hips: 0.5 / 0.95, spine: 0.45 / 0.95})  # 4 of 5 influences
    assert weight(quad, 3) == {spine: 1.0}  # the bind-shape influence is dropped
    assert np.allclose(quad.base_color, [0.6, 0.1, 0.05, 1.0]) and quad.colors is None
    # The texture reads set 1 (bound by the material), origin bottom left, sRGB to linear.
    linear = lambda byte: (byte / 255.0 / 12.92) if byte / 255.0 <= 0.04045 else ((byte / 255.0 + 0.055) / 1.055) ** 2.4  # noqa: E731
    for k, (row, col) in {2: (0, 1), 3: (0, 0), 6: (0, 1), 5: (1, 1), 4: (1, 0)}.items():
        expected = [linear(c) for c in pixels[row, col, :3]]
        assert np.allclose(pentagon.colors[_vertex(pentagon, bind[k]), :3], expected, atol=1e-6), k
    # The prop follows the spine rigidly, where its node puts it (Armature scale 2, 5 cm aside).
    assert np.allclose(box.positions, _core((SPINE_WORLD @ _translate(5, 0, 0) @ np.c_[BOX, np.ones(3)].T).T[:, :3]))
    assert list(box.bind_joints) == [spine] and np.all(box.weights == 1.0)

    # A pose: the file's skinning, sum of w · C · W_j · IBM_j · BSM · v, with C · W_j = G_j · 0.02 (cm, scale 2).
    axes = quat.normalize(np.array([[0.3, 0.9, 0.1, 0.0], [0.8, -0.2, 0.5, 0.0]]))[:, :3]
    local = quat.multiply(sk.rest_rotations, quat.from_axis_angle(axes, np.array([0.7, -1.1])))
    rot, pos = forward_kinematics(sk, local[None], np.array([[0.2, 0.0, -0.1]]))
    g = rigid_matrices(rot[0], pos[0]) @ np.diag([0.02, 0.02, 0.02, 1.0])
    skins = g[[hips, spine]] @ np.linalg.inv([HIPS_WORLD, SPINE_WORLD]) @ BIND_SHAPE
    posed = quad.skin(rot, pos)[0][0]
    for k in range(5):
        w = weight(quad, k)
        file_point = np.append(BODY[k], 1.0)
        expected = sum(wj * (skins[0 if j == hips else 1] @ file_point)[:3] for j, wj in w.items())
        assert np.allclose(posed[_vertex(quad, bind[k])], expected, atol=1e-5), k
    rigid = rigid_matrices(rot[0, spine], pos[0, spine]) @ np.linalg.inv(rigid_matrices(sk.rest_global_rotations[spine], sk.rest_global_positions[spine]))
    assert np.allclose(box.skin(rot, pos)[0][0], box.positions @ rigid[:3, :3].T + rigid[:3, 3], atol=1e-5)


def test_missing_texture_gives_the_plain_colour_and_a_warning(tmp_path):
    asset = infuse.load(write_case(tmp_path, "body", scene(loose=False), ".dae"))  # no checker.png beside it
    pentagon = next(m for m in asset.meshes if m.name == "body.m2")
    assert pentagon.colors is None and np.allclose(pentagon.base_color, [0.8, 0.8, 0.8, 1.0])
    assert asset.warnings == ["texture images not found beside the file, plain colours used: checker.png"]


def test_a_skinned_morph_keeps_its_targets(tmp_path):
    asset = infuse.load(write_case(tmp_path, "body", scene(morph=True, loose=False, prop=False), ".dae"))
    assert asset.morph_targets == ["bump"]
    quad = asset.meshes[0]
    assert quad.morph_names == ("bump",)
    bind = _core(BODY + BIND_SHAPE[:3, 3])
    offsets = quad.morph_positions[0]
    top = _vertex(quad, bind[4])
    assert np.allclose(offsets[top], [0, 0.05, 0], atol=1e-7)  # 5 cm up the file's Z, up the core's Y
    assert np.abs(np.delete(offsets, top, axis=0)).max() == 0
    rest = asset.skeleton.rest_global_rotations[None], asset.skeleton.rest_global_positions[None]
    assert np.allclose(quad.skin(*rest, morph_weights=np.array([[1.0]]))[0][0, top], bind[4] + [0, 0.05, 0], atol=1e-6)


@pytest.mark.parametrize("case, problem", [
    (dict(body_positions=_matrix(BODY)[:-3] + " 1.0x"), "not a number: '1.0x'"),
    (dict(body_p="0 1 2 3 3 2 7"), "a vertex index is out of range (there are 7 positions)"),
    (dict(vcount="1 2 5 2 1 1"), "count=7 but <vcount> lists 6 vertices"),
    (dict(skin_source="#nowhere"), "the geometry its skin names is not in the file"),
    (dict(body_positions=_matrix(BODY)[:-3] + " 1e308"), "mesh 'body.m2': positions holds NaN or infinity"),
], ids=["float", "index", "vcount", "source", "overflow"])
def test_unusable_geometry_is_left_out_with_a_warning(tmp_path, case, problem):
    asset = infuse.load(write_case(tmp_path, "body", scene(loose=False, **case), ".dae"))
    assert [m.name for m in asset.meshes] == ["box"]  # the rigid prop is still drawn
    warning, *textures = asset.warnings
    assert all(t.startswith("texture images not found") for t in textures)
    assert re.fullmatch(r"line \d+ <\w+.*>: not drawn: .*", warning) and warning.endswith(problem), warning


def test_malformed_geometry_with_nothing_left_to_draw_is_bad_input(tmp_path, capsys):
    path = write_case(tmp_path, "body", scene(loose=False, prop=False, body_positions=_matrix(BODY)[:-3] + " nan"), ".dae")
    asset = infuse.load(path)  # the skeleton reads: geometry is decoded on first use
    assert asset.skeleton.num_joints == 2
    with pytest.raises(InputError) as info:
        asset.meshes
    assert info.value.file == str(path) and info.value.problem == "value is not finite (NaN or infinity)"
    code = main(["render", str(path), "-o", str(tmp_path / "x.png"), "--style", "mesh"])
    out = capsys.readouterr()
    line = assert_one_error_line(path, code, out.out, out.err)
    assert "<float_array 'body-pos-a'>" in line and not (tmp_path / "x.png").exists()


def test_a_character_written_to_glb_keeps_its_body(characters, tmp_path):
    asset = characters["smartbody/mesh/elder/Elder.dae"][0]
    back = infuse.load(infuse.save(asset, tmp_path / "elder.glb"))
    assert sum(m.num_triangles for m in back.meshes) == sum(m.num_triangles for m in asset.meshes)
    mine = np.concatenate([m.positions for m in asset.meshes])
    theirs = np.concatenate([m.skin(back.skeleton.rest_global_rotations[None], back.skeleton.rest_global_positions[None])[0][0]
                             for m in back.meshes])
    assert cKDTree(mine).query(theirs)[0].max() < 1e-4
