"""Swappable mappers: the names mapper, name normalization, and a third-party mapper package."""
from __future__ import annotations

import json

import pytest

import infuse
from infuse import registry
from infuse.canonical import CANONICAL_NAMES, canonical_skeleton
from infuse.cli import main as cli_main
from infuse.mapping import map_skeleton
from infuse_heuristic_mapper.names import analyse, common_prefix

from corpus_data import corpus_file, labels, require_corpus


@pytest.mark.parametrize("name, side, role, flag", [
    ("mixamorig:LeftHandIndex4_end", 1, "index", "end"),
    ("Bip01 R Finger01", -1, "finger", None),
    ("JtForearmTwistALf", 1, "forearm", "twist"),
    ("lhumerus", 1, "upperarm", None),
    ("LHipJoint", 1, None, "helper"),
    ("LeftHip", 1, "thigh", None),
    ("Hip", 0, "hips", None),
    ("thigh_twist_01_r", -1, "thigh", "twist"),
    ("J_Bip_L_UpperArm", 1, "upperarm", None),
    ("J_Sec_R_SkirtBack0_01", -1, None, "secondary"),
    ("Ctrl_Hand_IK_Left", 1, "hand", "control"),
    ("hand.R.001", -1, "hand", None),
    ("DEF-forearm.L", 1, "forearm", None),
    ("CC_Base_L_Upperarm", 1, "upperarm", None),
    ("__LeftShoulder", 1, "shoulder", "helper"),
    ("leftThumbMetacarpal", 1, "thumb", "metacarpal"),
    ("左腕", 1, "upperarm", None),
    ("右ひじ", -1, "forearm", None),
    ("右大腿", -1, "thigh", None),
    ("HeadTop_End", 0, None, "end"),
])
def test_name_tokens(name, side, role, flag):
    info = analyse(name)
    assert info.side == side
    if role:
        assert role in info.roles
    if flag:
        assert flag in info.flags


def test_common_prefix():
    names = ["rig_Hips", "rig_Spine", "rig_Spine1", "rig_Neck", "rig_Head", "rig_LeftArm", "rig_RightArm",
             "rig_LeftLeg", "rig_RightLeg", "rig_LeftFoot", "Armature"]
    assert common_prefix(names) == "rig_"  # shared by at least 90% of the names
    info = analyse("rig_LeftArm", "rig_")
    assert info.tokens == ("arm",) and info.side == 1 and "upperarm" in info.roles
    assert common_prefix(["Hips", "Spine", "Head"]) == ""


def _label(fragment):
    return next(d for d in labels() if fragment in d["file"])


@pytest.mark.parametrize("fragment", ["Xbot.glb", "SK_Mannequin", "Ubiq_Robot_Rocketbox", "example.bvh", "131_01.bvh",
                                      "01.asf", "ChrBrad/ChrBrad.sk", "test_utah.sk", "DAZFriendlyCMU", "makehuman.bvh",
                                      "test.vrma", "dataset-1_walk_normal_001"])
def test_names_mapper_on_known_conventions(fragment):
    require_corpus()
    label = _label(fragment)
    mapping = map_skeleton(infuse.load(corpus_file(label["file"])), mapper="names")
    alts = label.get("alternatives") or {}
    wrong = [k for k in CANONICAL_NAMES if mapping[k] != label["mapping"][k] and mapping[k] not in alts.get(k, [])]
    assert len(wrong) <= 2, wrong
    assert mapping.mapper == "names"


def test_names_mapper_uses_the_vrm_humanoid_map():
    require_corpus()
    asset = infuse.load(corpus_file(_label("test.vrma")["file"]))
    humanoid = asset.humanoid
    renamed = {bone: node for bone, node in humanoid.items()}
    mapping = map_skeleton(asset, mapper="names")
    assert "VRM humanoid map" in mapping.reasons["base"]
    assert mapping["base"] == renamed["hips"] and mapping["l_shoulder"] == renamed["leftUpperArm"]


def test_names_mapper_refuses_unknown_names():
    sk = canonical_skeleton()
    odd = infuse.Skeleton(tuple(f"bone{i}" for i in range(sk.num_joints)), sk.parents, sk.rest_translations,
                          sk.rest_rotations)
    with pytest.raises(infuse.NotHumanoidError, match="naming convention"):
        map_skeleton(odd, mapper="names")


def test_mappers_are_plugins():
    table = registry.mappers()
    assert {"heuristic", "names"} <= set(table)
    records = {(r.name, r.kind): r for r in registry.plugins().records}
    assert records[("heuristic", "mapper")].distribution == "infuse-anim-heuristic-mapper"
    assert records[("names", "mapper")].distribution == "infuse-anim-names-mapper"


def test_third_party_mapper_is_picked_up(capsys, tmp_path):
    """examples/third_party_mapper registers 'studio-prefix' through its own entry point."""
    records = {(r.name, r.kind): r for r in registry.plugins().records}
    assert ("studio-prefix", "mapper") in records, "install examples/third_party_mapper (make setup)"
    assert records[("studio-prefix", "mapper")].distribution == "infuse-anim-example-mapper"
    assert cli_main(["plugins"]) == 0
    listing = capsys.readouterr().out
    assert any("studio-prefix" in line and "mapper" in line and "infuse-anim-example-mapper" in line
               for line in listing.splitlines())
    # a skeleton using the studio's names for a few joints: those win, the rest comes from the default mapper
    sk = canonical_skeleton(extras=False)
    names = [("c_" + n) if n in ("base", "l_wrist", "r_wrist") else n.upper() for n in sk.names]
    studio = infuse.Skeleton(tuple(names), sk.parents, sk.rest_translations, sk.rest_rotations)
    bvh = tmp_path / "studio.bvh"
    from test_mapping_core import _bvh_of
    _bvh_of(studio, bvh)
    assert cli_main(["map", str(bvh), "--mapper", "studio-prefix", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["mapping"]["base"] == "c_base" and doc["mapping"]["l_wrist"] == "c_l_wrist"
    assert doc["mapping"]["l_elbow"] == "L_ELBOW" and doc["mapping"]["r_hip"] == "R_HIP"


def test_third_party_mapper_never_gives_a_studio_joint_twice():
    """A studio name that contradicts the geometry wins, and the default mapper's pick of that joint goes."""
    sk = canonical_skeleton(extras=False)
    names = ["c_l_wrist" if n == "l_forearm" else n.upper() for n in sk.names]  # the twist joint called the wrist
    studio = infuse.Skeleton(tuple(names), sk.parents, sk.rest_translations, sk.rest_rotations)
    plain = map_skeleton(studio, mapper="heuristic")
    assert plain["l_forearm"] == "c_l_wrist"  # by geometry, without the studio's word
    mapping = map_skeleton(studio, mapper="studio-prefix")
    assert mapping["l_wrist"] == "c_l_wrist" and mapping.reasons["l_wrist"] == "studio name 'c_l_wrist'"
    assert mapping["l_forearm"] is None and "by hand" in mapping.reasons["l_forearm"]
    used = list(mapping.mapped().values())
    assert len(used) == len(set(used))


@pytest.mark.parametrize("name, side, role, flag", [
    ("leftarm", 1, "upperarm", None), ("rightupleg", -1, "thigh", None), ("BrasGauche", 1, "upperarm", None),
    ("mano_der", -1, "hand", None), ("r-ARMCONTROL", -1, "upperarm", "control"),
    ("COM_LeftForeArm", 1, "forearm", "helper"), ("LeftAcromion", 1, None, "helper"), ("Wing1.L", 1, None, "secondary"),
])
def test_glued_and_foreign_names(name, side, role, flag):
    """Words written together are split, a few other languages are known, landmarks and segment
    centres of mass are helpers, wings are not limbs."""
    info = analyse(name)
    assert info.side == side
    assert role is None or role in info.roles
    assert flag is None or flag in info.flags
