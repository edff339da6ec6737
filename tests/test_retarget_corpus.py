"""Retargeting real clips onto real characters: the quality targets on a representative subset.

Mappings come from the corpus labels, so these checks measure the retargeter alone (the CLI tests
go through the mapper). Targets: foot skate <= source x 1.1 + 0.5 cm/m, bone-direction error
<= 5 degrees on body joints, reachable IK goals met within 1 mm, and no popping: every mapped
joint's largest turn between frames at most 1.5 x the source's + 10 degrees.
"""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.kinematics import motion_fk
from infuse_retarget import RetargetPlan, retarget_clip
from infuse_retarget.quality import evaluate, reach_error

from corpus_data import corpus_file, labels, require_corpus

BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_{}_001.bvh"
UTAH = "smartbody/behaviorsets/MaleLocomotion/"
XBOT = "runxaway-models/Xbot.glb"
ROBOT = "adibkn1-robot/RobotExpressive.glb"
CMU = "bvh11/resources/131_03.bvh"
REACH = "smartbody/behaviorsets/reaching/motions/ChrHarmony_Relax001_ArmReachLfMidHigh.skm"
PAIRS = [
    (BANDAI.format("walk_normal"), XBOT),
    (BANDAI.format("walk_feminine"), UTAH + "skeletons/test_utah.sk"),
    (BANDAI.format("run_masculinity"), CMU),
    (BANDAI.format("walk_masculinity"), ROBOT),
    (BANDAI.format("dash_feminine"), XBOT),
    (BANDAI.format("dash_normal"), CMU),
    (UTAH + "motions/ChrUtah_Walk001.skm", BANDAI.format("walk_normal")),
    (UTAH + "motions/ChrUtah_Run001.skm", XBOT),
]


def label_map(rel: str) -> dict[str, str]:
    for doc in labels():
        if doc["file"] == rel:
            return {k: v for k, v in doc["mapping"].items() if v is not None}
    pytest.fail(f"no label for {rel}")


@pytest.fixture(scope="module")
def loaded():
    require_corpus()
    cache = {}

    def get(rel):
        if rel not in cache:
            asset = infuse.load(corpus_file(rel))
            cache[rel] = (asset, label_map(rel), next(iter(asset.motions.values()), None))
        return cache[rel]

    return get


def plan_for(loaded, src: str, tgt: str) -> tuple[RetargetPlan, infuse.Motion]:
    _, s_map, clip = loaded(src)
    t_asset, t_map, t_clip = loaded(tgt)
    return RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip, target_motion=t_clip), clip


@pytest.fixture(scope="module")
def qualities(loaded):
    return {(src, tgt): evaluate(*plan_for(loaded, src, tgt)) for src, tgt in PAIRS}


@pytest.mark.parametrize("src,tgt", PAIRS, ids=[f"{s.rsplit('/', 1)[-1]}->{t.rsplit('/', 1)[-1]}" for s, t in PAIRS])
def test_quality_targets(qualities, src, tgt):
    q = qualities[(src, tgt)]
    assert q.skate_final <= q.skate_limit(), q
    assert q.bones_final <= 5.0 and q.bones_plain <= 1.0, q
    assert q.residual_mm <= 1.0, q
    assert abs(q.speed_ratio - 1.0) < 0.02, q  # the root travels at source speed x leg scale
    assert q.penetration_final < 1.0 and q.float_final < 2.5, q
    assert q.unreachable < 0.25, q
    assert q.popping_final.ok, q.popping_final


def test_contacts_beat_the_paper_and_the_plain_transfer(qualities):
    """Pinned contacts leave less skate than the paper's warping, which leaves less than no IK, over the subset."""
    final = sum(q.skate_final for q in qualities.values())
    paper = sum(q.skate_paper for q in qualities.values())
    plain = sum(q.skate_plain for q in qualities.values())
    assert final < 0.2 * paper and paper < plain
    assert all(q.skate_final <= q.skate_source + 0.05 for q in qualities.values())


def test_default_pose_comes_from_the_clip_for_a_lying_rest(loaded):
    plan, _ = plan_for(loaded, BANDAI.format("walk_normal"), XBOT)
    assert plan.source.pose_from.startswith("frame") and plan.target.pose_from == "rest"
    assert 1.05 < plan.scale < 1.2  # X Bot's legs are a little longer than the Bandai actor's


def test_robot_feet_hung_from_the_ground_bone_follow_the_shins(loaded):
    """RobotExpressive's feet are children of its ground bone: they get translations that keep them
    at the shins' ends, as in its rest pose."""
    plan, clip = plan_for(loaded, BANDAI.format("walk_normal"), ROBOT)
    out = retarget_clip(plan, clip).motion
    assert out.joint_translations is not None
    sk = out.skeleton
    _, pos = motion_fk(out)
    for side in "LR":
        foot, shin_end = sk.index[f"Foot{side}"], sk.index[f"LowerLeg{side}_end"]
        rest = np.linalg.norm(sk.rest_global_positions[foot] - sk.rest_global_positions[shin_end])
        assert np.allclose(np.linalg.norm(pos[:, foot] - pos[:, shin_end], axis=1), rest, atol=1e-6)


def test_sternoclavicular_reach_moves_the_single_clavicle(loaded):
    """The SmartBody reaches turn l_sternoclavicular (not in any label): X Bot's one clavicle follows."""
    asset, _, clip = loaded(REACH)
    from infuse.mapping import map_skeleton

    s_map = {k: v for k, v in label_map(UTAH + "skeletons/test_utah.sk").items() if v in asset.skeleton.index}
    t_asset, t_map, _ = loaded(XBOT)
    plan = RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip)
    out = retarget_clip(plan, clip, ik="none").motion
    _, ps = motion_fk(clip)
    _, po = motion_fk(out)
    src = asset.skeleton.index
    tgt = t_asset.skeleton.index
    v_s = ps[:, src["l_shoulder"]] - ps[:, src["l_sternoclavicular"]]
    v_o = po[:, tgt[t_map["l_shoulder"]]] - po[:, tgt[t_map["l_acromioclavicular"]]]
    turn_s = np.degrees(quat.angle_between(quat.between(v_s[:1], v_s), quat.IDENTITY))
    turn_o = np.degrees(quat.angle_between(quat.between(v_o[:1], v_o), quat.IDENTITY))
    assert turn_s.max() > 3.0  # the clip really moves the clavicle
    assert np.abs(turn_o - turn_s).max() < 1.0
    assert map_skeleton is not None


def test_limb_scaling_reaches_like_the_source(loaded):
    """On a character whose upper arm is 30% longer than its forearm, scaling by extension makes the
    hand reach as far, relative to the arm, as the source's."""
    asset, _, clip = loaded(REACH)
    s_map = {k: v for k, v in label_map(UTAH + "skeletons/test_utah.sk").items() if v in asset.skeleton.index}
    t_asset, t_map, _ = loaded(CMU)
    plan = RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip)
    plain = retarget_clip(plan, clip)
    scaled = retarget_clip(plan, clip, limb_scaling=True)
    before = reach_error(plan, plain.motion, plain.source_positions)
    after = reach_error(plan, scaled.motion, scaled.source_positions)
    assert before > 0.5 and after < 0.1 * before
    # The relaxed arm hangs straight: its goals sit at the edge of reach, and are met.
    assert scaled.residual[t_map["l_wrist"]].max() < 1e-3


def _distinct_rigs() -> list[str]:
    """One labelled humanoid file per distinct (convention, mapping), legs mapped."""
    seen, out = set(), []
    for doc in labels():
        mapping = {k: v for k, v in doc["mapping"].items() if v}
        key = (doc["convention"], tuple(sorted(mapping.items())))
        legs = all(f"{s}_{n}" in mapping for s in "lr" for n in ("hip", "knee", "ankle"))
        if doc["humanoid"] and doc["meta"].get("plain_python") and legs and key not in seen:
            seen.add(key)
            out.append(doc["file"])
    return out


@pytest.mark.parametrize("rel", _distinct_rigs(), ids=lambda rel: rel.rsplit("/", 1)[-1])
def test_walk_onto_every_kind_of_rig(loaded, rel):
    """The Bandai walk onto one rig of every family in the corpus (VRM, Mixamo, Biped, Ogre rigs facing
    -Z and +X, MakeHuman, CMU, SmartBody, Daz, glTF samples...): the targets hold on all of them."""
    q = evaluate(*plan_for(loaded, BANDAI.format("walk_normal"), rel))
    assert q.skate_final <= q.skate_limit() and q.bones_final <= 5.0 and q.residual_mm <= 1.0, q
    assert abs(q.speed_ratio - 1.0) < 0.02, q
    assert q.popping_final.ok, q.popping_final
