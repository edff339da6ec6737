"""Malformed glTF/GLB files through ``infuse info``: exit code 2, one line naming the file, no traceback."""
from __future__ import annotations

import json
import struct
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import infuse

from cli_errors import assert_info_exits_2, assert_one_error_line, load_error, run_info, write_case
from gltf_builder import mini_rig


def _glb_bytes(mutate=None) -> bytes:
    b, n = mini_rig()
    if mutate:
        mutate(b, n)
    return b.glb()


def _patch_json(glb: bytes, text: bytes) -> bytes:
    """A GLB with its JSON chunk replaced by ``text`` (lengths kept consistent)."""
    clen = struct.unpack_from("<I", glb, 12)[0]
    rest = glb[20 + clen:]
    text += b" " * ((-len(text)) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + rest
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def _set_nan(b, n):
    out = b.doc["animations"][0]["samplers"][1]["output"]  # the hips translation keys
    view = b.doc["bufferViews"][b.doc["accessors"][out]["bufferView"]]
    b.bin[view["byteOffset"] + 4:view["byteOffset"] + 8] = struct.pack("<f", float("nan"))


def _decreasing_times(b, n):
    b.doc["animations"][0]["samplers"][1]["input"] = b.accessor(np.array([[1.0], [0.5], [0.0]]), minmax=True)


def _doc(edit):
    def mutate(b, n):
        edit(b.doc, n)
    return mutate


def _cases() -> dict[str, tuple[str, bytes]]:
    """Case name -> (file suffix, file content)."""
    good = _glb_bytes()
    rng = np.random.default_rng(7)
    clen = struct.unpack_from("<I", good, 12)[0]
    good_json = json.loads(good[20:20 + clen])
    no_bin = _patch_json(good[:20 + clen], good[20:20 + clen])
    cases = {
        "empty": (".glb", b""),
        "truncated_header": (".glb", good[:7]),
        "truncated_json": (".glb", good[:60]),
        "truncated_bin": (".glb", good[:-100]),
        "garbage": (".glb", rng.integers(0, 256, 3000, dtype=np.uint8).tobytes()),
        "garbage_after_magic": (".glb", b"glTF" + rng.integers(0, 256, 3000, dtype=np.uint8).tobytes()),
        "glb_version_1": (".glb", good[:4] + struct.pack("<I", 1) + good[8:]),
        "trailing_bytes": (".glb", good + b"\0" * 16),
        "chunk_length_too_big": (".glb", good[:12] + struct.pack("<I", 1 << 30) + good[16:]),
        "first_chunk_not_json": (".glb", good[:16] + struct.pack("<I", 0x004E4942) + good[20:]),
        "json_garbage": (".glb", _patch_json(good, b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [,,]}")),
        "json_not_utf8": (".glb", _patch_json(good, b"\xff\xfe{}")),
        "json_not_object": (".glb", _patch_json(good, b"[1, 2, 3]")),
        "gltf_version_1": (".glb", _patch_json(good, json.dumps(dict(good_json, asset={"version": "1.0"})).encode())),
        "no_bin_chunk": (".glb", no_bin),
        "nan_in_accessor": (".glb", _glb_bytes(_set_nan)),
        "nan_in_node": (".glb", _patch_json(good, json.dumps(good_json).replace("[0.0, 0.0, 100.0]", "[0.0, NaN, 100.0]", 1).encode())),
        "node_cycle": (".glb", _glb_bytes(_doc(lambda d, n: d["nodes"][n["head"]].setdefault("children", []).append(n["hips"])))),
        "node_two_parents": (".glb", _glb_bytes(_doc(lambda d, n: d["nodes"][n["arm.L"]].setdefault("children", []).append(n["head"])))),
        "node_self_child": (".glb", _glb_bytes(_doc(lambda d, n: d["nodes"][n["spine"]]["children"].append(n["spine"])))),
        "child_out_of_range": (".glb", _glb_bytes(_doc(lambda d, n: d["nodes"][n["spine"]]["children"].append(999)))),
        "skin_joint_out_of_range": (".glb", _glb_bytes(_doc(lambda d, n: d["skins"][0]["joints"].append(-1)))),
        "accessor_index_out_of_range": (".glb", _glb_bytes(_doc(lambda d, n: d["animations"][0]["samplers"][0].update(output=5000)))),
        "bufferview_index_out_of_range": (".glb", _glb_bytes(_doc(lambda d, n: d["accessors"][d["animations"][0]["samplers"][0]["output"]].update(bufferView=77)))),
        "bufferview_past_buffer": (".glb", _glb_bytes(_doc(lambda d, n: d["bufferViews"][-1].update(byteOffset=10 ** 6)))),
        "accessor_past_view": (".glb", _glb_bytes(_doc(lambda d, n: d["accessors"][d["animations"][0]["samplers"][2]["output"]].update(count=500)))),
        "bad_component_type": (".glb", _glb_bytes(_doc(lambda d, n: d["accessors"][d["animations"][0]["samplers"][0]["output"]].update(componentType=1234)))),
        "times_decrease": (".glb", _glb_bytes(_decreasing_times)),
        "output_count_mismatch": (".glb", _glb_bytes(_doc(lambda d, n: d["animations"][0]["samplers"][0].update(output=d["animations"][0]["samplers"][1]["output"])))),
        "unknown_interpolation": (".glb", _glb_bytes(_doc(lambda d, n: d["animations"][0]["samplers"][0].update(interpolation="BEZIER")))),
        "zero_quaternion": (".glb", _glb_bytes(_doc(lambda d, n: d["nodes"][n["spine"]].update(rotation=[0, 0, 0, 0])))),
        "nodes_not_array": (".glb", _glb_bytes(_doc(lambda d, n: d.update(nodes={"0": {}})))),
        "gltf_bad_json": (".gltf", b'{"asset": {"version": "2.0"}, "nodes": [{"name": "a"}'),
        "gltf_missing_buffer": (".gltf", json.dumps(dict(good_json, buffers=[{"uri": "gone.bin", "byteLength": 400}])).encode()),
        "gltf_bad_data_uri": (".gltf", json.dumps(dict(good_json, buffers=[{"uri": "data:application/octet-stream,xyz", "byteLength": 3}])).encode()),
        "gltf_short_buffer": (".gltf", json.dumps(dict(good_json, buffers=[{"uri": "data:application/octet-stream;base64,AAAA", "byteLength": 400}])).encode()),
    }
    return cases


CASES = _cases()


#: One case per kind of damage, run through the installed ``infuse`` program; every case also runs
#: through the same entry point in-process below (a process start costs about a second).
THROUGH_PROGRAM = ["truncated_bin", "garbage", "json_garbage", "nan_in_accessor", "node_cycle", "node_two_parents",
                   "gltf_missing_buffer", "accessor_index_out_of_range", "bufferview_past_buffer", "empty"]


def _write(folder: Path, name: str) -> Path:
    suffix, data = CASES[name]
    return write_case(folder, name, data, suffix)


@pytest.fixture(scope="module")
def program_runs(tmp_path_factory):
    """The THROUGH_PROGRAM cases through ``infuse info``, a few at a time: name -> (path, CompletedProcess)."""
    folder = tmp_path_factory.mktemp("malformed_gltf")

    def run(name):
        path = _write(folder, name)
        return name, (path, run_info(path))

    with ThreadPoolExecutor(max_workers=3) as pool:
        return dict(pool.map(run, THROUGH_PROGRAM))


@pytest.mark.parametrize("name", THROUGH_PROGRAM)
def test_program_reports_malformed_input_in_one_line(program_runs, name):
    path, done = program_runs[name]
    assert_one_error_line(path, done.returncode, done.stdout, done.stderr)


@pytest.mark.parametrize("name", list(CASES))
def test_cli_reports_malformed_input_in_one_line(tmp_path, capsys, name):
    assert_info_exits_2(_write(tmp_path, name), capsys)


PLACES = {
    "node_cycle": "nodes[", "node_two_parents": "has two parents", "child_out_of_range": "nodes[",
    "accessor_index_out_of_range": "animations[0].samplers[0]", "bufferview_index_out_of_range": "accessors[",
    "bufferview_past_buffer": "bufferViews[", "nan_in_accessor": "accessors[", "nan_in_node": "nodes[1].translation",
    "gltf_missing_buffer": "buffers[0]", "no_bin_chunk": "buffers[0]", "truncated_bin": "GLB header",
    "times_decrease": "keyframe times decrease", "skin_joint_out_of_range": "skins[0].joints",
}


@pytest.mark.parametrize("name", list(PLACES))
def test_error_names_the_place(tmp_path, name):
    assert PLACES[name] in str(load_error(_write(tmp_path, name)))


def _mutations(doc: dict, rng: np.random.Generator, count: int):
    """``count`` copies of ``doc`` with one to three values replaced by a wrong type, a bad index or NaN,
    or a key removed."""
    def paths(obj, prefix=()):
        if prefix:
            yield prefix
        items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list) else ()
        for key, value in items:
            yield from paths(value, prefix + (key,))

    every = list(paths(doc))
    values = [None, -1, 0, 7, 10 ** 9, "x", [], {}, 1.5, True, [1, 2], {"a": 1}, float("nan"), [0, 0, 0, 0]]
    for _ in range(count):
        mutated = json.loads(json.dumps(doc))
        for _ in range(rng.integers(1, 4)):
            path = every[rng.integers(len(every))]
            parent = mutated
            try:
                for key in path[:-1]:
                    parent = parent[key]
                if isinstance(parent, dict) and rng.random() < 0.2:
                    parent.pop(path[-1], None)
                else:
                    parent[path[-1]] = values[rng.integers(len(values))]
            except (KeyError, IndexError, TypeError):
                pass  # an earlier change removed this place
        yield mutated


def test_random_damage_gives_typed_errors_only(tmp_path):
    """Random damage to the JSON of a VRM-flavoured rig: every outcome is a clean read (then a clean
    write) or an infuse error; never a stray exception (a bug, exit code 1)."""
    b, n = mini_rig()
    b.doc["extensions"] = {"VRMC_vrm": {"specVersion": "1.0", "humanoid": {"humanBones": {"hips": {"node": n["hips"]}}},
                                        "expressions": {"preset": {"aa": {"morphTargetBinds": [{"node": n["face"], "index": 0, "weight": 1}]}}}}}
    good = b.glb()
    clen = struct.unpack_from("<I", good, 12)[0]
    doc = json.loads(good[20:20 + clen])
    path, out = tmp_path / "damaged.glb", tmp_path / "written.glb"
    outcomes = {"read": 0, "refused": 0}
    for mutated in _mutations(doc, np.random.default_rng(11), 300):
        path.write_bytes(_patch_json(good, json.dumps(mutated).encode()))
        try:
            asset = infuse.load(path)
            infuse.save(asset, out)
            outcomes["read"] += 1
        except infuse.InfuseError as exc:
            assert getattr(exc, "file", None) in (str(path), None), exc
            outcomes["refused"] += 1
    assert outcomes["read"] > 30 and outcomes["refused"] > 30
