"""Ogre skeleton XML reader: the corpus skeletons, Ogre's keyframe semantics, malformed input through the CLI."""
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from infuse.kinematics import motion_fk

from cli_errors import assert_cli_exits_2, assert_info_exits_2, write_case
from corpus_data import corpus_file, labels

OGRE_LABELS = [lab for lab in labels() if lab["file"].lower().endswith(".skeleton.xml")]


@pytest.fixture(scope="module")
def corpus_assets():
    return {lab["file"]: infuse.load(corpus_file(lab["file"])) for lab in OGRE_LABELS}


def test_corpus_has_ogre_labels():
    assert len(OGRE_LABELS) >= 3 or not labels()


@pytest.mark.parametrize("label", OGRE_LABELS, ids=lambda lab: Path(lab["file"]).name)
def test_corpus_file_loads_with_labelled_joints_and_a_plausible_size(label, corpus_assets):
    asset = corpus_assets[label["file"]]
    summary = asset_summary(asset)
    wanted = {v for v in label["mapping"].values() if v}
    assert wanted <= set(summary["joints"]), sorted(wanted - set(summary["joints"]))
    assert summary["units_detected_by"] == "guess" and asset.meta["units_guess"]
    assert summary["up_axis"] == "Y"
    sk = asset.skeleton
    pos = sk.rest_global_positions
    m = label["mapping"]
    head = pos[sk.index[m["skullbase"]], 1]
    feet = pos[[sk.index[m["l_ankle"]], sk.index[m["r_ankle"]]], 1]
    assert head - feet.max() > 0.4
    if Path(label["file"]).name.startswith("Sinbad"):  # the human of the three
        assert 1.2 <= sk.height() <= 2.2
    else:
        assert 0.5 <= sk.height() <= 3.0
    assert asset.motions, "the corpus skeletons all carry animations"
    for motion in asset.motions.values():
        assert motion.fps == 30.0
        _, p = motion_fk(motion)
        assert np.all(np.isfinite(p))
        assert np.ptp(p, axis=(0, 1)).max() < 10 * sk.height()


def test_sinbad_units_are_scaled_to_a_human_and_overridable():
    path = corpus_file("smartbody/mesh/Ogre/Sinbad.skeleton.xml")
    guessed = infuse.load(path)
    assert "scaled to" in guessed.meta["units_guess"]
    raw = infuse.load(path, units="m")
    assert raw.units_detected_by == "override" and raw.source_units == "m"
    ratio = raw.skeleton.height() / guessed.skeleton.height()
    assert np.isclose(ratio, 1.0 / float(guessed.source_units.split()[0]))


# -- Ogre's keyframe semantics on a small skeleton, against a hand-written chain -----------------------

SKELETON = """<skeleton blendmode="average">
  <bones>
    <bone id="1" name="Spine"><position x="0" y="20" z="0"/><rotation angle="0"><axis x="1" y="0" z="0"/></rotation></bone>
    <bone id="0" name="Hips"><position x="0" y="100" z="0"/><rotation angle="1.5707963267948966"><axis x="0" y="1" z="0"/></rotation></bone>
    <bone id="2" name="Head"><position x="0" y="50" z="0"/><rotation qx="0" qy="0" qz="0" qw="1"/>
      <scale x="1" y="1" z="1"/></bone>
    <bone id="3" name="Arm"><position x="10" y="30" z="0"/><rotation angle="0"><axis x="0" y="0" z="1"/></rotation></bone>
  </bones>
  <bonehierarchy>
    <boneparent bone="Head" parent="Spine"/>
    <boneparent bone="Spine" parent="Hips"/>
    <boneparent bone="Arm" parent="Spine"/>
  </bonehierarchy>
  <animations>
    <animation name="Bend" length="1">
      <tracks>
        <track bone="Spine"><keyframes>
          <keyframe time="0"><translate x="0" y="0" z="0"/><rotate angle="0"><axis x="0" y="0" z="1"/></rotate></keyframe>
          <keyframe time="0.5"><translate x="0" y="10" z="0"/><rotate angle="1.5707963267948966"><axis x="0" y="0" z="1"/></rotate></keyframe>
        </keyframes></track>
        <track bone="Hips"><keyframes>
          <keyframe time="0.5"><translate x="30" y="0" z="0"/></keyframe>
        </keyframes></track>
      </tracks>
    </animation>
  </animations>
</skeleton>
"""


def _expected(t):
    """Global positions (file units, Y up) of Hips, Spine, Head, Arm at time t by explicit matrices."""
    def T(x, y, z):
        m = np.eye(4)
        m[:3, 3] = (x, y, z)
        return m

    def R(axis, angle):
        c, s = np.cos(angle), np.sin(angle)
        m = np.eye(4)
        i, j = {"y": (2, 0), "z": (0, 1)}[axis]
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m

    # Spine keys at 0 and 0.5 s, then back towards the first key at length + 0 = 1 s (Ogre wraps).
    u = t / 0.5 if t <= 0.5 else 1.0 - (t - 0.5) / 0.5
    # nlerp between identity and 90 degrees about z: the angle of the normalized blend.
    half = np.arctan2(u * np.sin(np.pi / 4), (1 - u) + u * np.cos(np.pi / 4))
    hips = T(30, 100, 0) @ R("y", np.pi / 2)  # one key: holds everywhere
    spine = hips @ T(0, 20 + 10 * u, 0) @ R("z", 2 * half)
    return np.array([m[:3, 3] for m in (hips, spine, spine @ T(0, 50, 0), spine @ T(10, 30, 0))])


QUATERNION_KEYS = SKELETON.replace(
    '<rotate angle="1.5707963267948966"><axis x="0" y="0" z="1"/></rotate>',
    '<rotate qx="0" qy="0" qz="0.7071067811865476" qw="0.7071067811865476"/>')


@pytest.mark.parametrize("text", [SKELETON, QUATERNION_KEYS], ids=["angle-axis", "quaternion"])
def test_keyframes_offset_the_binding_pose_and_wrap(tmp_path, text):
    assert "qz=" in QUATERNION_KEYS
    path = tmp_path / "small.skeleton.xml"
    path.write_text(text)
    asset = infuse.load(path, units="cm")
    sk = asset.skeleton
    assert sk.names == ("Hips", "Spine", "Head", "Arm") and list(sk.parents) == [-1, 0, 1, 1]
    rest = np.array([[0, 100, 0], [0, 120, 0], [0, 170, 0], [0, 150, -10.0]]) * 0.01
    assert np.allclose(sk.rest_global_positions, rest, atol=1e-9)
    motion = asset.motions["Bend"]
    assert motion.num_frames == 31
    _, pos = motion_fk(motion)
    expected = np.stack([_expected(k / 30.0) for k in range(31)]) * 0.01
    assert np.allclose(pos, expected, atol=1e-9)


# -- malformed input through the CLI ----------------------------------------------------------------

def _malformed_cases():
    yield "truncated", SKELETON[: len(SKELETON) // 2]
    yield "garbage", "\x00\x01 binary junk \xff"
    yield "empty", ""
    yield "wrong-root", "<mesh><submeshes/></mesh>"
    yield "no-bones", "<skeleton><bones/></skeleton>"
    yield "nan-position", SKELETON.replace('<position x="0" y="20" z="0"/>', '<position x="0" y="nan" z="0"/>')
    yield "overflow", SKELETON.replace('<position x="0" y="20" z="0"/>', '<position x="0" y="1e308" z="0"/>').replace('<position x="0" y="50" z="0"/>', '<position x="0" y="1e308" z="0"/>')
    yield "text-angle", SKELETON.replace('angle="1.5707963267948966"><axis x="0" y="1"', 'angle="ninety"><axis x="0" y="1"')
    yield "missing-position", SKELETON.replace('<position x="0" y="50" z="0"/>', "")
    yield "missing-attribute", SKELETON.replace('<position x="10" y="30" z="0"/>', '<position x="10" y="30"/>')
    yield "unknown-parent", SKELETON.replace('parent="Spine"/>\n    <boneparent bone="Spine"', 'parent="Neck"/>\n    <boneparent bone="Spine"')
    yield "cycle", SKELETON.replace('<boneparent bone="Spine" parent="Hips"/>',
                                    '<boneparent bone="Spine" parent="Head"/>')
    yield "two-parents", SKELETON.replace("</bonehierarchy>", '<boneparent bone="Head" parent="Hips"/></bonehierarchy>')
    yield "duplicate-bone", SKELETON.replace('name="Arm"', 'name="Head"')
    yield "unknown-track-bone", SKELETON.replace('<track bone="Hips">', '<track bone="Tail">')
    yield "zero-axis", SKELETON.replace('<rotate angle="1.5707963267948966"><axis x="0" y="0" z="1"/>',
                                        '<rotate angle="1.5707963267948966"><axis x="0" y="0" z="0"/>')
    yield "negative-length", SKELETON.replace('length="1"', 'length="-1"')
    yield "inf-key-time", SKELETON.replace('keyframe time="0.5"><translate x="30"', 'keyframe time="inf"><translate x="30"')


MALFORMED = dict(_malformed_cases())


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_input_exits_2_with_one_line(tmp_path, capsys, name):
    assert_info_exits_2(write_case(tmp_path, name, MALFORMED[name], ".skeleton.xml"), capsys)


def test_malformed_input_through_the_installed_command(tmp_path):
    paths = [write_case(tmp_path, name, MALFORMED[name], ".skeleton.xml")
             for name in ("garbage", "nan-position", "cycle", "unknown-parent")]
    label = OGRE_LABELS[0] if OGRE_LABELS else None
    if label:
        data = corpus_file(label["file"]).read_bytes()
        paths.append(write_case(tmp_path, "cut", data[: len(data) // 3], ".skeleton.xml"))
    assert_cli_exits_2(paths)


def test_absurd_animation_length_is_refused_before_sampling(tmp_path):
    path = tmp_path / "long.skeleton.xml"
    path.write_text(SKELETON.replace('length="1"', 'length="1e9"'))
    with pytest.raises(infuse.UnusableInputError, match="too long"):
        infuse.load(path)
