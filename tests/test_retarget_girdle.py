"""Retargeting keeps each character's build: shoulder girdle, trunk and feet move from the target's own rest.

Where a rig puts its clavicle, spine and neck joints, and how steeply its ankle looks down at the
ball, is its build, not its pose: SmartBody's Utah has its clavicle rise 20° then run flat, Brad's
dips 36° then rises 27°. A walk must turn the target's girdle joints from their rest as the source's
turn from theirs, and keep the shoulders at the target's own height below the neck (lining the
short bones up one by one turned Brad's acromioclavicular by 71° and raised his shoulders 4 cm).
"""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton, sample_poses
from infuse_retarget import RetargetPlan, retarget, retarget_clip

from corpus_data import corpus_file, require_corpus
from retarget_helpers import from_globals, identity_map, parts, smooth_clip

UTAH_WALK = "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"
BANDAI_WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
PAIRS = [
    (UTAH_WALK, "smartbody/mesh/brad/Brad.dae"),  # both with two clavicle joints, placed differently
    (UTAH_WALK, "runxaway-models/Xbot.glb"),  # one clavicle joint, played by Utah's sternoclavicular
    (BANDAI_WALK, "smartbody/mesh/doctor/Doctor.dae"),  # a rest lying along X: the default pose from the clip
]
GIRDLE = ("sternoclavicular", "acromioclavicular")


def _load(rel: str):
    """(asset, canonical mapping as the retarget command makes it, first clip or None)."""
    asset = infuse.load(corpus_file(rel))
    mapping = map_skeleton(asset.skeleton, pose=sample_poses(asset), meta=asset.meta, file=asset.path)
    return asset, mapping, next(iter(asset.motions.values()), None)


@pytest.fixture(scope="module")
def walks():
    """{(source, target): (plan, source clip, retargeted clip)} for every pair."""
    require_corpus()
    cache: dict = {}
    out = {}
    for src, tgt in PAIRS:
        for rel in (src, tgt):
            if rel not in cache:
                cache[rel] = _load(rel)
        _, s_map, clip = cache[src]
        t_asset, t_map, t_clip = cache[tgt]
        plan = RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip, target_motion=t_clip)
        out[(src, tgt)] = (plan, clip, retarget_clip(plan, clip).motion)
    return out


def _turn_from_reference(prepared, motion: infuse.Motion, joint: int) -> np.ndarray:
    """(F,) degrees a joint's rotation relative to its parent turns from the default pose's."""
    g, _ = motion_fk(motion)
    parent = motion.skeleton.parents[joint]
    ref = prepared.rig.rotations
    now = quat.multiply(quat.conjugate(g[:, parent]), g[:, joint])
    rest = quat.multiply(quat.conjugate(ref[parent]), ref[joint])
    return np.degrees(quat.angle_between(rest, now))


def _shoulder_drop(prepared, motion: infuse.Motion, side: str) -> np.ndarray:
    """(F,) metres the shoulder joint rises, relative to the neck (spine4), from the default pose."""
    _, p = motion_fk(motion)
    i, ref = prepared.index, prepared.rig.positions
    shoulder, neck = i[f"{side}_shoulder"], i["spine4"]
    return (p[:, shoulder, 1] - p[:, neck, 1]) - (ref[shoulder, 1] - ref[neck, 1])


@pytest.mark.parametrize("src,tgt", PAIRS, ids=[f"{s.rsplit('/', 1)[-1]}->{t.rsplit('/', 1)[-1]}" for s, t in PAIRS])
def test_girdle_turns_from_rest_as_the_source_does(walks, src, tgt):
    plan, clip, out = walks[(src, tgt)]
    checked = 0
    for side in "lr":
        for name in (f"{side}_{g}" for g in GIRDLE):
            if name not in plan.target.index:
                continue
            turned = _turn_from_reference(plan.target, out, plan.target.index[name])
            driver = plan.pairs.get(name)  # a joint the source lacks rides with the one that drives it
            wanted = _turn_from_reference(plan.source, clip, plan.source.index[driver]) if driver else 0.0
            assert np.abs(turned - wanted).max() < 2.0, (name, driver, turned.max())
            checked += 1
    assert checked >= 2


@pytest.mark.parametrize("src,tgt", PAIRS, ids=[f"{s.rsplit('/', 1)[-1]}->{t.rsplit('/', 1)[-1]}" for s, t in PAIRS])
def test_shoulders_keep_their_height_below_the_neck(walks, src, tgt):
    """The shoulder joints stay at the target's own height below the neck, moving as the source's
    move from theirs (scaled by the leg ratio), within a centimetre."""
    plan, clip, out = walks[(src, tgt)]
    for side in "lr":
        drop = _shoulder_drop(plan.target, out, side)
        wanted = plan.scale * _shoulder_drop(plan.source, clip, side)
        assert np.abs(drop - wanted).max() < 0.01, (side, np.abs(drop - wanted).max())
        assert abs(drop.mean()) < 0.005, (side, drop.mean())


def _rebuilt(sk: infuse.Skeleton, moves: dict[str, np.ndarray]) -> infuse.Skeleton:
    """``sk`` with the named joints moved by world offsets (metres), the rest of each chain in place."""
    names, parents, rots, pos = parts(sk)
    pos = [p + moves.get(n, 0.0) for n, p in zip(names, pos)]
    return from_globals(names, parents, rots, pos)


def test_a_rig_built_otherwise_moves_from_its_own_rest():
    """A target whose clavicle joints zigzag (the acromioclavicular 4 cm down), whose lower spine
    bends back, whose ankles sit 3 cm higher up the shin and whose thumbs start 2 cm lower gets the
    source's motion on those joints exactly: where the source's clavicles, spine, feet and wrists
    hold their rest, the target's hold theirs."""
    sk = canonical_skeleton(extras=True)
    rest = sk.rest_global_positions
    down, back = np.array([0.0, -0.04, 0.0]), np.array([0.0, 0.0, -0.03])
    shin = {s: rest[sk.index[f"{s}_knee"]] - rest[sk.index[f"{s}_ankle"]] for s in "lr"}
    target = _rebuilt(sk, {"l_acromioclavicular": down, "r_acromioclavicular": down, "spine2": back,
                           "l_thumb1": 0.5 * down, "r_thumb1": 0.5 * down,
                           **{f"{s}_ankle": 0.03 * v / np.linalg.norm(v) for s, v in shin.items()}})
    clip = smooth_clip(sk, joints=("base", "spine3", "l_shoulder", "l_elbow", "r_shoulder", "r_hip", "r_knee"))
    out = retarget(clip, identity_map(sk), target, identity_map(target), ik="none")
    g, _ = motion_fk(out)
    ref = target.rest_global_rotations
    for name in ("l_sternoclavicular", "l_acromioclavicular", "r_acromioclavicular", "spine1", "spine2",
                 "l_ankle", "l_forefoot", "r_toe", "l_wrist", "r_wrist"):
        j = target.index[name]
        parent = target.parents[j]
        local = quat.multiply(quat.conjugate(g[:, parent]), g[:, j])
        rest = quat.multiply(quat.conjugate(ref[parent]), ref[j])
        assert np.degrees(quat.angle_between(local, rest)).max() < 1e-4, name
    # The limbs still follow the source's bone directions.
    _, ps = motion_fk(clip)
    _, po = motion_fk(out)
    for a, b in (("l_shoulder", "l_elbow"), ("r_hip", "r_knee")):
        u = ps[:, sk.index[b]] - ps[:, sk.index[a]]
        v = po[:, target.index[b]] - po[:, target.index[a]]
        cos = np.sum(u * v, axis=1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        assert np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).max() < 1e-4, (a, b)
