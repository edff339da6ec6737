"""The heuristic mapper on the hard cases of the mapping issue, one test each, on real corpus
skeletons (as read) and on skeletons generated from them or from the canonical skeleton."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.canonical import BODY_NAMES, CANONICAL_NAMES, canonical_skeleton
from infuse.mapping import map_skeleton, sample_poses

import skeleton_variants
from corpus_data import corpus_file, labels, require_corpus


@lru_cache(maxsize=None)
def _label(fragment: str) -> dict:
    matches = [d for d in labels() if fragment in d["file"]]
    assert len(matches) >= 1, fragment
    return matches[0]


@lru_cache(maxsize=None)
def _asset(fragment: str):
    require_corpus()
    return infuse.load(corpus_file(_label(fragment)["file"]))


def _wrong(joints: dict, label: dict, names=CANONICAL_NAMES) -> list:
    alts = label.get("alternatives") or {}
    return [(k, joints.get(k), label["mapping"][k]) for k in names
            if joints.get(k) != label["mapping"][k] and joints.get(k) not in alts.get(k, [])]


def _check_file(fragment: str, names=CANONICAL_NAMES):
    mapping = map_skeleton(_asset(fragment))
    assert _wrong(mapping.joints, _label(fragment), names) == []
    return mapping


def _check_variant(variant, names=BODY_NAMES, meta=None):
    joints = map_skeleton(variant.skeleton, pose=variant.poses, meta=meta or {}).joints
    expected = {"mapping": variant.mapping, "alternatives": variant.alternatives}
    assert _wrong(joints, expected, names) == []


def _canonical_variant(positions=None, names=None, drop=()) -> skeleton_variants.Variant:
    """The canonical skeleton (required joints) with other rest positions, other names or joints removed."""
    sk = canonical_skeleton(extras=False)
    pos = sk.rest_global_positions if positions is None else positions
    keep = [i for i, n in enumerate(sk.names) if n not in drop]
    index = {old: new for new, old in enumerate(keep)}
    parents = []
    for i in keep:
        p = int(sk.parents[i])
        while p >= 0 and p not in index:
            p = int(sk.parents[p])
        parents.append(index[p] if p >= 0 else -1)
    rename = {sk.names[i]: (names or {}).get(sk.names[i], sk.names[i]) for i in keep}
    new = skeleton_variants._from_positions([rename[sk.names[i]] for i in keep], parents, pos[keep])
    mapping = {n: (rename[n] if n in rename else None) for n in CANONICAL_NAMES}
    return skeleton_variants.Variant("canonical", new, None, mapping, {}, rename)


# -- up axis, units, facing -------------------------------------------------------------------------------
@pytest.mark.parametrize("rotation", ["z_up", "facing_-z", "facing_+x"])
@pytest.mark.parametrize("fragment", ["Xbot.glb", "SK_Mannequin", "dataset-1_walk_normal_001"])
def test_up_axis_and_facing(fragment, rotation):
    asset = _asset(fragment)
    v = skeleton_variants.transformed(asset.skeleton, sample_poses(asset), _label(fragment), rotation=rotation)
    _check_variant(v, CANONICAL_NAMES)


@pytest.mark.parametrize("unit", ["cm", "dm", "inch"])
def test_units(unit):
    asset = _asset("Ely.glb")
    _check_variant(skeleton_variants.transformed(asset.skeleton, None, _label("Ely.glb"), unit=unit), CANONICAL_NAMES)


def test_real_files_facing_minus_z_and_plus_x():
    _check_file("ninja.skeleton.xml")  # faces -Z: its left is -X
    _check_file("robot.skeleton.xml")  # faces +X: its left is -Z


# -- rest poses ---------------------------------------------------------------------------------------------
def test_t_pose():
    _check_variant(_canonical_variant(), CANONICAL_NAMES)
    _check_file("Xbot.glb")


def test_a_pose():
    sk = canonical_skeleton(extras=False)
    pos = sk.rest_global_positions.copy()
    for side, sign in (("l", 1.0), ("r", -1.0)):
        pivot = pos[sk.index[f"{side}_shoulder"]]
        down = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), -sign * np.radians(45))
        for i, n in enumerate(sk.names):
            if n.startswith(f"{side}_") and n not in (f"{side}_acromioclavicular", f"{side}_hip", f"{side}_knee",
                                                      f"{side}_ankle", f"{side}_forefoot", f"{side}_toe"):
                pos[i] = pivot + quat.rotate(down, pos[i] - pivot)
    assert pos[sk.index["l_wrist"]][1] < pos[sk.index["l_shoulder"]][1] - 0.3
    _check_variant(_canonical_variant(pos), CANONICAL_NAMES)


def test_arbitrary_rest_uses_frames_of_motion():
    # Bandai: every rest offset along the bone's +X, so the rest pose is no body at all
    asset = _asset("dataset-1_walk_normal_001")
    rest = asset.skeleton.rest_global_positions
    assert np.ptp(rest[:, 0]) > np.ptp(rest[:, 1])  # lying along X
    _check_file("dataset-1_walk_normal_001")
    # the same idea on the canonical skeleton: a rest with every bone along +X, a T-pose given as pose
    sk = canonical_skeleton(extras=False)
    flat = np.zeros_like(sk.rest_global_positions)
    for i in range(1, sk.num_joints):
        p = sk.parents[i]
        flat[i] = flat[p] + np.array([np.linalg.norm(sk.rest_translations[i]), 0.0, 0.0])
    v = _canonical_variant(flat)
    v.poses = sk.rest_global_positions
    _check_variant(v, CANONICAL_NAMES)


# -- extra joints -------------------------------------------------------------------------------------------
def test_twist_joints():
    _check_file("SK_Mannequin")  # UE4 *_twist_01 leaves; lowerarm_twist_01 is the canonical forearm
    _check_file("ChrBrad.sk")  # twist joints inside the arm chain, at the elbow and wrist
    asset = _asset("Xbot.glb")
    _check_variant(skeleton_variants.extra_joints(asset.skeleton, None, _label("Xbot.glb")), CANONICAL_NAMES)


def test_ik_targets_and_poles():
    for fragment in ("Soldier.glb", "godotman.glb", "RobotExpressive.glb"):
        _check_file(fragment)


def test_props():
    for fragment in ("ninja.skeleton.xml", "Sinbad.skeleton.xml", "Soldier.glb"):
        _check_file(fragment)


def test_control_rig():
    mapping = _check_file("Paladin.glb")
    assert not any(v.startswith("Ctrl_") for v in mapping.mapped().values())


def test_190_hair_and_skirt_bones():
    asset = _asset("vroid.glb")
    assert sum(n.startswith("J_Sec_") for n in asset.skeleton.names) >= 150
    mapping = _check_file("vroid.glb")
    assert not any(v.startswith("J_Sec_") for v in mapping.mapped().values())


def test_face_bones():
    _check_file("ChrBrad/ChrBrad.sk")
    # a face-only motion file: only the eyes are animated there
    mapping = _check_file("ChrBrad@FV.skm")
    assert set(mapping.mapped()) & set(CANONICAL_NAMES) == {"eyeball_left", "eyeball_right"}
    assert mapping["upper_eyelid_left"] == "JtEyelidUpperLf"  # an extra name, animated there too


def test_root_above_the_hips():
    for fragment in ("dataset-1_walk_normal_001", "SK_Mannequin", "ninja.skeleton.xml", "test_utah.sk"):
        _check_file(fragment)
    asset = _asset("Ely.glb")  # a ground root added above the pelvis
    _check_variant(skeleton_variants.extra_joints(asset.skeleton, None, _label("Ely.glb")), CANONICAL_NAMES)


# -- missing joints -----------------------------------------------------------------------------------------
def test_missing_clavicles():
    mapping = _check_file("CesiumMan.glb")
    assert mapping["l_acromioclavicular"] is None
    v = _canonical_variant(drop=("l_acromioclavicular", "r_acromioclavicular"))
    _check_variant(v, CANONICAL_NAMES)


def test_missing_fingers_toes_and_neck():
    fingers = tuple(f"{s}_{f}{k}" for s in "lr" for f in ("thumb", "index", "middle", "ring", "pinky") for k in (1, 2, 3, 4))
    _check_variant(_canonical_variant(drop=fingers), CANONICAL_NAMES)
    _check_variant(_canonical_variant(drop=("l_forefoot", "l_toe", "r_forefoot", "r_toe")), CANONICAL_NAMES)
    _check_variant(_canonical_variant(drop=("spine4", "spine5")), CANONICAL_NAMES)
    _check_file("Paladin.glb")  # no fingers
    _check_file("AV_8Walk_Meredith")  # one torso joint, no neck


def test_metacarpals():
    mapping = _check_file("makehuman.bvh")
    assert not any("metacarpal" in v for v in mapping.mapped().values())


# -- names --------------------------------------------------------------------------------------------------
def test_misleading_names():
    _check_file("RobotExpressive.glb")  # "Hips" is the first spine joint
    _check_file("godotman.glb")  # hand.L is the clavicle, foot.L.001 the thigh
    _check_file("131_01.bvh")  # CMU 3ds Max names: LeftShoulder is the upper arm


def test_reversed_numbering():
    mapping = _check_file("CesiumMan.glb")
    assert mapping["l_shoulder"].endswith("L__4_") and mapping["l_wrist"].endswith("L__2_")


JAPANESE = {"Hips": "下半身", "Spine": "上半身", "Spine1": "上半身2", "Spine2": "上半身3", "Neck": "首", "Head": "頭",
            "Shoulder": "肩", "Arm": "腕", "ForeArm": "ひじ", "Hand": "手首", "UpLeg": "足", "Leg": "ひざ", "Foot": "足首",
            "ToeBase": "つま先", "HandThumb": "親指", "HandIndex": "人指", "HandMiddle": "中指", "HandRing": "薬指",
            "HandPinky": "小指", "Toe_End": "つま先先", "HeadTop_End": "頭先"}
CHINESE = {"Hips": "骨盆", "Spine": "脊椎", "Spine1": "脊椎1", "Spine2": "胸", "Neck": "颈", "Head": "头", "Shoulder": "锁骨",
           "Arm": "上臂", "ForeArm": "前臂", "Hand": "手腕", "UpLeg": "大腿", "Leg": "小腿", "Foot": "脚踝", "ToeBase": "脚趾",
           "HandThumb": "拇指", "HandIndex": "食指", "HandMiddle": "中指", "HandRing": "无名指", "HandPinky": "小指",
           "Toe_End": "脚趾末端", "HeadTop_End": "头顶端"}


def _translate(name: str, table: dict, left: str, right: str) -> str:
    base = name.split(":")[-1]
    side = ""
    for word, mark in (("Left", left), ("Right", right)):
        if base.startswith(word):
            side, base = mark, base[len(word):]
    digits = "".join(c for c in base if c.isdigit())
    stem = base.rstrip("0123456789")
    if stem not in table:
        return name
    return f"{side}{table[stem]}{digits}"


@pytest.mark.parametrize("table, left, right", [(JAPANESE, "左", "右"), (CHINESE, "左", "右")], ids=["japanese", "chinese"])
def test_cjk_names(table, left, right):
    asset = _asset("Xbot.glb")
    label = _label("Xbot.glb")
    rename = {n: _translate(n, table, left, right) for n in asset.skeleton.names}
    assert len(set(rename.values())) == len(rename)
    sk = infuse.Skeleton(tuple(rename[n] for n in asset.skeleton.names), asset.skeleton.parents,
                         asset.skeleton.rest_translations, asset.skeleton.rest_rotations)
    v = skeleton_variants.Variant("cjk", sk, None, *skeleton_variants._translate(label, rename), rename)
    _check_variant(v, CANONICAL_NAMES)
    # the names alone still tell left from right when the body is turned to face -Z
    turned = skeleton_variants.transformed(sk, None, {"mapping": v.mapping, "alternatives": {}}, rotation="facing_-z")
    _check_variant(turned, CANONICAL_NAMES)


@pytest.mark.parametrize("fragment", ["Ely.glb", "ChrBrad/ChrBrad.sk", "Ubiq_Robot_Rocketbox", "131_01.bvh",
                                      "makehuman.bvh", "dataset-2_walk_normal_001"])
def test_meaningless_names(fragment):
    """Hierarchy and geometry only (joint1..N style names): every body joint still right."""
    asset = _asset(fragment)
    v = skeleton_variants.meaningless(asset.skeleton, sample_poses(asset), _label(fragment))
    _check_variant(v, BODY_NAMES)


def test_extra_names_when_the_rig_has_them():
    """Both ends of the clavicle (SmartBody) and eyelid joints: mapped to the optional extras."""
    utah = map_skeleton(_asset("test_utah.sk"))
    assert utah["l_sternoclavicular"] == "l_sternoclavicular" and utah["l_acromioclavicular"] == "l_acromioclavicular"
    assert utah["upper_eyelid_right"] == "upper_eyelid_right"
    brad = map_skeleton(_asset("ChrBrad/ChrBrad.sk"))
    assert brad["lower_eyelid_left"] == "JtEyelidLowerLf"
    assert brad["l_sternoclavicular"] is None  # one clavicle joint: it is the acromioclavicular one
    assert "l_sternoclavicular" not in map_skeleton(_asset("Xbot.glb")).to_dict(extras=False)["mapping"]


ARMS = tuple(n for n in CANONICAL_NAMES if n[:2] in ("l_", "r_") and n[2:] not in ("hip", "knee", "ankle", "forefoot", "toe"))
LEGS = tuple(f"{s}_{j}" for s in "lr" for j in ("hip", "knee", "ankle", "forefoot", "toe"))


@pytest.mark.parametrize("drop", [ARMS, LEGS], ids=["no_arms", "no_legs"])
@pytest.mark.parametrize("renamed", [False, True], ids=["named", "meaningless"])
def test_bodies_without_legs_or_arms_are_refused(drop, renamed):
    """An upper body without legs, or a body without arms, is not a humanoid: refused with the reason."""
    names = {n: f"j{i}" for i, n in enumerate(CANONICAL_NAMES)} if renamed else None
    variant = _canonical_variant(names=names, drop=drop)
    with pytest.raises(infuse.NotHumanoidError) as err:
        map_skeleton(variant.skeleton)
    assert "two legs and two arms" in err.value.reason


def test_winged_body_is_refused():
    """Two legs and two wings (a bird): the arms' chains are named wings, so not a humanoid."""
    arm_parts = ("acromioclavicular", "shoulder", "elbow", "forearm", "wrist")
    names = {f"{s}_{p}": f"Wing{k}.{s.upper()}" for s in "lr" for k, p in enumerate(arm_parts, start=1)}
    fingers = tuple(n for n in CANONICAL_NAMES if n[2:-1] in ("thumb", "index", "middle", "ring", "pinky"))
    variant = _canonical_variant(names=names, drop=fingers)
    with pytest.raises(infuse.NotHumanoidError) as err:
        map_skeleton(variant.skeleton)
    assert "wings" in err.value.reason and "Wing1.L" in err.value.reason


def test_thighs_on_a_ground_root():
    """Legs parented to a ground root at the feet's level, the pelvis carrying only the spine: the
    body stands and the pelvis is the base."""
    sk = canonical_skeleton(extras=False)
    names = list(sk.names) + ["ground"]
    pos = np.concatenate((sk.rest_global_positions, [[0.0, 0.0, 0.0]]))
    parents = [int(p) for p in sk.parents] + [-1]
    ground = len(names) - 1
    parents[sk.index["base"]] = ground
    for side in "lr":
        parents[sk.index[f"{side}_hip"]] = ground
    skeleton = skeleton_variants._topological(names, parents, list(pos), None)
    new = skeleton_variants._from_positions(skeleton[0], skeleton[1], skeleton[2])
    mapping = map_skeleton(new)
    for name in BODY_NAMES:
        assert mapping[name] == name, (name, mapping[name], mapping.reasons[name])


def test_mirrored_side_names_follow_the_geometry():
    """Every left joint named as the right one and vice versa: the sides follow the body, and the
    reasons say that the names disagree."""
    sk = canonical_skeleton(extras=False)
    label = {"mapping": {n: n for n in CANONICAL_NAMES}}
    variant = skeleton_variants.mirrored_names(sk, None, label)
    mapping = map_skeleton(variant.skeleton)
    assert mapping["l_hip"] == "r_hip" and mapping["r_wrist"] == "l_wrist"
    assert "opposite" in mapping.reasons["l_hip"] and "geometry decides" in mapping.reasons["l_hip"]
    assert mapping.confidence["l_hip"] <= 0.85


def test_long_skirt_chains_do_not_make_a_many_legged_body():
    """Four skirt chains of three joints from the pelvis down to the shins (as long as the legs),
    with names that say nothing: a humanoid in a long skirt, not a many-legged body (its legs stand
    on the ground, the skirt does not)."""
    sk = canonical_skeleton(extras=False)
    names, parents = list(sk.names), [int(p) for p in sk.parents]
    pos = list(sk.rest_global_positions)
    base = sk.index["base"]
    drop = 0.7 * pos[base][1]  # the canonical body stands on y = 0
    for k, (x, z) in enumerate(((0.12, 0.1), (-0.12, 0.1), (0.12, -0.1), (-0.12, -0.1))):
        parent = base
        for step in (1, 2, 3):
            names.append(f"s{k}_{step}")
            parents.append(parent)
            pos.append(pos[base] + np.array([x * step / 2, -drop * step / 3, z]))
            parent = len(names) - 1
    new = skeleton_variants._from_positions(names, parents, np.array(pos))
    mapping = map_skeleton(new)
    for name in BODY_NAMES:
        assert mapping[name] == name, (name, mapping[name], mapping.reasons[name])
