"""COLLADA reader: the corpus characters, a hand-checked synthetic scene, and malformed input through the CLI."""
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from infuse.kinematics import motion_fk

from cli_errors import assert_cli_exits_2, assert_info_exits_2, write_case
from corpus_data import corpus_file, labels

COLLADA_LABELS = [lab for lab in labels() if lab["file"].lower().endswith(".dae")]


@pytest.fixture(scope="module")
def corpus_assets():
    return {lab["file"]: infuse.load(corpus_file(lab["file"])) for lab in COLLADA_LABELS}


def test_corpus_has_collada_labels():
    assert len(COLLADA_LABELS) >= 4 or not labels()


@pytest.mark.parametrize("label", COLLADA_LABELS, ids=lambda lab: Path(lab["file"]).name)
def test_corpus_file_loads_with_labelled_joints_and_a_standing_rest(label, corpus_assets):
    asset = corpus_assets[label["file"]]
    summary = asset_summary(asset)
    wanted = {v for v in label["mapping"].values() if v}
    assert wanted <= set(summary["joints"]), sorted(wanted - set(summary["joints"]))
    assert summary["units"] == "cm" and summary["units_detected_by"] == "file" and summary["up_axis"] == "Y"
    sk = asset.skeleton
    pos = sk.rest_global_positions
    m = label["mapping"]
    head = pos[sk.index[m["skullbase"]], 1]
    feet = pos[[sk.index[m["l_ankle"]], sk.index[m["r_ankle"]]], 1]
    assert 1.2 <= sk.height() <= 2.2
    assert head - feet.max() > 1.0
    # +X is the character's left: the left wrist sits on +X.
    assert pos[sk.index[m["l_wrist"]], 0] > 0.3 > -0.3 > pos[sk.index[m["r_wrist"]], 0]
    for motion in asset.motions.values():
        _, p = motion_fk(motion)
        assert np.all(np.isfinite(p)) and motion.num_frames > 1
        assert np.abs(p - pos).max() < 0.2  # the corpus clips move face joints, not the body


# -- a synthetic scene with every feature, checked against an independent matrix chain --------------

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="body-mesh" name="body"/><geometry id="smile-geo" name="smile"/><geometry id="blink-geo" name="blink"/>
  </library_geometries>
  <library_controllers>
    <controller id="skin"><skin source="#body-mesh">
      <source id="skin-joints"><Name_array id="skin-joints-array" count="4">hips spine head thigh_l</Name_array>
        <technique_common><accessor source="#skin-joints-array" count="4" stride="1"/></technique_common></source>
      <joints><input semantic="JOINT" source="#skin-joints"/></joints>
    </skin></controller>
    <controller id="faces"><morph source="#body-mesh" method="RELATIVE">
      <source id="faces-targets"><IDREF_array id="faces-targets-array" count="2">smile-geo blink-geo</IDREF_array>
        <technique_common><accessor source="#faces-targets-array" count="2" stride="1"/></technique_common></source>
      <targets><input semantic="MORPH_TARGET" source="#faces-targets"/></targets>
    </morph></controller>
  </library_controllers>
  <library_animations>
    <animation id="turn">
      <source id="turn-in"><float_array id="turn-in-a" count="2">0 1</float_array>
        <technique_common><accessor source="#turn-in-a" count="2" stride="1"/></technique_common></source>
      <source id="turn-out"><float_array id="turn-out-a" count="2">0 90</float_array>
        <technique_common><accessor source="#turn-out-a" count="2" stride="1"/></technique_common></source>
      <sampler id="turn-s"><input semantic="INPUT" source="#turn-in"/><input semantic="OUTPUT" source="#turn-out"/></sampler>
      <channel source="#turn-s" target="hips-node/rotateZ.ANGLE"/>
    </animation>
    <animation id="grow">
      <source id="grow-in"><float_array id="grow-in-a" count="2">0 1</float_array>
        <technique_common><accessor source="#grow-in-a" count="2" stride="1"/></technique_common></source>
      <source id="grow-out"><float_array id="grow-out-a" count="6">0 0 20 0 0 40</float_array>
        <technique_common><accessor source="#grow-out-a" count="2" stride="3"/></technique_common></source>
      <sampler id="grow-s"><input semantic="INPUT" source="#grow-in"/><input semantic="OUTPUT" source="#grow-out"/></sampler>
      <channel source="#grow-s" target="spine-node/translate"/>
    </animation>
  </library_animations>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="armature" name="Armature" type="NODE"><scale sid="scale">2 2 2</scale>
        <node id="hips-node" name="Hips" sid="hips" type="JOINT">
          <translate sid="translate">0 0 50</translate><rotate sid="rotateZ">0 0 1 0</rotate>
          <node id="spine-node" name="Spine" sid="spine" type="JOINT"><translate sid="translate">0 0 20</translate>
            <node id="head-node" name="Head" sid="head" type="JOINT">
              <matrix sid="transform">1 0 0 0 0 1 0 0 0 0 1 30 0 0 0 1</matrix>
            </node>
          </node>
          <node id="helper" name="Helper"><translate>10 0 0</translate>
            <node id="thigh-node" name="LeftThigh" sid="thigh_l"><translate>0 0 -25</translate></node>
          </node>
        </node>
      </node>
      <node id="body" name="Body"><instance_controller url="#skin"><skeleton>#hips-node</skeleton></instance_controller></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def _expected_positions(t):
    """Global joint positions (core frame) at time t, by an explicit matrix chain."""
    def T(x, y, z):
        m = np.eye(4)
        m[:3, 3] = (x, y, z)
        return m

    a = np.radians(90.0 * t)
    rz = np.eye(4)
    rz[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    z_up_to_y_up = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1.0]])
    root = np.diag([0.01, 0.01, 0.01, 1.0]) @ z_up_to_y_up @ np.diag([2.0, 2.0, 2.0, 1.0])
    hips = root @ T(0, 0, 50) @ rz
    spine = hips @ T(0, 0, 20 + 20 * t)
    head = spine @ T(0, 0, 30)
    thigh = hips @ T(10, 0, 0) @ T(0, 0, -25)
    return np.array([m[:3, 3] for m in (hips, spine, head, thigh)])


def test_synthetic_scene_matches_an_independent_matrix_chain(tmp_path):
    asset = infuse.load(write_case(tmp_path, "scene", SCENE, ".dae"))
    sk = asset.skeleton
    assert sk.names == ("Hips", "Spine", "Head", "LeftThigh")  # the skin makes the untyped thigh a joint
    assert list(sk.parents) == [-1, 0, 1, 0]  # Helper is folded into LeftThigh
    assert asset.morph_targets == ["smile", "blink"]
    assert (asset.source_units, asset.source_up_axis, asset.units_detected_by) == ("cm", "Z", "file")
    assert set(asset.meta["folded_nodes"]) == {"Armature", "Helper"}
    assert np.allclose(sk.rest_global_positions, _expected_positions(0.0), atol=1e-9)
    motion = asset.motions["scene"]
    assert motion.fps == 30.0 and motion.num_frames == 31
    _, pos = motion_fk(motion)
    expected = np.stack([_expected_positions(k / 30.0) for k in range(31)])
    assert np.allclose(pos, expected, atol=1e-9)


def test_overrides_replace_file_units_and_up_axis(tmp_path):
    path = write_case(tmp_path, "scene", SCENE, ".dae")
    base = infuse.load(path)
    asset = infuse.load(path, units="m", up_axis="Y")
    assert (asset.source_units, asset.source_up_axis, asset.units_detected_by) == ("m", "Y", "override")
    assert np.isclose(asset.skeleton.height(), base.skeleton.height() * 100)
    # Read as Y-up, the file's +Z (the body's up) stays +Z.
    assert np.ptp(asset.skeleton.rest_global_positions[:, 2]) > np.ptp(asset.skeleton.rest_global_positions[:, 1])


def test_bezier_and_step_keys_are_sampled_as_curves(tmp_path):
    curve = """<animation id="bend">
      <source id="b-in"><float_array id="b-in-a" count="3">0 1 2</float_array>
        <technique_common><accessor source="#b-in-a" count="3" stride="1"/></technique_common></source>
      <source id="b-out"><float_array id="b-out-a" count="3">0 90 0</float_array>
        <technique_common><accessor source="#b-out-a" count="3" stride="1"/></technique_common></source>
      <source id="b-int"><Name_array id="b-int-a" count="3">BEZIER STEP LINEAR</Name_array>
        <technique_common><accessor source="#b-int-a" count="3" stride="1"/></technique_common></source>
      <source id="b-ti"><float_array id="b-ti-a" count="6">0 0 0.6667 90 2 0</float_array>
        <technique_common><accessor source="#b-ti-a" count="3" stride="2"/></technique_common></source>
      <source id="b-to"><float_array id="b-to-a" count="6">0.3333 0 1 90 2 0</float_array>
        <technique_common><accessor source="#b-to-a" count="3" stride="2"/></technique_common></source>
      <sampler id="b-s"><input semantic="INPUT" source="#b-in"/><input semantic="OUTPUT" source="#b-out"/>
        <input semantic="INTERPOLATION" source="#b-int"/><input semantic="IN_TANGENT" source="#b-ti"/>
        <input semantic="OUT_TANGENT" source="#b-to"/></sampler>
      <channel source="#b-s" target="hips-node/rotateZ.ANGLE"/>
    </animation>"""
    text = SCENE.replace('<library_animations>', '<library_animations>' + curve, 1)
    text = text.replace('target="hips-node/rotateZ.ANGLE"/>\n    </animation>\n    <animation id="grow">',
                        'target="helper/nothing"/>\n    </animation>\n    <animation id="grow">')
    motion = infuse.load(write_case(tmp_path, "scene", text, ".dae")).motions["scene"]
    angles = np.degrees(2 * np.arctan2(motion.local_rotations[:, 0, 1], motion.local_rotations[:, 0, 3]))
    # Tangents at thirds of the segment with the key values: an ease-in/ease-out 0 -> 90 over 1 s.
    s = np.linspace(0, 1, 31)
    ease = 90 * (3 * s**2 - 2 * s**3)
    assert np.allclose(angles[:31], ease, atol=0.05)
    assert np.allclose(angles[31:60], 90.0)  # STEP holds the key value for the whole segment
    assert abs(angles[60]) < 1e-6


# -- malformed input through the CLI ----------------------------------------------------------------

def _malformed_cases():
    yield "truncated", SCENE[: len(SCENE) // 2]
    yield "garbage", "\x00\xff garbage <<< not xml"
    yield "empty", ""
    yield "not-collada", "<?xml version='1.0'?><scene/>"
    yield "nan-translate", SCENE.replace("<translate sid=\"translate\">0 0 50</translate>", "<translate sid=\"translate\">0 nan 50</translate>")
    yield "overflow", SCENE.replace("<translate sid=\"translate\">0 0 50</translate>", "<translate sid=\"translate\">0 1e300 50</translate>").replace("2 2 2", "1e300 1e300 1e300")
    yield "text-in-matrix", SCENE.replace("1 0 0 0 0 1 0 0 0 0 1 30 0 0 0 1", "1 0 0 0 0 1 0 x 0 0 1 30 0 0 0 1")
    yield "short-matrix", SCENE.replace("1 0 0 0 0 1 0 0 0 0 1 30 0 0 0 1", "1 0 0 0 0 1 0 0 0 0 1 30 0 0 0")
    yield "no-scene", SCENE.split("<library_visual_scenes>")[0] + "</COLLADA>"
    yield "scene-url-unknown", SCENE.replace('url="#scene"', 'url="#elsewhere"')
    yield "cycle", SCENE.replace('<translate sid="translate">0 0 20</translate>',
                                 '<translate sid="translate">0 0 20</translate><instance_node url="#hips-node"/>')
    yield "unknown-skin-joint", SCENE.replace("hips spine head thigh_l", "hips spine head knee_r")
    yield "key-count", SCENE.replace('<float_array id="grow-out-a" count="6">0 0 20 0 0 40</float_array>',
                                     '<float_array id="grow-out-a" count="3">0 0 20</float_array>')
    yield "decreasing-keys", SCENE.replace('<float_array id="turn-in-a" count="2">0 1</float_array>',
                                           '<float_array id="turn-in-a" count="2">1 0</float_array>')
    yield "bad-unit", SCENE.replace('meter="0.01"', 'meter="abc"')
    yield "bad-up-axis", SCENE.replace("Z_UP", "W_UP")
    yield "entity-bomb", ('<?xml version="1.0"?><!DOCTYPE c [<!ENTITY a "aaaaaaaaaa">'
                          '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;"><!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]>'
                          '<COLLADA><asset>&c;</asset></COLLADA>')


MALFORMED = dict(_malformed_cases())


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_input_exits_2_with_one_line(tmp_path, capsys, name):
    assert_info_exits_2(write_case(tmp_path, name, MALFORMED[name], ".dae"), capsys)


def test_malformed_input_through_the_installed_command(tmp_path):
    paths = [write_case(tmp_path, name, MALFORMED[name], ".dae") for name in ("truncated", "nan-translate", "cycle", "no-scene")]
    label = COLLADA_LABELS[0] if COLLADA_LABELS else None
    if label:
        data = corpus_file(label["file"]).read_bytes()
        paths.append(write_case(tmp_path, "cut", data[: len(data) // 3], ".dae"))
    assert_cli_exits_2(paths)
