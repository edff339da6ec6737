"""Each failure class the fuzzer found, as a minimal reproducer built here: bounds checked before
allocating (typed errors naming the limit), references confined to the file's folder, iterative walks,
non-finite and huge numbers refused at read time, BML bounded in size and time, and the cases a new
user met (a file named ``.bvh``, a text file named ``.glb``, facing a character added later)."""
from __future__ import annotations

import io
import json
import struct
import sys
import time
import warnings
import zlib
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse import limits, quaternions as quat
from infuse.bml import Scheduler, parse_bml
from infuse.cli import main
from infuse.errors import ExternalReferenceError, InputError, LimitError, UsageError
from infuse.scene import Scene
from infuse.scene.scenefile import read_scene_file
from infuse.texture import decode_image

from cli_errors import assert_info_exits_2
from fuzz_support import TINY_BML, TINY_BVH, TINY_SCENE_TOML
from gltf_builder import mini_rig
from runtime_characters import synthetic_character

BML_NS = 'xmlns="http://www.bml-initiative.org/bml/bml-1.0"'


def _bvh_chain(depth: int) -> str:
    """A BVH whose joints form one chain ``depth`` long, one frame."""
    lines = ["HIERARCHY", "ROOT j0", "{", "OFFSET 0 0 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    for k in range(1, depth):
        lines += [f"JOINT j{k}", "{", "OFFSET 0 1 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    lines += ["End Site", "{", "OFFSET 0 1 0", "}"] + ["}"] * depth
    lines += ["MOTION", "Frames: 1", "Frame Time: 0.0333333", " ".join(["0"] * 3 * depth)]
    return "\n".join(lines) + "\n"


def _gltf(tmp_path: Path, edit, name: str = "case.gltf") -> Path:
    """The mini rig as a .gltf with an external .bin, its JSON passed through ``edit``."""
    builder, _ = mini_rig()
    path = builder.write_gltf(tmp_path / name, external=True)
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    return path


def _limit(path: Path, limit: str) -> LimitError:
    with pytest.raises(LimitError) as info:
        infuse.load(path)
    assert info.value.limit == limit and info.value.file == str(path)
    assert f"infuse.limits.{limit}" in str(info.value)
    return info.value


# -- counts and sizes, checked before allocating ---------------------------------------------------------------

def test_bvh_declaring_two_to_the_31_frames_without_data_is_refused_at_once(tmp_path, capsys):
    for frames, channels in ((2 ** 31, "CHANNELS 3 Zrotation Xrotation Yrotation"), (10 ** 14, "CHANNELS 0")):
        text = f"HIERARCHY\nROOT a\n{{\nOFFSET 0 0 0\n{channels}\n}}\nMOTION\nFrames: {frames}\nFrame Time: 0.01\n"
        path = tmp_path / f"frames{frames}.bvh"
        path.write_text(text)
        started = time.process_time()
        _limit(path, "MAX_FRAMES")
        assert time.process_time() - started < 1.0
        assert "MAX_FRAMES" in assert_info_exits_2(path, capsys)


def test_gltf_accessor_sparse_and_meshopt_counts_of_two_to_the_31_are_refused(tmp_path):
    def zero_accessor(doc):  # an accessor without a bufferView is all zeros: nothing bounds it but its count
        doc["accessors"].append({"componentType": 5126, "count": 2 ** 31, "type": "VEC3"})
        doc["skins"][0]["inverseBindMatrices"] = len(doc["accessors"]) - 1
        doc["accessors"][-1]["type"] = "MAT4"

    _limit(_gltf(tmp_path, zero_accessor, "zeros.gltf"), "MAX_ELEMENTS")

    def sparse(doc):
        acc = doc["accessors"][doc["skins"][0]["inverseBindMatrices"]]
        acc["count"] = 2 ** 31
        acc["sparse"] = {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}
        del acc["bufferView"]

    _limit(_gltf(tmp_path, sparse, "sparse.gltf"), "MAX_ELEMENTS")

    def meshopt(doc):
        view = doc["bufferViews"][doc["accessors"][doc["skins"][0]["inverseBindMatrices"]]["bufferView"]]
        view["extensions"] = {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": 0, "byteLength": 64,
                                                          "byteStride": 64, "count": 2 ** 31, "mode": "ATTRIBUTES"}}
        doc["extensionsUsed"] = ["EXT_meshopt_compression"]

    path = _gltf(tmp_path, meshopt, "meshopt.gltf")
    started = time.process_time()
    error = pytest.raises(InputError, infuse.load, path).value
    assert "compressed bytes can hold" in error.problem and time.process_time() - started < 2.0


def test_a_chain_of_5000_nodes_is_refused_and_one_of_900_loads_in_linear_time(tmp_path):
    def chain(length):
        def edit(doc):
            nodes = doc["nodes"]
            start = len(nodes)
            nodes.extend({"name": f"tip{k}", "children": [start + k + 1]} for k in range(length - 1))
            nodes.append({"name": "last"})
            nodes[3].setdefault("children", []).append(start)  # below the head joint: an empty chain of bone tips
        return edit

    _limit(_gltf(tmp_path, chain(5000), "long.gltf"), "MAX_DEPTH")
    started = time.process_time()
    asset = infuse.load(_gltf(tmp_path, chain(900), "deep.gltf"))
    assert asset.skeleton.num_joints >= 900 and time.process_time() - started < 10.0


def test_deep_hierarchies_are_walked_without_recursion(tmp_path):
    depth = limits.MAX_DEPTH  # deeper than Python's recursion limit allows a recursive walk with its callers
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(600)
    try:
        path = tmp_path / "deep.bvh"
        path.write_text(_bvh_chain(depth + 1))
        asset = infuse.load(path)
        tree = asset.skeleton.describe_tree()
    finally:
        sys.setrecursionlimit(old)
    assert len(tree.splitlines()) == depth + 1 and tree.splitlines()[-1] == "  " * depth + f"j{depth}"
    path.write_text(_bvh_chain(depth + 2))
    _limit(path, "MAX_DEPTH")


def test_json_nested_past_the_limit_is_refused(tmp_path):
    def nest(doc):
        deep: list = []
        for _ in range(limits.MAX_NESTING + 5):
            deep = [deep]
        doc["extras"] = {"deep": deep}

    _limit(_gltf(tmp_path, nest), "MAX_NESTING")


def test_image_bomb_is_refused_before_decoding():
    from PIL import Image

    buffer = io.BytesIO()
    Image.new("RGB", (1, 1)).save(buffer, "PNG")
    png = bytearray(buffer.getvalue())
    ihdr = png.index(b"IHDR")
    png[ihdr + 4:ihdr + 12] = struct.pack(">II", 100_000, 100_000)  # ten gigapixels declared
    png[ihdr + 17:ihdr + 21] = struct.pack(">I", zlib.crc32(bytes(png[ihdr:ihdr + 17])))
    started = time.process_time()
    with pytest.raises(ValueError):
        decode_image(bytes(png))
    assert time.process_time() - started < 1.0


# -- references ---------------------------------------------------------------------------------------------------

def test_buffer_uris_resolve_only_to_regular_files_in_the_folder(tmp_path, monkeypatch):
    monkeypatch.delenv("INFUSE_ALLOW_EXTERNAL", raising=False)
    folder = tmp_path / "model"
    folder.mkdir()
    outside = tmp_path / "secret.bin"
    builder, _ = mini_rig()
    outside.write_bytes(bytes(builder.bin))
    (folder / "link.bin").symlink_to(outside)
    cases = {"device": "/dev/zero", "absolute": str(outside), "escape": "../secret.bin", "link": "link.bin",
             "encoded": "%2e%2e/secret.bin"}
    for label, uri in cases.items():
        path = _gltf(folder, lambda doc, uri=uri: doc["buffers"][0].update(uri=uri), f"{label}.gltf")
        with pytest.raises(ExternalReferenceError) as info:
            infuse.load(path)
        assert info.value.file == str(path) and info.value.place == "buffers[0]", label
    # allowed by the user: files outside are read, a device never
    assert infuse.load(folder / "escape.gltf", allow_external=True).skeleton.num_joints > 0
    monkeypatch.setenv("INFUSE_ALLOW_EXTERNAL", "1")
    assert infuse.load(folder / "link.gltf").skeleton.num_joints > 0
    with pytest.raises(ExternalReferenceError, match="not a regular file"):
        infuse.load(folder / "device.gltf")
    # and a file inside the folder, through a sub-folder, is fine without it
    monkeypatch.delenv("INFUSE_ALLOW_EXTERNAL")
    (folder / "sub").mkdir()
    (folder / "sub" / "data.bin").write_bytes(bytes(builder.bin))
    inside = _gltf(folder, lambda doc: doc["buffers"][0].update(uri="sub/../sub/data.bin"), "inside.gltf")
    assert infuse.load(inside).skeleton.num_joints > 0


def test_cli_refuses_an_escaping_reference_unless_allowed(tmp_path, capsys):
    folder = tmp_path / "model"
    folder.mkdir()
    builder, _ = mini_rig()
    (tmp_path / "secret.bin").write_bytes(bytes(builder.bin))
    path = _gltf(folder, lambda doc: doc["buffers"][0].update(uri="../secret.bin"))
    assert "INFUSE_ALLOW_EXTERNAL" in assert_info_exits_2(path, capsys)
    assert main(["info", "--allow-external", str(path)]) == 0


# -- numbers --------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["1e308", "-1e308", "1e300"])
def test_huge_offsets_are_refused_at_read_time(tmp_path, value, capsys):
    path = tmp_path / "huge.bvh"
    path.write_text(TINY_BVH.replace("OFFSET 0.0 50.0 0.0", f"OFFSET 0.0 {value} 0.0"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # an overflow warning would be a second line on stderr
        error = _limit(path, "MAX_COORDINATE_M")
    assert "Head" in error.place
    assert_info_exits_2(path, capsys)


def test_a_tiny_frame_time_is_refused_at_read_time(tmp_path):
    path = tmp_path / "fast.bvh"
    path.write_text(TINY_BVH.replace("Frame Time: 0.0333333", "Frame Time: 1e-300"))
    _limit(path, "MAX_FPS")


ASF_ONE_BONE = """:version 1.10
:name t
:units
  mass 1.0
  length 1.0
  angle deg
:root
  order TX TY TZ RX RY RZ
  axis XYZ
  position 0 0 0
  orientation 0 0 0
:bonedata
  begin
    id 1
    name a
    direction 0 1 0
    length 1
    axis 0 0 0 XYZ
    dof rx rz
    limits (-inf inf)
           (-45.0 45.0)
  end
:hierarchy
  begin
    root a
  end
"""


def test_info_json_is_valid_json_for_unbounded_acclaim_limits(tmp_path, capsys):
    asf = ASF_ONE_BONE.replace("(-45.0 45.0)", "(-45.0 {high})")
    path = tmp_path / "t.asf"
    path.write_text(asf.format(high="inf"))
    assert main(["info", "--json", str(path)]) == 0
    summary = json.loads(capsys.readouterr().out, parse_constant=lambda name: pytest.fail(f"{name} in JSON"))
    assert summary["meta"]["bones"]["a"]["limits"] == [[None, None], [-45.0, None]]
    path.write_text(asf.format(high="nan"))
    assert "limits" in assert_info_exits_2(path, capsys)


def test_joint_names_with_control_characters_are_refused():
    with pytest.raises(InputError, match="control characters"):
        infuse.Skeleton(("root", "bad\x00name"), np.array([-1, 0]), np.zeros((2, 3)), quat.identity((2,)))


# -- what a new user met ----------------------------------------------------------------------------------------

def test_a_bvh_named_only_by_its_extension_loads(tmp_path):
    path = tmp_path / ".bvh"
    path.write_text(TINY_BVH)
    assert infuse.load(path).skeleton.names == ("Hips", "Spine", "Head")


def test_a_text_file_named_glb_is_not_a_gltf_file(tmp_path, capsys):
    path = tmp_path / "notes.glb"
    path.write_text("These are my notes, not a model.\n")
    assert "not a glTF or GLB file" in assert_info_exits_2(path, capsys)


def test_error_messages_quoting_the_file_stay_on_one_line(tmp_path, capsys):
    path = tmp_path / "bad.dae"
    path.write_bytes(b'<?xml version="1.0"?>\n<COLLADA>\n<asset>\x00</asset></COLLADA>\n')
    assert_info_exits_2(path, capsys)
    error = InputError("f.xml", "line\n2", "first\nsecond\r\n  third")
    assert str(error) == "f.xml:line 2: first second third"


def test_a_character_may_face_one_added_later():
    scene = Scene(fps=30, quiet=True)
    scene.add_character(synthetic_character(), "ann", position=(0.0, 0.0, 0.0), facing="bob")
    scene.add_character(synthetic_character(), "bob", position=(2.0, 0.0, 0.0), facing="ann")
    scene.step()
    ann, bob = scene.runtime.rig("ann"), scene.runtime.rig("bob")
    # the synthetic character's front is +Z: Ann turns to +X (bob), Bob to -X
    np.testing.assert_allclose(quat.rotate(ann.rotation, np.array([0.0, 0.0, 1.0])), [1.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(quat.rotate(bob.rotation, np.array([0.0, 0.0, 1.0])), [-1.0, 0.0, 0.0], atol=1e-9)
    lonely = Scene(fps=30, quiet=True)
    lonely.add_character(synthetic_character(), "ann", facing="nobody")
    with pytest.raises(UsageError, match="nobody"):
        lonely.step()


# -- BML and scenes -------------------------------------------------------------------------------------------------

def test_bml_times_past_a_day_are_not_scheduled():
    scheduler = Scheduler()
    records = scheduler.submit(f'<bml {BML_NS} id="b1"><head id="h1" lexeme="NOD" start="2147483648"/>'
                               f'<gaze id="g1" target="x" start="0" end="g1:start+2147483648"/></bml>')
    scheduler.flush()
    assert all(abs(t) <= limits.MAX_TIME_S for r in records for a in r.activations for t in a.sync_times.values())
    warnings = " ".join(e.description for e in scheduler.feedback.log if e.kind == "warningFeedback")
    assert warnings.count("infuse.limits.MAX_TIME_S") == 2
    late = scheduler.submit(f'<bml {BML_NS} id="b2"><head id="h2" lexeme="NOD"/></bml>', at=2.0 ** 31)[0]
    assert late.failed and "MAX_TIME_S" in late.failed


def test_head_repetitions_are_bounded():
    started = time.process_time()
    record = Scheduler().submit(f'<bml {BML_NS} id="b1"><head id="h1" lexeme="NOD" repetition="1e9"/></bml>')[0]
    assert time.process_time() - started < 2.0
    assert record.end_s < 10.0  # the default repetition, with a note


def test_bml_documents_over_the_element_limit_are_refused():
    n = limits.MAX_BML_ELEMENTS
    text = f'<bml {BML_NS} id="b1">' + '<head lexeme="NOD"/>' * n + "</bml>"
    with pytest.raises(LimitError, match="MAX_BML_ELEMENTS"):
        parse_bml(text)


def test_scheduling_grows_linearly_with_behaviours():
    """Two thousand gazes, chained heads, unnamed and repeated ids: each schedules in seconds (the
    quadratic passes took minutes)."""
    kinds = {"gaze": lambda i: f'<gaze id="g{i}" target="cup" start="{i * 0.01}"/>',
             "chain": lambda i: f'<head id="h{i}" lexeme="NOD" start="{f"h{i - 1}:end" if i else 0}"/>',
             "unnamed": lambda i: '<head lexeme="NOD"/>', "repeated": lambda i: '<head id="h" lexeme="NOD"/>'}
    for kind, element in kinds.items():
        text = f'<bml {BML_NS} id="b1">' + "".join(element(i) for i in range(2000)) + "</bml>"
        started = time.process_time()
        scheduler = Scheduler()
        record = scheduler.submit(text)[0]
        scheduler.flush()
        assert not record.failed and len(record.activations) == 2000, kind
        assert time.process_time() - started < 15.0, kind


def test_scene_file_numbers_are_bounded(tmp_path):
    (tmp_path / "bob.bvh").write_text(TINY_BVH)
    (tmp_path / "block.xml").write_text(TINY_BML)
    for old, new in (("at = 0.5", "at = 1e14"), ("fps = 30", "fps = 1e300"), ("duration = 3.0", "duration = 1e9"),
                     ("position = [0.0, 0.0, 2.0]", "position = [0.0, 1e300, 2.0]")):
        path = tmp_path / "scene.toml"
        path.write_text(TINY_SCENE_TOML.replace(old, new))
        with pytest.raises(InputError) as info:
            read_scene_file(path)
        assert info.value.file == str(path) and "must be within" in info.value.problem
    path.write_text(TINY_SCENE_TOML)
    assert len(read_scene_file(path).blocks) == 2


def test_acclaim_long_lines_and_many_limit_lines_are_answered_at_once(tmp_path):
    asf = tmp_path / "many.asf"
    asf.write_text(ASF_ONE_BONE.replace("limits (-inf inf)", "limits (-inf inf)\n" + "(\n" * 20000))
    started = time.process_time()
    with pytest.raises(InputError, match="limits"):
        infuse.load(asf)
    assert time.process_time() - started < 2.0
    amc = tmp_path / "long.amc"
    amc.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\na " + "1" * 200_000 + "\n")
    (tmp_path / "long.asf").write_text(ASF_ONE_BONE)
    with pytest.raises(InputError, match="characters long") as info:
        infuse.load(amc, skeleton=str(tmp_path / "long.asf"))
    assert info.value.place == "line 5"


def test_amc_of_millions_of_short_lines_is_refused_before_its_array_is_made(tmp_path):
    (tmp_path / "t.asf").write_text(ASF_ONE_BONE)
    amc = tmp_path / "t.amc"
    amc.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0 " + "0" * 60 + "\na 0 0\n" + "(\n" * 2_000_000)
    started = time.process_time()
    with pytest.raises(InputError, match="unequal length") as info:
        infuse.load(amc, skeleton=str(tmp_path / "t.asf"))
    assert info.value.place == "line 4" and time.process_time() - started < 5.0


def test_xml_scene_attributes_naming_elements_are_refused(tmp_path):
    from fuzz_support import TINY_SCENE_XML

    (tmp_path / "bob.bvh").write_text(TINY_BVH)
    (tmp_path / "block.xml").write_text(TINY_BML)
    path = tmp_path / "scene.xml"
    path.write_text(TINY_SCENE_XML.replace('<scene fps="30"', '<scene character="30"'))
    with pytest.raises(InputError, match="is an element, not an attribute"):
        read_scene_file(path)


def test_gltf_top_level_arrays_must_hold_objects(tmp_path, capsys):
    for key, value in (("images", 5), ("nodes", [1, 2]), ("extensionsUsed", [3]), ("scene", "main")):
        path = _gltf(tmp_path, lambda doc, key=key, value=value: doc.update({key: value}), f"{key}.gltf")
        with pytest.raises(InputError) as info:
            infuse.load(path)
        assert info.value.place.startswith(key), key
    assert "images" in assert_info_exits_2(tmp_path / "images.gltf", capsys)
