"""Limbs whose end hangs outside them: a foot hanging from the root (rigs built for IK) is carried by
the end of its shin. The limb IK solves such a leg as it solves one whose foot hangs from the shin,
the runtime keeps the foot on the shin's end, and the packs that pose legs walk and pose such rigs."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.errors import MissingJointsError
from infuse.kinematics import forward_kinematics
from infuse.mapping import map_skeleton
from infuse.packs import infuse_character
from infuse.runtime.limb_ik import carried_offset, carry_ends, solve_limb
from infuse.skeleton import Skeleton

from corpus_data import corpus_file

rng = np.random.default_rng(16)
LEG_JOINTS = ("hip", "knee", "ankle")


def legs_of(names) -> list[tuple[int, int, int]]:
    index = {n: i for i, n in enumerate(names)}
    return [tuple(index[f"{s}_{j}"] for j in LEG_JOINTS) for s in "lr"]


def two_legs() -> tuple[Skeleton, Skeleton]:
    """A pelvis with two legs (hip, knee, ankle, toe) at turned rest rotations: the ankles hanging from
    the knees, and the same body with each ankle (its toe below it) hanging from the pelvis, where the
    first has it at rest."""
    names = ["pelvis", "l_hip", "l_knee", "l_ankle", "l_toe", "r_hip", "r_knee", "r_ankle", "r_toe"]
    parents = np.array([-1, 0, 1, 2, 3, 0, 5, 6, 7])
    offsets = np.array([[0, 1.0, 0], [0.1, 0, 0], [0, -0.45, 0.02], [0, -0.42, -0.01], [0, -0.05, 0.15],
                        [-0.1, 0, 0], [0, -0.45, 0.02], [0, -0.40, -0.01], [0, -0.05, 0.14]])
    rest = quat.normalize(np.array([0, 0, 0, 1.0]) + 0.3 * rng.normal(size=(len(names), 4)))
    attached = Skeleton(names, parents, offsets, rest)
    g_rot, g_pos = attached.rest_global_rotations, attached.rest_global_positions
    carried_parents, carried_offsets, carried_rest = parents.copy(), offsets.copy(), rest.copy()
    for ankle in (3, 7):
        carried_parents[ankle] = 0
        carried_offsets[ankle] = quat.rotate(quat.conjugate(g_rot[0]), g_pos[ankle] - g_pos[0])
        carried_rest[ankle] = quat.multiply(quat.conjugate(g_rot[0]), g_rot[ankle])
    return attached, Skeleton(names, carried_parents, carried_offsets, carried_rest)


def carried_pose(attached: Skeleton, carried: Skeleton, local: np.ndarray, root: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The local rotations (F, J, 4) and translations (F, J, 3) that put ``carried`` in the pose
    ``local``, ``root`` gives ``attached`` (each ankle's global rotation and position kept)."""
    g_rot, g_pos = forward_kinematics(attached, local, root)
    rotations = local.copy()
    translations = np.repeat(carried.rest_translations[None], len(local), axis=0)
    for ankle in (3, 7):
        rotations[:, ankle] = quat.multiply(quat.conjugate(g_rot[:, 0]), g_rot[:, ankle])
        translations[:, ankle] = quat.rotate(quat.conjugate(g_rot[:, 0]), g_pos[:, ankle] - g_pos[:, 0])
    return rotations, translations


def test_the_carried_point_is_where_the_foot_sits_at_rest():
    attached, carried = two_legs()
    for leg in legs_of(carried.names):
        assert carried_offset(attached, leg) is None
        hip, knee, ankle = leg
        g_rot, g_pos = carried.rest_global_rotations, carried.rest_global_positions
        assert np.allclose(g_pos[knee] + quat.rotate(g_rot[knee], carried_offset(carried, leg)), g_pos[ankle], atol=1e-12)


@pytest.mark.parametrize("frames", [1, 40, 700])
@pytest.mark.parametrize("several", [False, True])
@pytest.mark.parametrize("ending", ["keep", "turn", "set"])
def test_a_carried_foot_is_solved_as_a_foot_hanging_from_its_shin(frames, several, ending):
    """Whatever the goals (some out of reach), weights, poles and end rotation, a leg whose foot hangs
    from the pelvis ends in the pose the same leg with its foot on the shin does: every joint's global
    rotation and position alike, and the same distances left to the goals."""
    attached, carried = two_legs()
    legs = legs_of(attached.names)
    local = quat.normalize(rng.normal(size=(frames, attached.num_joints, 4)))
    root = rng.normal(size=(frames, 3))
    _, pos = forward_kinematics(attached, local, root)
    goals = pos[:, [3, 7]] + 0.3 * rng.normal(size=(frames, 2, 3))
    weight = rng.uniform(size=(frames, 2))
    weight[: frames // 3] = 1.0
    pole = rng.normal(size=(frames, 2, 3))
    wanted = quat.normalize(rng.normal(size=(frames, 2, 4))) if ending == "set" else None
    rotations, translations = carried_pose(attached, carried, local, root)
    solved = local.copy()
    limbs = [legs] if several else [[leg] for leg in legs]
    for k, limb in enumerate(limbs):
        part = slice(None) if several else k
        arguments = dict(weight=weight[:, part], pole=pole[:, part], keep_end=ending == "keep",
                         end_rotation=None if wanted is None else wanted[:, part])
        one = limb if several else limb[0]
        left = solve_limb(attached, solved, root, None, one, goals[:, part], **arguments)
        right = solve_limb(carried, rotations, root, translations, one, goals[:, part], **arguments)
        assert np.allclose(right, left, rtol=0.0, atol=1e-9)
    expected = forward_kinematics(attached, solved, root)
    found = forward_kinematics(carried, rotations, root, translations)
    assert np.allclose(quat.canonical_sign(found[0]), quat.canonical_sign(expected[0]), atol=1e-9)
    assert np.allclose(found[1], expected[1], atol=1e-9)
    assert not np.allclose(solved, local)  # the legs did move


def test_a_carried_foot_is_put_back_on_its_shin_keeping_its_turn():
    """:func:`carry_ends` moves a foot left anywhere (a blend of translations, a clip that has none) onto
    its shin's end, its global rotation as it was, and leaves the rest of the pose."""
    attached, carried = two_legs()
    frames = 60
    local = quat.normalize(rng.normal(size=(frames, carried.num_joints, 4)))
    root = rng.normal(size=(frames, 3))
    translations = np.repeat(carried.rest_translations[None], frames, axis=0)
    translations[:, [3, 7]] += 0.2 * rng.normal(size=(frames, 2, 3))
    before = forward_kinematics(carried, local, root, translations)
    rotations = local.copy()
    carry_ends(carried, rotations, root, translations, legs_of(carried.names))
    g_rot, g_pos = forward_kinematics(carried, rotations, root, translations)
    assert np.array_equal(rotations, local)
    assert np.allclose(quat.canonical_sign(g_rot), quat.canonical_sign(before[0]), atol=1e-12)
    for hip, knee, ankle in legs_of(carried.names):
        shin_end = g_pos[:, knee] + quat.rotate(g_rot[:, knee], carried_offset(carried, (hip, knee, ankle)))
        assert np.abs(g_pos[:, ankle] - shin_end).max() < 1e-12
    kept = [j for j in range(carried.num_joints) if j not in (3, 4, 7, 8)]
    assert np.allclose(g_pos[:, kept], before[1][:, kept], atol=1e-12)


def test_a_carried_foot_needs_joint_translations_and_a_foot_hung_inside_its_leg_is_refused():
    attached, carried = two_legs()
    local = quat.identity((3, carried.num_joints))
    leg = legs_of(carried.names)[0]
    with pytest.raises(ValueError, match="'l_ankle' hangs outside its limb"):
        solve_limb(carried, local, np.zeros((3, 3)), None, leg, np.zeros((3, 3)))
    frozen = np.repeat(carried.rest_translations[None], 3, axis=0)
    frozen.flags.writeable = False  # a Motion's arrays: the foot's place would be lost
    with pytest.raises(ValueError, match="writable joint translations"):
        carry_ends(carried, local, np.zeros((3, 3)), frozen, [leg])
    carry_ends(attached, local, np.zeros((3, 3)), None, [leg])  # nothing to carry: no translations needed
    thigh_foot = Skeleton(carried.names, np.where(np.arange(carried.num_joints) == 3, 1, carried.parents),
                          carried.rest_translations, carried.rest_rotations)
    with pytest.raises(ValueError, match="'l_ankle' hangs neither below 'l_knee'"):
        carried_offset(thigh_foot, leg)


def rehung(asset: infuse.Asset, moves) -> infuse.Asset:
    """``asset`` with each joint of ``moves`` ((joint, new parent) index pairs) hanging from its new
    parent where it sits at rest (the joints below it following). No motions."""
    sk = asset.skeleton
    parents, translations, rotations = sk.parents.copy(), sk.rest_translations.copy(), sk.rest_rotations.copy()
    g_rot, g_pos = sk.rest_global_rotations, sk.rest_global_positions
    for joint, parent in moves:
        parents[joint] = parent
        translations[joint] = quat.rotate(quat.conjugate(g_rot[parent]), g_pos[joint] - g_pos[parent])
        rotations[joint] = quat.multiply(quat.conjugate(g_rot[parent]), g_rot[joint])
    skeleton = Skeleton(sk.names, parents, translations, rotations, sk.end_site_parents, sk.end_site_offsets)
    return dataclasses.replace(asset, skeleton=skeleton, motions={}, path=None)


def test_feet_hung_inside_their_legs_are_refused_naming_them_and_feet_outside_them_walk():
    """RobotExpressive's feet hang from its ground bone: locomotion is infused (it was refused); X Bot with
    its ankles hung from its thighs (a foot the leg's turns would carry, but not as the leg) is refused,
    naming them."""
    robot = infuse_character(corpus_file("adibkn1-robot/RobotExpressive.glb"), ["locomotion-female"])
    assert set(robot.spaces) == {"locomotion-female"}
    original = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    mapping = map_skeleton(original)  # the joints as mapped on X Bot (a mapper may not find such feet)
    index = mapping.indices(original.skeleton)
    variant = rehung(original, [(index[f"{s}_ankle"], index[f"{s}_hip"]) for s in "lr"])
    with pytest.raises(MissingJointsError) as err:
        infuse_character(infuse.Character("x", variant, mapping), ["locomotion-female"], mapping=mapping)
    assert "l_ankle, r_ankle do not hang below the joint before it" in str(err.value)


#: The wild rigs whose feet hang from the root, and whether they have hands (postures drive the wrists too).
BUILT_FOR_IK = {"single_knight_pack/KnightCharacter.glb": True, "cyberpunk_pack/Character.glb": True,
                "platformer_game_pack/Character.glb": True, "Astronaut_FinnTheFrog": False}


@pytest.mark.parametrize("key", BUILT_FOR_IK)
def test_rigs_built_for_ik_walk_to_a_target_with_their_feet_on_their_shins(key, tmp_path):
    """The four Quaternius rigs whose feet hang from the root (refused before) infuse the built-in
    locomotion and postures (the frog, without hands, only locomotion) and walk to a point 4 m away at
    90 degrees to the left: the pelvis ends within 6 cm of it, each foot joint stays within 1 mm of its
    shin's end on every frame of the scene (walk, beat, posture), and no leg joint turns in one frame
    more than 1.5 times the pack cycles the walk blends turn theirs, plus 10 degrees (the wild table's
    bound on popping)."""
    import sys
    from pathlib import Path

    from wild_data import require_wild, wild_file

    from infuse import metrics

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.wild_pipeline import humanoid_rigs, pack_row
    from test_locomotion_feet import LEGS, played_source_turns

    require_wild()
    (rel,) = humanoid_rigs(key)
    row = pack_row(str(wild_file(rel)), tmp_path / "infusions")
    assert "locomotion-male" in row.packs and row.finite, row.refused
    if BUILT_FOR_IK[key]:
        assert "postures" in row.packs, row.refused
        assert row.posture_arm > 30.0, row.posture_arm
    else:
        assert "l_wrist, r_wrist" in row.refused["postures"]
    assert row.miss_m < 0.06, row.miss_m
    sk = row.motion.skeleton
    index = row.mapping.indices(sk)
    g_rot, g_pos = forward_kinematics(sk, row.motion.local_rotations, row.motion.root_translations,
                                      row.motion.joint_translations)
    for s in "lr":
        leg = tuple(index[f"{s}_{j}"] for j in LEG_JOINTS)
        offset = carried_offset(sk, leg)
        assert offset is not None  # the foot hangs outside its leg
        shin_end = g_pos[:, leg[1]] + quat.rotate(g_rot[:, leg[1]], offset)
        assert np.linalg.norm(g_pos[:, leg[2]] - shin_end, axis=-1).max() < 1e-3
    joints = [index[n] for n in LEGS if n in index]
    turns = metrics.largest_turns(g_rot[:, joints])
    source = played_source_turns(row, infuse.load(wild_file(rel)), tmp_path / "infusions")
    assert (turns <= 1.5 * source + metrics.POP_MARGIN_DEG).all(), (turns, source)


def test_hands_hanging_outside_their_arms_gesture_and_pose(tmp_path):
    """X Bot with each wrist (its fingers below it) hanging from the joint its shoulder hangs from walks to
    a point 2 m to its left (within 6 cm), beats (the right wrist moves 10 cm or more) and crosses
    its arms (both 15 cm or more), its wrists on its forearms' ends (within 1 mm) throughout."""
    import sys
    from pathlib import Path

    from infuse.scene import Scene

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.wild_pipeline import BEAT, BML, POSTURE

    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    mapping = map_skeleton(xbot)  # as mapped on X Bot (a mapper may not find such hands)
    index = mapping.indices(xbot.skeleton)
    parents = xbot.skeleton.parents
    variant = rehung(xbot, [(index[f"{s}_wrist"], int(parents[index[f"{s}_shoulder"]])) for s in "lr"])
    scene = Scene(fps=30.0, tts=None, quiet=True, idle=False, pack_cache=tmp_path / "infusions")
    scene.add_character(infuse.Character("bob", variant, mapping), "bob", facing=0.0,
                        packs=("locomotion-male", "gestures", "postures"))
    scene.walk_to("bob", (2.0, 0.0), at=0.2)
    scene.run(5.0)
    scene.bml("bob", BML.format(id="beat", body=BEAT), at=5.2)
    scene.bml("bob", BML.format(id="pose", body=POSTURE), at=7.0)
    scene.run(scene.end_time + 0.5)
    motion = scene.motion("bob")
    assert len(scene.runtime.rig("bob").carried_limbs) == 2  # the arms
    sk = variant.skeleton
    g_rot, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    assert np.isfinite(g_pos).all()
    assert np.linalg.norm(g_pos[135:150, index["base"]][:, [0, 2]].mean(axis=0) - (2.0, 0.0)) < 0.06
    for s in "lr":
        arm = tuple(index[f"{s}_{j}"] for j in ("shoulder", "elbow", "wrist"))
        forearm_end = g_pos[:, arm[1]] + quat.rotate(g_rot[:, arm[1]], carried_offset(sk, arm))
        assert np.linalg.norm(g_pos[:, arm[2]] - forearm_end, axis=-1).max() < 1e-3
        chest = int(parents[index[f"{s}_shoulder"]])
        wrist = quat.rotate(quat.conjugate(g_rot[:, chest]), g_pos[:, arm[2]] - g_pos[:, chest])  # in the chest's frame
        crossed = np.linalg.norm(wrist[210:] - wrist[205], axis=-1).max()
        assert crossed > 0.15, crossed  # the posture moves both wrists (metres, an arm of about 0.5 m)
        if s == "r":
            beat = np.linalg.norm(wrist[156:200] - wrist[156], axis=-1).max()
            assert beat > 0.1, beat
