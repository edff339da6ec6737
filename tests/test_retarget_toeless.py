"""Retargeting onto feet without a ball joint: the foot's tip (the joint or end site below its ankle
farthest from it) stays on or above the level the foot is planted at, measured with forward
kinematics on the written clip against the source's own feet, on a corpus rig with its toe joints
removed and on a wild rig built without them; a foot with nothing below its ankle takes its heel and
tip from the mesh it carries, and both stay on or above that level."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import infuse
from infuse import metrics, quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.cli import main
from infuse.contacts import feet, joint_index, lowest_points
from infuse.errors import MissingFeatureError
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse_retarget import RetargetPlan, retarget_clip

import skeleton_variants
from corpus_data import corpus_file, labels, require_corpus

WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
XBOT = "runxaway-models/Xbot.glb"
MOCAPBANK = "20tab-bvh-python/tests/test_mocapbank.bvh"
WITCH = "trebeljahr-quaternius-showcase/public/glb/modular_women/Witch.glb"


def _label(rel: str) -> dict:
    for doc in labels():
        if doc["file"] == rel:
            return doc
    pytest.fail(f"no label for {rel}")


def deepest(motion: infuse.Motion, mapping, planted: np.ndarray) -> float:
    """cm: how far the lowest point of either foot (its joints and end sites) goes below the level it
    is planted at (its median over the frames ``planted`` (F, 2) marks for that foot)."""
    g, p = motion_fk(motion)
    low = lowest_points(motion.skeleton, feet(motion.skeleton, mapping), g, p)
    levels = np.array([np.median(low[planted[:, k], k]) for k in (0, 1)])
    return float(100.0 * max(0.0, -(low - levels).min()))


def walk() -> tuple[infuse.Motion, dict]:
    require_corpus()
    source = infuse.load(corpus_file(WALK))
    return next(iter(source.motions.values())), {k: v for k, v in _label(WALK)["mapping"].items() if v is not None}


def toeless_xbot() -> tuple[infuse.Skeleton, dict]:
    require_corpus()
    variant = skeleton_variants.toeless(infuse.load(corpus_file(XBOT)).skeleton, None, _label(XBOT))
    return variant.skeleton, {k: v for k, v in variant.mapping.items() if v is not None}


def check(target: infuse.Skeleton, mapping: dict) -> None:
    clip, s_map = walk()
    assert all(f.ball is None for f in feet(target, mapping)), "the target's feet should have no ball joint"
    plan = RetargetPlan(clip.skeleton, s_map, target, mapping, source_motion=clip)
    result = retarget_clip(plan, clip)
    planted = result.contacts.foot_flags()
    src, plain, out = (deepest(m, k, planted) for m, k in ((clip, s_map), (result.plain, mapping), (result.motion, mapping)))
    print(f"deepest foot below its planted level: source {src:.2f} cm, plain transfer {plain:.2f}, retargeted {out:.2f}")
    assert out <= src + 1.0, (src, plain, out)
    assert plain > out + 2.0, (src, plain, out)  # the rigid foot digs in without the pitch
    g_src, _ = motion_fk(clip)
    g_out, _ = motion_fk(result.motion)
    pop = metrics.popping(g_src, joint_index(clip.skeleton, s_map), g_out, joint_index(target, mapping))
    assert pop.ok, pop


def test_corpus_rig_without_toes():
    check(*toeless_xbot())


def test_end_site_on_the_ankle_is_no_tip():
    """A foot whose only end site sits on the ankle (OpenNI captures) has no tip to pitch: it is
    retargeted as a foot with nothing below the ankle."""
    clip, s_map = walk()
    target, mapping = toeless_xbot()
    ankles = [f.ankle for f in feet(target, mapping)]
    on_ankle = np.isin(target.end_site_parents, ankles)
    offsets = np.where(on_ankle[:, None], 0.0, target.end_site_offsets)
    bare = replace(target, end_site_parents=target.end_site_parents[~on_ankle],
                   end_site_offsets=target.end_site_offsets[~on_ankle])
    out = [retarget_clip(RetargetPlan(clip.skeleton, s_map, sk, mapping, source_motion=clip), clip).motion
           for sk in (replace(target, end_site_offsets=offsets), bare)]
    np.testing.assert_allclose(motion_fk(out[0])[0][:, ankles], motion_fk(out[1])[0][:, ankles], atol=1e-9)


def test_wild_rig_without_toes():
    from wild_data import wild_file

    asset = infuse.load(wild_file(MOCAPBANK))
    check(asset.skeleton, map_skeleton(asset))


def sole_depths(motion: infuse.Motion, plan: RetargetPlan, planted: np.ndarray) -> np.ndarray:
    """(2,) cm: how far the heel and the tip (the plan's mesh points, carried by the ankles) go below
    the level their foot is planted at (the median over the frames ``planted`` (F, 2) marks of the
    lowest of its ankle, heel and tip)."""
    g, p = motion_fk(motion)
    ankles = [f.ankle for f in plan.target.feet]
    points = np.stack(plan.sole_points)  # (2 feet, heel and tip, 3)
    sites = p[:, ankles, None] + quat.rotate(g[:, ankles, None], points[None])  # (F, 2, 2, 3)
    low = np.minimum(sites[..., 1].min(axis=2), p[:, ankles, 1])
    levels = np.array([np.median(low[planted[:, k], k]) for k in (0, 1)])
    return 100.0 * np.maximum(0.0, -(sites[..., 1] - levels[None, :, None]).min(axis=(0, 1)))


def test_mesh_gives_heel_and_tip(tmp_path):
    """The Witch's feet end at the ankle joint; her shoes give each foot a heel behind the ankle
    and a tip ahead of it. Retargeted by ``infuse retarget`` and read back, neither goes deeper
    below the planted level than the source's feet do; without the mesh the tip digs in."""
    from wild_data import wild_file

    clip, s_map = walk()
    path = wild_file(WITCH)
    asset = infuse.load(path)
    mapping = map_skeleton(asset)
    assert all(f.joints == (f.ankle,) and not len(f.end_sites) for f in feet(asset.skeleton, mapping))
    plans = [RetargetPlan(clip.skeleton, s_map, asset.skeleton, mapping, source_motion=clip, target_meshes=meshes)
             for meshes in ((), asset.meshes)]
    assert plans[0].sole_points == (None, None)
    heel, tip = plans[1].sole_points[0]
    assert np.linalg.norm(tip - heel) > 0.15, (heel, tip)  # a shoe's length, metres
    out = tmp_path / "witch.glb"
    assert main(["retarget", str(corpus_file(WALK)), "--to", str(path), "-o", str(out)]) == 0
    written = next(iter(infuse.load(out).motions.values()))
    plain = retarget_clip(plans[0], clip)
    planted = plain.contacts.foot_flags()
    src = deepest(clip, s_map, planted)
    before, after = (sole_depths(m, plans[1], planted) for m in (plain.motion, written))
    print(f"heel / tip below the planted level: source {src:.2f} cm, without the mesh {before}, with it {after}")
    assert after.max() <= src + 1.0, (src, before, after)
    assert before[1] > after[1] + 2.0, (before, after)
    g_src, _ = motion_fk(clip)
    g_out, _ = motion_fk(written)
    pop = metrics.popping(g_src, joint_index(clip.skeleton, s_map), g_out, joint_index(asset.skeleton, mapping))
    assert pop.ok, pop


def test_sole_points_of_a_shoe():
    """A box-shaped shoe on a turned ankle: the heel and tip are the box's back and front at its
    bottom, midway across, in the ankle's frame; a vertex the foot holds under half of is not the
    shoe's."""
    from infuse.mesh import SkinnedMesh, rigid_matrices, sole_points

    corners = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (0.0, 0.1) for z in (-0.05, 0.2)])
    stray = np.array([[0.0, -0.3, 0.5]])  # held 0.4 by the foot, 0.6 by the shin
    positions = np.concatenate([corners, stray]).astype(np.float32)
    rotations = np.array([[0.0, 0.0, 0.0, 1.0], quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2)])
    joint_positions = np.array([[0.0, 0.5, 0.0], [0.01, 0.08, 0.0]])  # shin, ankle; the mesh bound as posed
    binds = np.stack([np.linalg.inv(m) for m in rigid_matrices(rotations, joint_positions)])
    mesh = SkinnedMesh("shoe", positions, np.tile([0.0, 1.0, 0.0], (9, 1)).astype(np.float32),
                       np.array([[0, 1, 2]], dtype=np.int32), np.tile([1, 0], (9, 1)).astype(np.int32),
                       np.array([[1.0, 0.0]] * 8 + [[0.4, 0.6]], dtype=np.float32), np.array([0, 1]), binds)
    points = sole_points([mesh], rotations, joint_positions, [1], 1, np.array([0.0, 0.3, 2.0]))
    expected = quat.rotate(quat.conjugate(rotations[1]), np.array([[0.0, 0.0, -0.05], [0.0, 0.0, 0.2]]) - joint_positions[1])
    np.testing.assert_allclose(points, expected, atol=1e-6)
    assert sole_points([mesh], rotations, joint_positions, [0], 1, np.array([0.0, 0.0, 1.0])) is not None  # the stray
    assert sole_points([], rotations, joint_positions, [1], 1, np.array([0.0, 0.0, 1.0])) is None


@pytest.mark.parametrize("failure", [ValueError("bad accessor"), MissingFeatureError("x.glb", "Draco-compressed")])
def test_a_character_whose_meshes_cannot_be_decoded_still_retargets_without_soles(failure):
    from infuse_retarget.command import _meshes_if_readable

    def broken():
        raise failure

    asset = infuse.Asset(None, "synthetic", canonical_skeleton(), mesh_loader=broken)
    assert _meshes_if_readable(asset) == ()
