"""FBX reader: the corpus files, a synthetic binary FBX checked against explicit matrices, malformed input."""
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from infuse.kinematics import motion_fk

from cli_errors import assert_cli_exits_2, assert_info_exits_2, write_case
from affine import rotation as _R, translation as _T
from corpus_data import corpus_file, labels

FBX_LABELS = [lab for lab in labels() if lab["file"].lower().endswith(".fbx")]
SECOND = 46_186_158_000


@pytest.fixture(scope="module")
def corpus_assets():
    return {lab["file"]: infuse.load(corpus_file(lab["file"])) for lab in FBX_LABELS}


def test_corpus_has_fbx_labels():
    assert len(FBX_LABELS) >= 3 or not labels()


@pytest.mark.parametrize("label", FBX_LABELS, ids=lambda lab: Path(lab["file"]).name)
def test_corpus_file_loads_with_labelled_joints_and_a_standing_rest(label, corpus_assets):
    asset = corpus_assets[label["file"]]
    summary = asset_summary(asset)
    wanted = {v for v in label["mapping"].values() if v}
    assert wanted <= set(summary["joints"]), sorted(wanted - set(summary["joints"]))
    assert summary["units_detected_by"] == "file"
    assert np.isclose(asset.meta["unit_scale_factor_cm"], label["meta"]["unit_scale_factor_cm"])
    assert "+" + summary["up_axis"] == label["meta"]["up_axis"]
    sk = asset.skeleton
    pos = sk.rest_global_positions
    m = label["mapping"]
    head = pos[sk.index[m["skullbase"]], 1]
    feet = pos[[sk.index[m["l_ankle"]], sk.index[m["r_ankle"]]], 1]
    assert 1.2 <= sk.height() <= 2.2
    assert head - feet.max() > 1.0
    # In the core frame the character's left is +X and its toes point along +Z.
    assert pos[sk.index[m["l_wrist"]], 0] > 0.3 > -0.3 > pos[sk.index[m["r_wrist"]], 0]
    assert pos[sk.index[m["l_forefoot"]], 2] > pos[sk.index[m["l_ankle"]], 2]
    assert set(asset.motions) <= set(label["meta"]["animation_stacks"])


def test_mixamo_walk_moves_forward_with_planted_feet(corpus_assets):
    asset = corpus_assets.get("talkinghead/animations/walking.fbx") or pytest.skip("no corpus")
    motion = asset.motions["mixamo.com"]
    assert motion.fps == 30.0 and motion.num_frames >= 29
    _, pos = motion_fk(motion)
    sk = asset.skeleton
    hips = pos[:, sk.index["mixamorig:Hips"]]
    assert hips[-1, 2] - hips[0, 2] > 0.8  # about 1.6 m/s forward along +Z
    feet = pos[:, [sk.index["mixamorig:LeftToeBase"], sk.index["mixamorig:RightToeBase"]], 1]
    assert feet.min() > -0.05 and np.all(feet.min(axis=1) < 0.1)  # one foot near the ground at all times


# -- a small binary FBX writer, for the synthetic scene and its malformed variants ----------------------

def _prop(p):
    if isinstance(p, bool):
        return b"C" + struct.pack("<?", p)
    if isinstance(p, int):
        return b"L" + struct.pack("<q", p)
    if isinstance(p, float):
        return b"D" + struct.pack("<d", p)
    if isinstance(p, str):
        return b"S" + struct.pack("<I", len(p.encode())) + p.encode()
    if isinstance(p, np.ndarray):
        code = {np.dtype("int64"): b"l", np.dtype("float32"): b"f", np.dtype("float64"): b"d", np.dtype("int32"): b"i"}[p.dtype]
        raw = zlib.compress(p.tobytes())
        return code + struct.pack("<III", len(p), 1, len(raw)) + raw
    raise TypeError(p)


def _node(name, props, children, pos, wide):
    head = 25 if wide else 13
    body = b"".join(_prop(p) for p in props)
    start = pos + head + len(name) + len(body)
    kids, cur = b"", start
    for child in children:
        b = _node(*child, cur, wide)
        kids, cur = kids + b, cur + len(b)
    if children:
        kids += b"\0" * head
    fields = struct.pack("<QQQ" if wide else "<III", start + len(kids), len(props), len(body))
    return fields + bytes([len(name)]) + name.encode() + body + kids


def fbx_bytes(top, version=7400):
    out = b"Kaydara FBX Binary  \x00\x1a\x00" + struct.pack("<I", version)
    for n in top:
        out += _node(*n, len(out), version >= 7500)
    return out + b"\0" * (25 if version >= 7500 else 13)


def _ascii_value(p):
    if isinstance(p, str):
        if "\x00\x01" in p:  # binary "name\0\1Class" is "Class::name" in ASCII
            name, cls = p.split("\x00\x01")
            p = f"{cls}::{name}"
        return '"' + p + '"'
    if isinstance(p, np.ndarray):
        return f"*{len(p)} {{\n a: " + ",".join(repr(v.item()) for v in p) + "\n}"
    return repr(int(p) if isinstance(p, bool) else p)


def _ascii_node(name, props, children, indent=""):
    line = f"{indent}{name}: " + ", ".join(_ascii_value(p) for p in props)
    if not children:
        return line + "\n"
    return line + " {\n" + "".join(_ascii_node(*c, indent + "\t") for c in children) + indent + "}\n"


def fbx_text(top, version=7400):
    """The same records as :func:`fbx_bytes`, as an ASCII FBX file (names as ``Class::name``)."""
    header = ("FBXHeaderExtension", [], [("FBXVersion", [version], [])])
    out = f"; FBX {version // 1000}.{version // 100 % 10}.0 project file\n; written by a test\n"
    for n in [header] + list(top):
        out += _ascii_node(*n)
    return out.encode()


def P(name, *values):
    return ("P", [name, "", "", "A", *values], [])


def model(oid, name, cls, *props):
    return ("Model", [oid, f"{name}\x00\x01Model", cls], [("Properties70", [], list(props))])


def curve(oid, times_s, values, flags, slopes=(0.0, 0.0)):
    return ("AnimationCurve", [oid, "\x00\x01AnimCurve", ""], [
        ("KeyTime", [np.array([round(t * SECOND) for t in times_s], dtype=np.int64)], []),
        ("KeyValueFloat", [np.array(values, dtype=np.float32)], []),
        ("KeyAttrFlags", [np.array([flags], dtype=np.int32)], []),
        ("KeyAttrDataFloat", [np.array([slopes[0], slopes[1], 0.0, 0.0], dtype=np.float32)], []),
        ("KeyAttrRefCount", [np.array([len(times_s)], dtype=np.int32)], []),
    ])


def C(kind, child, parent, prop=None):
    return ("C", [kind, child, parent] + ([prop] if prop else []), [])


def scene(objects=None, connections=None, settings=None):
    settings = settings if settings is not None else [P("UpAxis", 2), P("UpAxisSign", 1), P("UnitScaleFactor", 2.54),
                                                      P("TimeMode", 11)]
    objects = objects if objects is not None else OBJECTS
    connections = connections if connections is not None else CONNECTIONS
    return [
        ("GlobalSettings", [], [("Properties70", [], settings)]),
        ("Definitions", [], [("ObjectType", ["Model"], [("PropertyTemplate", ["FbxNode"], [
            ("Properties70", [], [P("RotationActive", 0), P("Lcl Scaling", 1.0, 1.0, 1.0)])])])]),
        ("Objects", [], objects),
        ("Connections", [], connections),
    ]


OBJECTS = [
    model(10, "Armature", "Null", P("Lcl Scaling", 2.0, 2.0, 2.0), P("Lcl Rotation", 0.0, 0.0, 30.0)),
    model(11, "Hips", "LimbNode", P("Lcl Translation", 0.0, 0.0, 40.0), P("Lcl Rotation", 10.0, 20.0, 30.0),
          P("RotationActive", 1), P("RotationOrder", 4), P("PreRotation", 90.0, 0.0, 0.0), P("PostRotation", 0.0, 15.0, 0.0),
          P("RotationPivot", 1.0, 2.0, 3.0), P("ScalingPivot", 0.5, 0.0, 0.0), P("RotationOffset", 0.0, 1.0, 0.0),
          P("Lcl Scaling", 1.0, 1.5, 1.0)),
    model(12, "Spine", "LimbNode", P("Lcl Translation", 0.0, 10.0, 0.0), P("PreRotation", 0.0, 0.0, 45.0)),
    model(13, "Head", "LimbNode", P("Lcl Translation", 0.0, 12.0, 0.0)),
    model(14, "Prop", "Mesh", P("Lcl Translation", 5.0, 0.0, 0.0)),
    model(15, "Socket", "Null", P("Lcl Translation", 0.0, 3.0, 0.0)),
    model(16, "Skinned", "Mesh", P("Lcl Translation", 4.0, 0.0, 0.0)),
    ("Deformer", [20, "\x00\x01Deformer", "Skin"], []),
    ("Deformer", [21, "\x00\x01SubDeformer", "Cluster"], []),
    ("Deformer", [30, "Face\x00\x01Deformer", "BlendShape"], []),
    ("Deformer", [31, "smile\x00\x01SubDeformer", "BlendShapeChannel"], []),
    ("Deformer", [32, "blink\x00\x01SubDeformer", "BlendShapeChannel"], []),
    ("AnimationStack", [40, "Take 001\x00\x01AnimStack", ""], [("Properties70", [], [
        ("P", ["LocalStart", "KTime", "Time", "", 0], []), ("P", ["LocalStop", "KTime", "Time", "", SECOND], [])])]),
    ("AnimationLayer", [41, "Base\x00\x01AnimLayer", ""], []),
    ("AnimationCurveNode", [42, "T\x00\x01AnimCurveNode", ""], []),
    curve(43, [0.0, 1.0], [40.0, 80.0], 0x4),
    ("AnimationCurveNode", [44, "R\x00\x01AnimCurveNode", ""], [("Properties70", [], [P("d|Y", 5.0)])]),
    curve(45, [0.0, 1.0], [0.0, 90.0], 0x8),
]
CONNECTIONS = [
    C("OO", 10, 0), C("OO", 11, 10), C("OO", 12, 11), C("OO", 13, 12), C("OO", 14, 10), C("OO", 15, 13),
    C("OO", 16, 11), C("OO", 21, 20), C("OO", 16, 21), C("OO", 31, 30), C("OO", 32, 30), C("OO", 41, 40),
    C("OO", 42, 41), C("OP", 42, 11, "Lcl Translation"), C("OP", 43, 42, "d|Z"),
    C("OO", 44, 41), C("OP", 44, 12, "Lcl Rotation"), C("OP", 45, 44, "d|X"),
]


def _S(v):
    return np.diag([*v, 1.0])


def _xyz(x, y, z):
    return _R("z", z) @ _R("y", y) @ _R("x", x)  # X applied first


def _expected(t):
    """Global positions (metres, Y up) of Armature, Hips, Spine, Head, Socket, Skinned at time t."""
    inv = np.linalg.inv
    armature = _xyz(0, 0, 30) @ _S((2, 2, 2))
    rp, sp = _T((1, 2, 3)), _T((0.5, 0, 0))
    hips_r = _R("y", 20) @ _R("x", 10) @ _R("z", 30)  # RotationOrder 4 = ZXY: Z first, then X, then Y
    hips = armature @ (_T((0, 0, 40 + 40 * t)) @ _T((0, 1, 0)) @ rp @ _xyz(90, 0, 0) @ hips_r @ inv(_xyz(0, 15, 0))
                       @ inv(rp) @ sp @ _S((1, 1.5, 1)) @ inv(sp))
    ease = 90 * (3 * t**2 - 2 * t**3)  # cubic keys with flat slopes
    spine = hips @ _T((0, 10, 0)) @ _xyz(ease, 5, 0)  # PreRotation ignored: RotationActive is 0 there
    head = spine @ _T((0, 12, 0))
    core = _R("x", -90) @ _S((0.0254,) * 3)  # inches, Z up -> metres, Y up
    mats = [armature, hips, spine, head, head @ _T((0, 3, 0)), hips @ _T((4, 0, 0))]
    return np.array([(core @ m)[:3, 3] for m in mats])


@pytest.mark.parametrize("version,encode", [(7400, fbx_bytes), (7500, fbx_bytes), (7400, fbx_text)],
                         ids=["binary-7400", "binary-7500", "ascii-7400"])
def test_synthetic_scene_matches_explicit_matrices(tmp_path, version, encode):
    path = tmp_path / "scene.fbx"
    path.write_bytes(encode(scene(), version))
    asset = infuse.load(path)
    sk = asset.skeleton
    assert sk.names == ("Armature", "Hips", "Spine", "Head", "Socket", "Skinned")  # not the Prop mesh
    assert [sk.names[p] if p >= 0 else None for p in sk.parents] == [None, "Armature", "Hips", "Spine", "Head", "Hips"]
    assert asset.morph_targets == ["smile", "blink"]
    assert (asset.source_units, asset.source_up_axis, asset.units_detected_by) == ("inch", "Z", "file")
    assert np.allclose(sk.rest_global_positions, _expected(0.0), atol=1e-9)
    motion = asset.motions["Take 001"]
    assert motion.fps == 24.0 and motion.num_frames == 25
    _, pos = motion_fk(motion)
    assert np.allclose(pos, np.stack([_expected(k / 24) for k in range(25)]), atol=1e-6)


def test_overrides_and_unsupported_variants(tmp_path):
    path = tmp_path / "scene.fbx"
    path.write_bytes(fbx_bytes(scene()))
    base = infuse.load(path)
    asset = infuse.load(path, units="cm", up_axis="Y")
    assert (asset.source_units, asset.units_detected_by, asset.source_up_axis) == ("cm", "override", "Y")
    assert np.isclose(asset.skeleton.height() * 2.54, base.skeleton.height())
    for name, data in (("old-ascii.fbx", fbx_text(scene(), 6100)), ("old.fbx", fbx_bytes(scene(), 6100))):
        p = tmp_path / name
        p.write_bytes(data)
        with pytest.raises(infuse.UnusableInputError, match="not supported"):
            infuse.load(p)


# -- malformed input through the CLI ----------------------------------------------------------------

def _replace(objects, oid, new):
    return [new if o[1] and o[1][0] == oid else o for o in objects]


def _malformed_cases():
    good = fbx_bytes(scene())
    yield "truncated", good[: len(good) // 2]
    yield "garbage", b"\x00\xffnot an fbx file at all" * 3
    yield "empty", b""
    yield "header-only", good[:27]
    yield "record-overrun", good[:27] + struct.pack("<III", 10**6, 0, 0) + b"\x03abc"
    yield "unknown-type", good[:27] + _node("X", [], [], 27, False)[:13] + b"\x01X"  # patched below
    yield "nan-translation", fbx_bytes(scene(_replace(OBJECTS, 13, model(13, "Head", "LimbNode", P("Lcl Translation", 0.0, float("nan"), 0.0)))))
    yield "overflow", fbx_bytes(scene(_replace(OBJECTS, 12, model(12, "Spine", "LimbNode", P("Lcl Translation", 0.0, 1e308, 0.0),
                                                               P("Lcl Scaling", 1e308, 1e308, 1e308)))))
    yield "cycle", fbx_bytes(scene(connections=[C("OO", 10, 13)] + CONNECTIONS[1:]))
    yield "unknown-parent", fbx_bytes(scene(connections=[C("OO", 13, 999)] + [c for c in CONNECTIONS if c[1][1] != 13]))
    yield "two-parents", fbx_bytes(scene(connections=CONNECTIONS + [C("OO", 13, 11)]))
    yield "no-objects", fbx_bytes([s for s in scene() if s[0] != "Objects"])
    yield "duplicate-id", fbx_bytes(scene(OBJECTS + [model(13, "Again", "LimbNode")]))
    yield "key-count", fbx_bytes(scene(_replace(OBJECTS, 43, ("AnimationCurve", [43, "\x00\x01AnimCurve", ""], [
        ("KeyTime", [np.array([0, SECOND], dtype=np.int64)], []), ("KeyValueFloat", [np.array([1.0], dtype=np.float32)], [])]))))
    yield "decreasing-keys", fbx_bytes(scene(_replace(OBJECTS, 43, curve(43, [1.0, 0.0], [40.0, 80.0], 0x4))))
    yield "bad-settings", fbx_bytes(scene(settings=[P("UpAxis", 7)]))
    yield "bad-id", fbx_bytes(scene(OBJECTS + [("Model", ["not-an-id", "x\x00\x01Model", "Null"], [])]))
    deep = ("Leaf", [], [])
    for _ in range(100):
        deep = ("Nest", [], [deep])
    yield "too-deep", fbx_bytes(scene() + [deep])
    text = fbx_text(scene())
    yield "ascii-truncated", text[: len(text) // 2]
    yield "ascii-nan", text.replace(b'"Lcl Translation", "", "", "A", 0.0, 12.0, 0.0', b'"Lcl Translation", "", "", "A", 0.0, nan, 0.0')
    yield "ascii-array-count", text.replace(b"*2 {", b"*3 {", 1)
    yield "ascii-stray-brace", text + b"}\n"
    yield "ascii-no-version", b"; FBX 7.4.0 project file\nFBXHeaderExtension:  {\n}\n"
    yield "ascii-cycle", fbx_text(scene(connections=[C("OO", 10, 13)] + CONNECTIONS[1:]))


def _cases():
    cases = dict(_malformed_cases())
    # A record whose property type code is unknown: header, name "X", then the code 'Q'.
    body = b"Q\x00\x00\x00\x00"
    rec = struct.pack("<III", 27 + 13 + 1 + len(body), 1, len(body)) + b"\x01X" + body
    cases["unknown-type"] = cases["header-only"] + rec + b"\0" * 13
    # A compressed array whose bytes are not zlib.
    arr = b"d" + struct.pack("<III", 2, 1, 4) + b"oops"
    rec = struct.pack("<III", 27 + 13 + 1 + len(arr), 1, len(arr)) + b"\x01A" + arr
    cases["corrupt-zlib"] = cases["header-only"] + rec + b"\0" * 13
    return cases


CASES = _cases()


@pytest.mark.parametrize("name", sorted(CASES))
def test_malformed_input_exits_2_with_one_line(tmp_path, capsys, name):
    assert_info_exits_2(write_case(tmp_path, name, CASES[name], ".fbx"), capsys)


def test_malformed_input_through_the_installed_command(tmp_path):
    names = ("garbage", "nan-translation", "cycle", "corrupt-zlib")
    paths = [write_case(tmp_path, name, CASES[name], ".fbx") for name in names]
    if FBX_LABELS:
        data = corpus_file(FBX_LABELS[0]["file"]).read_bytes()
        for k, cut in enumerate((100, len(data) // 3)):
            paths.append(write_case(tmp_path, f"cut{k}", data[:cut], ".fbx"))
    assert_cli_exits_2(paths)


def test_inherit_type_rrs_ignores_the_parent_scale(tmp_path):
    """InheritType 2: the child's frame skips its parent's own scale; its offset still follows it."""
    objects = [
        model(1, "Parent", "LimbNode", P("Lcl Scaling", 2.0, 3.0, 4.0)),
        model(2, "Child", "LimbNode", P("Lcl Translation", 0.0, 10.0, 0.0), P("Lcl Rotation", 0.0, 0.0, 30.0),
              P("InheritType", 2)),
        model(3, "Tip", "LimbNode", P("Lcl Translation", 5.0, 0.0, 0.0)),
    ]
    connections = [C("OO", 1, 0), C("OO", 2, 1), C("OO", 3, 2)]
    settings = [P("UpAxis", 1), P("UnitScaleFactor", 100.0)]
    path = tmp_path / "rrs.fbx"
    path.write_bytes(fbx_bytes(scene(objects, connections, settings)))
    pos = infuse.load(path).skeleton.rest_global_positions
    child = _S((2, 3, 4)) @ _T((0, 10, 0)) @ _S((1 / 2, 1 / 3, 1 / 4)) @ _R("z", 30)
    assert np.allclose(pos, [[0, 0, 0], [0, 30, 0], (child @ [5, 0, 0, 1])[:3]], atol=1e-9)
    assert np.allclose(pos[2], [5 * np.cos(np.radians(30)), 30 + 5 * np.sin(np.radians(30)), 0.0])  # parent scale undone


def test_inherit_type_rrss_applies_the_parent_scale_after_the_child_rotation(tmp_path):
    """RrSs (0) against RSrs (1) under a parent scaled (1, 3, 1), child rotated 40 degrees about z."""
    objects = [model(2, "Parent", "LimbNode", P("Lcl Scaling", 1.0, 3.0, 1.0))]
    connections = [C("OO", 2, 0)]
    for base, mode in ((3, 0), (5, 1)):
        objects += [model(base, f"Arm{mode}", "LimbNode", P("Lcl Translation", 0.0, 2.0, 0.0),
                          P("Lcl Rotation", 0.0, 0.0, 40.0), P("InheritType", mode)),
                    model(base + 1, f"Hand{mode}", "LimbNode", P("Lcl Translation", 0.0, 5.0, 0.0), P("InheritType", mode))]
        connections += [C("OO", base, 2), C("OO", base + 1, base)]
    path = tmp_path / "modes.fbx"
    path.write_bytes(fbx_bytes(scene(objects, connections, [P("UpAxis", 1), P("UnitScaleFactor", 100.0)])))
    sk = infuse.load(path).skeleton
    pos = dict(zip(sk.names, sk.rest_global_positions))
    c, s = np.cos(np.radians(40)), np.sin(np.radians(40))
    # RrSs: the hand's offset is scaled by (1, 3, 1), then rotated with the arm.
    assert np.allclose(pos["Hand0"], [-15 * s, 6 + 15 * c, 0.0], atol=1e-9)
    # RSrs: plain products, the parent scale stretches the rotated offset.
    assert np.allclose(pos["Hand1"], [-5 * s, 3 * (2 + 5 * c), 0.0], atol=1e-9)
    assert np.allclose(pos["Arm0"], pos["Arm1"])
