"""The BVH reader and writer on generated files: channel orders and subsets, position channels on
any joint, several roots, odd whitespace, units and up axis, and writing assets that have rest
rotations."""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import infuse
from infuse import Asset, Motion, Skeleton
from infuse import quaternions as quat
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS
from infuse.kinematics import end_site_positions, motion_fk

from bvh_reference import matrix_chain_positions, parse_raw

rng = np.random.default_rng(11)
ORDERS = ["".join(p) for p in itertools.permutations("XYZ")]


def _joint_text(name, offset, channels, depth, keyword="JOINT"):
    pad = "\t" * depth
    lines = [f"{pad}{keyword} {name}", f"{pad}{{", f"{pad}\tOFFSET {offset[0]:.6f} {offset[1]:.6f} {offset[2]:.6f}"]
    if channels:
        lines.append(f"{pad}\tCHANNELS {len(channels)} {' '.join(channels)}")
    return lines


def _document(joints, frames, sites=(), frame_time=0.04):
    """BVH text from ``joints`` = [(name, parent, offset, channels)] in depth-first order, random values."""
    depth = {}
    lines = ["HIERARCHY"]
    open_stack: list[int] = []
    site_of = {p: off for p, off in sites}

    def close_to(d):
        while open_stack and depth[open_stack[-1]] >= d:
            j = open_stack.pop()
            pad = "\t" * depth[j]
            if j in site_of:
                o = site_of[j]
                lines.extend([f"{pad}\tEnd Site", f"{pad}\t{{", f"{pad}\t\tOFFSET {o[0]} {o[1]} {o[2]}", f"{pad}\t}}"])
            lines.append(f"{pad}}}")

    for i, (name, parent, offset, channels) in enumerate(joints):
        depth[i] = 0 if parent < 0 else depth[parent] + 1
        close_to(depth[i])
        lines += _joint_text(name, offset, channels, depth[i], "ROOT" if parent < 0 else "JOINT")
        open_stack.append(i)
    close_to(0)
    width = sum(len(j[3]) for j in joints)
    values = rng.uniform(-170, 170, (frames, width))
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in values]
    return "\n".join(lines) + "\n"


def _rotations(order):
    return [f"{a}rotation" for a in order]


def _mixed_document(frames=12):
    pos = ["Xposition", "Yposition", "Zposition"]
    joints = [
        ("Hips", -1, (0, 95, 0), pos + _rotations("ZXY")),
        ("Spine", 0, (0, 12, 1), _rotations("XYZ")),
        ("Chest", 1, (0, 15, 0), ["Yposition"] + _rotations("YZX")),     # a subset of positions
        ("Neck", 2, (0, 20, -2), _rotations("XZ")),                       # two rotation channels
        ("Head", 3, (0, 8, 1), _rotations("Y")),                          # one
        ("LeftArm", 2, (15, 10, 0), _rotations("ZYX") + pos),             # positions after rotations
        ("LeftForeArm", 5, (25, 0, 0), []),                               # no channels at all
        ("RightArm", 2, (-15, 10, 0), pos[::-1] + _rotations("YXZ")),
        ("LeftLeg", 0, (9, -5, 0), _rotations("XZY")),
        ("Prop", -1, (40, 0, 30), pos + _rotations("ZXY")),               # a second root
        ("PropTip", 9, (0, 10, 0), _rotations("ZYX")),
    ]
    sites = [(4, (0, 12, 0)), (6, (22, 0, 0)), (8, (0, -80, 0)), (10, (0, 5, 0))]
    for j in joints:
        rot = "".join(c[0] for c in j[3] if c.endswith("rotation"))
        assert rot in ORDERS or len(rot) < 3
    return _document(joints, frames, sites)


def _load_text(tmp_path, text, name="m.bvh", **options):
    path = tmp_path / name
    path.write_bytes(text.encode())
    return infuse.load(path, **options)


def test_any_channel_order_subset_and_root_match_the_matrix_chain(tmp_path):
    text = _mixed_document()
    asset = _load_text(tmp_path, text, units="cm", up_axis="Y")
    assert asset.units_detected_by == "override"
    motion = next(iter(asset.motions.values()))
    raw = parse_raw(text)
    reference = matrix_chain_positions(raw) * 0.01
    _, pos = motion_fk(motion)
    order = [asset.skeleton.index[j["name"]] for j in raw["joints"]]
    assert np.abs(pos[:, order] - reference).max() < 1e-9
    assert list(asset.skeleton.roots) == [0, asset.skeleton.index["Prop"]]
    assert asset.meta["channels"]["Chest"][0] == "Yposition" and asset.meta["channels"]["LeftForeArm"] == []
    assert motion.fps == pytest.approx(25.0)


def test_every_euler_order_is_intrinsic_first_axis_outermost(tmp_path):
    for order in ORDERS:
        joints = [("Root", -1, (0, 90, 0), _rotations(order)), ("Tip", 0, (0, 80, 0), [])]
        text = _document(joints, 5, sites=[(1, (0, 10, 0))])
        asset = _load_text(tmp_path, text, units="cm", up_axis="Y")
        motion = next(iter(asset.motions.values()))
        angles = parse_raw(text)["values"]
        expected = Rotation.from_euler(order, angles, degrees=True).as_quat()  # upper case: intrinsic
        assert np.allclose(quat.canonical_sign(motion.local_rotations[:, 0]), quat.canonical_sign(expected), atol=1e-12)


def test_crlf_tabs_and_odd_whitespace(tmp_path):
    text = _mixed_document()
    odd = text.replace("\n", "\r\n").replace("\t", " \t ").replace("OFFSET ", "OFFSET\t\t").replace("Frames: ", "Frames:\t")
    odd = odd.replace("JOINT Spine\r\n \t {", "JOINT Spine {")  # a brace on the joint's line
    odd = "\r\n\r\n" + odd + "\r\n   \r\n"
    plain = _load_text(tmp_path, text, "plain.bvh", units="cm", up_axis="Y")
    messy = _load_text(tmp_path, odd, "messy.bvh", units="cm", up_axis="Y")
    assert messy.skeleton.names == plain.skeleton.names
    (_, p1), (_, p2) = motion_fk(next(iter(plain.motions.values()))), motion_fk(next(iter(messy.motions.values())))
    assert np.array_equal(p1, p2)
    assert np.allclose(messy.skeleton.end_site_offsets, plain.skeleton.end_site_offsets)


def test_end_sites_and_joint_names_with_spaces(tmp_path):
    joints = [("Bip01 Pelvis", -1, (0, 100, 0), ["Xposition", "Yposition", "Zposition"] + _rotations("ZXY")),
              ("Bip01 L Thigh", 0, (10, 0, 0), _rotations("ZXY"))]
    asset = _load_text(tmp_path, _document(joints, 3, sites=[(1, (0, -90, 0))]), units="cm")
    assert asset.skeleton.names == ("Bip01 Pelvis", "Bip01 L Thigh")
    assert list(asset.skeleton.end_site_parents) == [1]
    assert np.allclose(asset.skeleton.end_site_offsets, [[0, -0.9, 0]])
    again = infuse.load(infuse.save(asset, tmp_path / "spaces.bvh"), units="cm")
    assert again.skeleton.names == asset.skeleton.names


def _human(up="Y", scale=1.0):
    """A small humanoid (name, parent, offset) in centimetres with the given up axis."""
    joints = [("Hips", -1, (0, 95, 0)), ("Spine", 0, (0, 25, 0)), ("Head", 1, (0, 45, 5)),
              ("LArm", 1, (20, 35, 0)), ("LHand", 3, (55, 0, 0)), ("RArm", 1, (-20, 35, 0)),
              ("RHand", 5, (-55, 0, 0)), ("LLeg", 0, (10, -5, 0)), ("LFoot", 7, (0, -85, 5)),
              ("RLeg", 0, (-10, -5, 0)), ("RFoot", 9, (0, -85, 5))]
    out = []
    for name, parent, (x, y, z) in joints:
        offset = (x, y, z) if up == "Y" else (x, -z, y)  # the core's (x, y, z) in a right-handed Z-up file
        out.append((name, parent, tuple(v * scale for v in offset),
                    (["Xposition", "Yposition", "Zposition"] if parent < 0 else []) + _rotations("ZXY")))
    return out


def _small_motion_document(joints, frames=6, head_size=10.0):
    """A clip on ``joints`` that stays near its rest pose: small angles, positions near the offsets."""
    text = _document(joints, frames, sites=[(2, (0, head_size, 0))])
    raw = parse_raw(text)
    values = raw["values"] * 0.05
    col = 0
    for j in raw["joints"]:
        for c in j["channels"]:
            if c.endswith("position"):
                values[:, col] = j["offset"]["XYZ".index(c[0])] + rng.normal(scale=1.0, size=frames)
            col += 1
    rows = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in values)
    return text.split("MOTION\n")[0] + f"MOTION\nFrames: {frames}\nFrame Time: 0.04\n{rows}\n"


@pytest.mark.parametrize("unit,scale", [("cm", 1.0), ("m", 0.01), ("mm", 10.0), ("dm", 0.1), ("inch", 1 / 2.54),
                                        ("cmu", 0.45 / 2.54), ("ft", 1 / 30.48)])
def test_unit_is_guessed_from_the_figure_size(tmp_path, unit, scale):
    asset = _load_text(tmp_path, _small_motion_document(_human(scale=scale), head_size=10 * scale))
    assert (asset.source_units, asset.units_detected_by, asset.source_up_axis) == (unit, "guess", "Y")
    assert 1.5 < asset.skeleton.height() < 2.2
    forced = _load_text(tmp_path, _small_motion_document(_human(scale=scale), head_size=10 * scale), units="inch")
    assert forced.source_units == "inch" and forced.units_detected_by == "override"
    assert forced.skeleton.height() / asset.skeleton.height() == pytest.approx(0.0254 / UNIT_SCALES[unit])


def test_z_up_is_detected_and_converted(tmp_path):
    text = _small_motion_document(_human(up="Z"))
    asset = _load_text(tmp_path, text)
    assert asset.source_up_axis == "Z"
    motion = next(iter(asset.motions.values()))
    _, pos = motion_fk(motion)
    raw = parse_raw(text)
    reference = quat.rotate(UP_AXIS_ROTATIONS["Z"], matrix_chain_positions(raw) * 0.01)
    order = [asset.skeleton.index[j["name"]] for j in raw["joints"]]
    assert np.abs(pos[:, order] - reference).max() < 1e-9
    head, foot = asset.skeleton.index["Head"], asset.skeleton.index["LFoot"]
    assert np.all(pos[:, head, 1] - pos[:, foot, 1] > 1.2)  # upright in the core frame
    kept = _load_text(tmp_path, text, up_axis="Y")
    assert kept.source_up_axis == "Y"
    # Written back, the file is Z up again and reads to the same positions.
    again = infuse.load(infuse.save(asset, tmp_path / "zup.bvh"))
    assert again.source_up_axis == "Z"
    assert np.abs(motion_fk(next(iter(again.motions.values())))[1] - pos).max() < 1e-6


def test_rest_pose_only_file_and_zero_frames(tmp_path):
    joints = [(n, p, o, c) for n, p, o, c in _human()]
    text = _document(joints, 0)
    asset = _load_text(tmp_path, text)
    assert asset.motions == {} and asset.source_units == "cm"
    again = infuse.load(infuse.save(asset, tmp_path / "rest.bvh"))
    motion = next(iter(again.motions.values()))
    assert motion.num_frames == 1
    assert np.allclose(motion_fk(motion)[1][0], asset.skeleton.rest_global_positions, atol=1e-9)


def _skeleton_with_rest_rotations():
    names = ["pelvis", "spine", "head", "l_arm", "l_hand", "r_arm", "l_leg", "l_foot", "tool", "tool_tip"]
    parents = [-1, 0, 1, 1, 3, 1, 0, 6, -1, 8]  # breadth-first-ish order, two roots
    offsets = np.array([[0, 0.95, 0], [0, 0.25, 0], [0, 0.45, 0.05], [0.2, 0.35, 0], [0.55, 0, 0],
                        [-0.2, 0.35, 0], [0.1, -0.05, 0], [0, -0.85, 0.05], [0.4, 0.0, 0.3], [0, 0.1, 0]])
    rest_rotations = Rotation.random(len(names), random_state=5).as_quat()
    return Skeleton(names, parents, offsets, rest_rotations, end_site_parents=[2, 4, 7], end_site_offsets=[[0, 0.1, 0], [0.05, 0, 0], [0, 0, 0.1]])


def test_writer_bakes_rest_rotations_and_keeps_positions(tmp_path):
    sk = _skeleton_with_rest_rotations()
    frames = 20
    rots = Rotation.random(frames * sk.num_joints, random_state=9).as_quat().reshape(frames, sk.num_joints, 4)
    root = rng.normal(scale=0.3, size=(frames, 3)) + [0, 0.95, 0]
    jt = np.broadcast_to(sk.rest_translations, (frames, sk.num_joints, 3)).copy()
    jt[:, 4] += rng.normal(scale=0.02, size=(frames, 3))  # an animated translation
    jt[:, 8] += rng.normal(scale=0.1, size=(frames, 3))   # the second root moves too
    motion = Motion(sk, 24.0, rots, root, jt, name="clip")
    asset = Asset(path=None, format="gltf", skeleton=sk, motions={"clip": motion})
    out = infuse.save(asset, tmp_path / "baked.bvh")
    text = out.read_text()
    assert "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" in text
    assert text.count("CHANNELS 6") == 3  # two roots and the joint with animated translation
    assert "Frame Time: 0.041666666666666664" in text
    assert "\tOFFSET 0 95 0\n" in text  # centimetres, +Y up: the writer's documented choice
    again = infuse.load(out, units="cm", up_axis="Y")  # random poses: no guessing
    assert np.allclose(again.skeleton.rest_rotations[:, 3], 1.0)  # BVH has no rest rotations
    g1, p1 = motion_fk(motion)
    g2, p2 = motion_fk(next(iter(again.motions.values())))
    order = [again.skeleton.index[n] for n in sk.names]
    assert np.abs(p1 - p2[:, order]).max() < 1e-6
    s1, s2 = end_site_positions(sk, g1, p1), end_site_positions(again.skeleton, g2, p2)
    assert np.abs(s1 - s2).max() < 1e-6
    # Global rotations differ exactly by the rest rotations that were folded away.
    assert np.allclose(np.abs(np.sum(quat.multiply(g2[:, order], sk.rest_global_rotations) * g1, axis=-1)), 1.0, atol=1e-6)


def test_a_motion_is_saved_as_a_file_of_its_skeleton(tmp_path):
    sk = _skeleton_with_rest_rotations()
    rots = Rotation.random(5 * sk.num_joints, random_state=4).as_quat().reshape(5, sk.num_joints, 4)
    motion = Motion(sk, 30.0, rots, np.tile([0.0, 0.95, 0.0], (5, 1)), name="wave")
    again = infuse.load(infuse.save(motion, tmp_path / "wave.bvh"), units="cm", up_axis="Y")
    out = next(iter(again.motions.values()))
    order = [again.skeleton.index[n] for n in sk.names]
    assert np.abs(motion_fk(motion)[1] - motion_fk(out)[1][:, order]).max() < 1e-6
    with pytest.raises(infuse.errors.UsageError, match="wave.bvh: save writes an Asset or a Motion, not a dict"):
        infuse.save({"clip": motion}, tmp_path / "wave.bvh")


def test_writer_adds_channels_an_edited_motion_needs(tmp_path):
    joints = [("Hips", -1, (0, 95, 0), ["Xposition", "Yposition", "Zposition"] + _rotations("ZXY")),
              ("Spine", 0, (0, 25, 0), _rotations("XZ")), ("Head", 1, (0, 45, 0), [])]
    asset = _load_text(tmp_path, _document(joints, 4, sites=[(2, (0, 10, 0))]), units="cm", up_axis="Y")
    motion = next(iter(asset.motions.values()))
    rots = np.array(motion.local_rotations)
    rots[:, 1] = Rotation.random(4, random_state=2).as_quat()  # needs all three axes now
    rots[:, 2] = Rotation.random(4, random_state=3).as_quat()  # had no channels
    jt = motion.local_translations()
    jt[:, 2] += [0.0, 0.05, 0.0]
    edited = motion.replace(local_rotations=rots, joint_translations=jt)
    asset.motions = {edited.name: edited}
    again = infuse.load(infuse.save(asset, tmp_path / "edited.bvh"), units="cm", up_axis="Y")
    assert again.meta["channels"]["Spine"] == ["Xrotation", "Zrotation", "Yrotation"]
    assert again.meta["channels"]["Head"] == ["Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"]
    assert np.abs(motion_fk(edited)[1] - motion_fk(next(iter(again.motions.values())))[1]).max() < 1e-6


def test_bandai_style_position_channels_on_every_joint(tmp_path):
    pos = ["Xposition", "Yposition", "Zposition"]
    joints = [(n, p, o, pos + c[-3:]) for n, p, o, c in _human()]
    text = _small_motion_document(joints)
    asset = _load_text(tmp_path, text)
    motion = next(iter(asset.motions.values()))
    assert motion.joint_translations is not None
    raw = parse_raw(text)
    assert np.allclose(motion.joint_translations[:, 3], raw["values"][:, 6 * 3:6 * 3 + 3] * 0.01)
    order = [asset.skeleton.index[j["name"]] for j in raw["joints"]]
    assert np.abs(motion_fk(motion)[1][:, order] - matrix_chain_positions(raw) * 0.01).max() < 1e-9


def test_unknown_overrides_are_input_errors_naming_the_file(tmp_path):
    text = _small_motion_document(_human())
    for options, place in (({"units": "furlong"}, "units"), ({"up_axis": "W"}, "up_axis")):
        with pytest.raises(infuse.InputError) as info:
            _load_text(tmp_path, text, **options)
        assert info.value.place == place and info.value.file.endswith("m.bvh")
