"""The postures pack (tools/motion_authoring/postures.py) and the posture controller, measured by FK: every
posture stands on the same footprints and loops; BML posture names map to the pack's postures (unknown ones
warn at scheduling); on Xbot, the Ready Player Me avatar, SmartBody's utah skeleton and Brad the feet stay planted
through postures, transitions and returns, the arms reach the authored places, breathing and gaze still add,
a walk ends a lasting posture, and the forearms and hands stay out of the torso's skin; seated postures sit on
a seat of knee height, sitting down and standing up keep the feet planted, and hands rest on the thighs, not
in them."""
from __future__ import annotations

import sys
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

import infuse
from infuse import Character, quaternions as quat
from infuse.bml import Scheduler
from infuse.kinematics import forward_kinematics
from infuse.mapping import map_skeleton
from infuse.mesh import skinning_matrices
from infuse.runtime import Runtime
from infuse.scene import Scene

from corpus_data import corpus_file
from infuse.packs import space_on
from infuse_postures.controller import Posture, PostureState
from runtime_characters import corpus_character

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tools.motion_authoring.body import Body  # noqa: E402
from tools.motion_authoring.postures import LEG_REACH, SPECS, footprints, posture_motion  # noqa: E402

FPS = 30.0
PACK = Path(__file__).resolve().parents[1] / "behaviour_libs" / "postures" / "infuse_pack_postures" / "pack"
BML = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="{id}" characterId="bob">{body}</bml>'
SHIFT = '<postureShift id="{id}" start="{start}"><stance type="STANDING"/><pose part="ARMS" lexeme="{lexeme}"/></postureShift>'


@pytest.fixture(scope="module")
def body():
    return Body.canonical()


@pytest.fixture(scope="module")
def pack_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("infusions")


# -- authoring ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("spec", SPECS, ids=lambda s: s.name)
def test_each_posture_stands_on_the_shared_footprints_and_loops(body, spec):
    motion = posture_motion(body, spec)
    g_rot, g_pos = forward_kinematics(body.skeleton, motion.local_rotations, motion.root_translations)
    for side, (ankle, yaw) in footprints(body).items():
        assert np.abs(g_pos[:, body.i(f"{side}_ankle")] - ankle).max() < 1e-4  # planted on its footprint, every frame
        forward = quat.rotate(g_rot[:, body.i(f"{side}_ankle")], np.array([0.0, 0.0, 1.0]))
        assert np.degrees(np.abs(np.arctan2(forward[:, 0], forward[:, 2]) - yaw)).max() < 0.01  # flat and toed out
        reach = np.linalg.norm(g_pos[:, body.i(f"{side}_ankle")] - g_pos[:, body.i(f"{side}_hip")], axis=-1)
        assert reach.max() <= LEG_REACH * body.leg + 1e-6  # the knee never locks
    assert np.abs(motion.local_rotations[0] - motion.local_rotations[-1]).max() < 1e-9  # a seamless loop
    assert np.abs(motion.root_translations[0] - motion.root_translations[-1]).max() < 1e-9
    # The idle shifts the weight, a little; seated, the pelvis stays on the seat and the chest sways.
    swaying = g_pos[:, body.i("spine3")] if spec.seated else motion.root_translations
    sway = np.ptp(swaying[:, [0, 2]], axis=0)
    assert 0.005 < sway.max() < 0.04


@pytest.mark.parametrize("spec", [s for s in SPECS if s.seated], ids=lambda s: s.name)
def test_seated_postures_sit_on_a_seat_of_knee_height_with_the_hands_on_the_thighs(body, spec):
    motion = posture_motion(body, spec)
    _, g_pos = forward_kinematics(body.skeleton, motion.local_rotations, motion.root_translations)
    for side in "lr":
        hip, knee, ankle = (g_pos[:, body.i(f"{side}_{j}")] for j in ("hip", "knee", "ankle"))
        assert np.abs(hip[:, 1] - knee[:, 1]).max() < 0.01  # the thigh level on the seat
        shin = knee - ankle
        assert np.degrees(np.arctan2(np.linalg.norm(shin[:, [0, 2]], axis=-1), shin[:, 1])).max() < 8.0  # upright
        # The wrist over the thigh (from the hip to a little past the knee), 9.5-15 cm above its bone: on it, not in it.
        along = knee - hip
        u = np.sum((g_pos[:, body.i(f"{side}_wrist")] - hip) * along, axis=-1) / np.sum(along * along, axis=-1)
        off = g_pos[:, body.i(f"{side}_wrist")] - (hip + u[:, None] * along)
        assert np.all((0.0 < u) & (u < 1.25)), (side, u.min(), u.max())
        assert np.all((0.095 < off[:, 1]) & (off[:, 1] < 0.15) & (np.linalg.norm(off[:, [0, 2]], axis=-1) < 0.06)), side


@pytest.mark.parametrize("spec", [s for s in SPECS if s.arms], ids=lambda s: s.name)
def test_placed_hands_are_where_the_posture_puts_them(body, spec):
    motion = posture_motion(body, spec)
    g_rot, g_pos = forward_kinematics(body.skeleton, motion.local_rotations, motion.root_translations)
    for side, place in spec.arms.items():
        wanted = np.asarray(place.wrist) * np.array([1.0 if side == "l" else -1.0, 1.0, 1.0])
        if place.frame == "thigh":  # +Z from the hip to the knee, +X across, +Y up off the thigh
            hip, knee = g_pos[:, body.i(f"{side}_hip")], g_pos[:, body.i(f"{side}_knee")]
            z = (knee - hip) / np.linalg.norm(knee - hip, axis=-1, keepdims=True)
            x = quat.rotate(g_rot[:, body.i("base")], np.array([1.0, 0.0, 0.0]))
            x = x - np.sum(x * z, axis=-1, keepdims=True) * z
            x /= np.linalg.norm(x, axis=-1, keepdims=True)
            d = g_pos[:, body.i(f"{side}_wrist")] - hip
            wrist = np.stack([np.sum(d * a, axis=-1) for a in (x, np.cross(z, x), z)], axis=-1)
        else:
            frame = body.i("spine3" if place.frame == "chest" else "base")
            wrist = quat.rotate(quat.conjugate(g_rot[:, frame]), g_pos[:, body.i(f"{side}_wrist")] - g_pos[:, frame])
        assert np.linalg.norm(wrist - wanted, axis=-1).max() < 0.002, side


def test_the_committed_clips_are_what_the_generator_makes(body):
    for spec in SPECS:
        committed = next(iter(infuse.load(PACK / "clips" / f"{spec.name}.bvh").motions.values()))
        made = posture_motion(body, spec)
        _, a = forward_kinematics(body.skeleton, made.local_rotations, made.root_translations)
        _, b = forward_kinematics(committed.skeleton, committed.local_rotations, committed.root_translations)
        assert np.abs(a - b[:, [committed.skeleton.index[n] for n in body.skeleton.names]]).max() < 1e-3, spec.name


# -- BML ----------------------------------------------------------------------------------------------------
def schedule(body: str):
    scheduler = Scheduler()
    warnings = []
    scheduler.feedback.subscribe(warnings.append, kinds=["warningFeedback"])
    (block,) = scheduler.submit(body if body.lstrip().startswith("<act") else BML.format(id="b1", body=body), at=0.0)
    return block.activations, warnings


@pytest.mark.parametrize("body,posture", [
    (SHIFT.format(id="p", start=0, lexeme="ARMS_CROSSED"), "arms_crossed"),
    (SHIFT.format(id="p", start=0, lexeme="HANDS_ON_HIP"), "hands_on_hips"),
    (SHIFT.format(id="p", start=0, lexeme="ARMS_AKIMBO"), "hands_on_hips"),
    (SHIFT.format(id="p", start=0, lexeme="HANDS_BEHIND_BACK"), "hands_behind_back"),
    (SHIFT.format(id="p", start=0, lexeme="HANDS_CLASPED"), "hands_clasped"),
    ('<posture id="p"><stance type="STANDING"/><pose part="WHOLEBODY" lexeme="LEANING_FORWARD"/></posture>', "leaning_forward"),
    ('<posture id="p"><pose part="WHOLEBODY" lexeme="LEANING_BACKWARD"/></posture>', "leaning_back"),
    ('<postureShift id="p"><stance type="STANDING"/><pose part="LEGS" lexeme="WEIGHT_ON_LEFT_LEG"/></postureShift>',
     "weight_left"),
    ('<postureShift id="p"><stance type="STANDING"/></postureShift>', "neutral"),
    ('<act><bml><body posture="ChrBrad@Idle01"/></bml></act>', "neutral"),
    ('<act><bml><body posture="ChrBrad@Idle01_ArmsCrossed01"/></bml></act>', "arms_crossed"),
    ('<torso id="t" lexeme="BodyRecline"/>', "leaning_back"),
    ('<gesture id="g" lexeme="ArmsCrossed" start="0" end="4"/>', "arms_crossed"),  # postures given as gestures
    ('<gesture id="g" lexeme="HandsTogether"/>', "hands_clasped"),
    ('<postureShift id="p"><stance type="SITTING"/></postureShift>', "sitting"),
    ('<posture id="p"><stance type="SITTING"/><pose part="ARMS" lexeme="HANDS_ON_LAP"/></posture>', "sitting_hands_on_lap"),
    ('<postureShift id="p"><stance type="SITTING"/><pose part="WHOLEBODY" lexeme="FOREARMS_ON_THIGHS"/></postureShift>',
     "sitting_leaning_forward"),
    ('<postureShift id="p"><stance type="SITTING"/><pose part="WHOLEBODY" lexeme="LEANING_FORWARD"/></postureShift>',
     "sitting_leaning_forward"),  # with a stance, only that stance's postures
    ('<gesture id="g" lexeme="rest=Lap" start="0" end="2"/>', "sitting_hands_on_lap"),  # Greta's rest positions
    ('<gesture id="g" lexeme="UnderTable"/>', "sitting_hands_on_lap"),
])
def test_bml_names_map_to_the_packs_postures(body, posture):
    (activation,), warnings = schedule(body)
    assert activation.controller == "posture" and activation.parameters["pack"] == "postures"
    assert activation.parameters["posture"] == posture
    assert not warnings


def test_unknown_names_and_other_stances_warn_at_scheduling_naming_the_postures():
    activations, warnings = schedule('<postureShift id="p1"><stance type="STANDING"/><pose part="ARMS" lexeme="JUGGLING"/>'
                                     '</postureShift><postureShift id="p2" start="2"><stance type="CROUCHING"/></postureShift>'
                                     '<torso id="t1" start="4" lexeme="Twisted_Sideways"/>'
                                     '<postureShift id="p3" start="6"><stance type="SITTING"/><pose part="ARMS" '
                                     'lexeme="ARMS_AKIMBO"/></postureShift><gesture id="g1" start="8" lexeme="allright_Pos_B"/>')
    by_id = {w.id: w.description for w in warnings}
    assert "JUGGLING" in by_id["b1:p1"] and "arms_crossed (ARMS_CROSSED" in by_id["b1:p1"]
    assert "CROUCHING" in by_id["b1:p2"] and "STANDING and SITTING" in by_id["b1:p2"]
    assert "Twisted_Sideways" in by_id["b1:t1"] and "hands_on_hips" in by_id["b1:t1"]
    # A standing pose with a sitting stance: the sitting postures are listed, and it sits upright.
    assert "no sitting posture" in by_id["b1:p3"] and "sitting_hands_on_lap (" in by_id["b1:p3"]
    assert "hands_on_hips" not in by_id["b1:p3"]
    # Greta's rest position whose name is no posture: the neutral rest, said so.
    assert "allright_Pos_B" in by_id["b1:g1"] and "neutral" in by_id["b1:g1"]
    postures = {a.behaviour: a.parameters.get("posture") for a in activations}
    # The pose unknown: the stance's plain posture.
    assert postures == {"p1": "neutral", "p2": None, "t1": None, "p3": "sitting", "g1": "neutral"}


# -- on characters ------------------------------------------------------------------------------------------
@lru_cache(maxsize=None)
def character(key: str) -> Character:
    """A corpus character of the runtime tests, or SmartBody's Brad with his mesh (``"brad"``)."""
    if key != "brad":
        return corpus_character(key)
    asset = infuse.load(corpus_file("smartbody/mesh/brad/Brad.dae"))
    return Character("brad", asset, mapping=map_skeleton(asset))


def play(key: str, body: str, cache, idle: bool = False, seconds: float | None = None, block_frames: int = 150):
    scene = Scene(fps=FPS, tts=None, quiet=True, idle=idle, pack_cache=cache, block_frames=block_frames)
    scene.add_character(character(key), "bob", packs=("locomotion-male",))
    scene.add_object("cup", (1.2, 1.6, 1.0))
    scene.bml("bob", BML.format(id="b1", body=body), at=0.0)
    scene.run(seconds if seconds is not None else scene.end_time + 1.0)
    return scene, scene.motion("bob")


def chest_frame(rig, motion, joint: str) -> np.ndarray:
    """(F, 3) ``joint`` in the frame of the joint the arms hang from (the chest)."""
    sk = motion.skeleton
    shoulder = rig.joint("l_acromioclavicular") or rig.joint("l_shoulder")
    chest = sk.parents[shoulder]
    g_rot, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    return quat.rotate(quat.conjugate(g_rot[:, chest]), g_pos[:, rig.joint(joint)] - g_pos[:, chest])


def feet_travel_m(rig, motion, frames) -> float:
    """The largest horizontal distance any ankle or ball of the foot moves from where it stands at the first of ``frames``."""
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    joints = [rig.joint(f"{s}_{j}") for s in "lr" for j in ("ankle", "forefoot") if rig.joint(f"{s}_{j}") is not None]
    p = g_pos[frames][:, joints][:, :, [0, 2]]
    return float(np.linalg.norm(p - p[0], axis=-1).max())


SEQUENCE = (SHIFT.format(id="p1", start=0.5, lexeme="ARMS_CROSSED")
            + '<posture id="p2" start="3" ready="4" relax="6" end="7"><stance type="STANDING"/>'
              '<pose part="ARMS" lexeme="HANDS_ON_HIP"/></posture>'
            + SHIFT.format(id="p3", start=8, lexeme="LEANING_FORWARD"))


@pytest.mark.parametrize("key", ["xbot", "rpm", "utah", "brad"])
def test_postures_follow_each_other_with_the_feet_planted(key, pack_cache):
    scene, motion = play(key, SEQUENCE, pack_cache, seconds=11.0)
    rig = scene.runtime.rig("bob")
    assert feet_travel_m(rig, motion, np.arange(motion.num_frames)) < 0.003  # through three transitions and a return
    space = space_on(rig, "postures")
    for side in "lr":
        wrist = chest_frame(rig, motion, f"{side}_wrist")
        for t, clip, start in ((2.5, "arms_crossed", 0.5), (5.0, "hands_on_hips", 3.0), (7.5, "arms_crossed", 0.5)):
            authored = chest_frame(rig, space.clips[clip].motion, f"{side}_wrist")
            loop = int(round((t - start) * FPS)) % (space.clips[clip].motion.num_frames - 1)
            assert np.linalg.norm(wrist[int(round(t * FPS))] - authored[loop]) < 0.002, (side, t, clip)
    # Leaning forward: the trunk pitches forward of where it stood (the chest ahead of the hips).
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    chest, hips = g_pos[:, rig.joint("spine3")], g_pos[:, rig.joint("base")]
    heading = quat.rotate(rig.rotation, np.array([0.0, 0.0, 1.0]))
    ahead = np.sum((chest - hips) * heading, axis=-1)
    assert ahead[int(10.5 * FPS)] - ahead[int(2.0 * FPS)] > 0.04


def test_the_frames_do_not_depend_on_the_block_size(pack_cache):
    body = SEQUENCE.split("<postureShift id=\"p3\"")[0] + '<locomotion id="w1" target="0 2" start="7.5"/>'
    scene, whole = play("xbot", body, pack_cache, seconds=10.0)
    assert scene.activities[("b1", "p1")].end_s < 10.0  # the walk ended the posture in the run
    _, blocks = play("xbot", body, pack_cache, seconds=10.0, block_frames=7)
    _, a = forward_kinematics(whole.skeleton, whole.local_rotations, whole.root_translations, whole.joint_translations)
    _, b = forward_kinematics(blocks.skeleton, blocks.local_rotations, blocks.root_translations, blocks.joint_translations)
    assert np.abs(a - b).max() < 1e-6


def test_a_posture_asked_for_during_a_walk_begins_once_the_character_stands(pack_cache):
    body = '<locomotion id="w1" target="0 2.5" start="0.5"/>' + SHIFT.format(id="p1", start="w1:end", lexeme="ARMS_CROSSED")
    scene, motion = play("xbot", body, pack_cache, seconds=8.0)
    posture = scene.activities[("b1", "p1")]
    assert posture.start_s >= posture.source.start - 1e-9 and posture.end_s is None  # it did not give way to the walk
    rig = scene.runtime.rig("bob")
    start = int(round(posture.start_s * FPS))
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations)
    hips = g_pos[:, rig.joint("base"), :][:, [0, 2]]
    assert np.linalg.norm(hips[start] - hips[0]) > 2.0  # it walked there
    assert feet_travel_m(rig, motion, np.arange(start, motion.num_frames)) < 0.003
    space = space_on(rig, "postures")
    authored = chest_frame(rig, space.clips["arms_crossed"].motion, "l_wrist")
    f = motion.num_frames - 1
    loop = (f - start) % (space.clips["arms_crossed"].motion.num_frames - 1)
    assert np.linalg.norm(chest_frame(rig, motion, "l_wrist")[f] - authored[loop]) < 0.002


def test_breathing_and_gaze_still_add_to_a_posture(pack_cache):
    body = SHIFT.format(id="p1", start=0.2, lexeme="ARMS_CROSSED") + '<gaze id="g1" target="cup" start="2" end="5"/>'
    plain, still = play("rpm", SHIFT.format(id="p1", start=0.2, lexeme="ARMS_CROSSED"), pack_cache, seconds=5.0)
    scene, lively = play("rpm", body, pack_cache, idle=True, seconds=5.0)
    rig = scene.runtime.rig("bob")
    frames = np.arange(still.num_frames)
    assert feet_travel_m(rig, lively, frames) < 0.003
    chest = rig.joint("spine3")
    breath = np.degrees(quat.angle_between(still.local_rotations[:, chest], lively.local_rotations[:, chest]))
    assert 0.1 < breath[15:60].max() < 5.0  # before the gaze, the breathing controller moves the chest over the posture
    g_rot, g_pos = forward_kinematics(lively.skeleton, lively.local_rotations, lively.root_translations)
    p_rot, p_pos = forward_kinematics(still.skeleton, still.local_rotations, still.root_translations)
    head, f = rig.joint("skullbase"), int(4.0 * FPS)
    cup = quat.rotate(quat.conjugate(rig.rotation), np.array([1.2, 1.6, 1.0]) - rig.position)  # in the character's frame
    # The head's forward axis in its own frame, from the posture without gaze (the face looks straight ahead).
    axis = quat.rotate(quat.conjugate(p_rot[f, head]), np.array([0.0, 0.0, 1.0]))

    def off_target_deg(rot, pos):
        forward, to = quat.rotate(rot[f, head], axis), cup - pos[f, head]
        return np.degrees(np.arccos(np.dot(forward, to) / np.linalg.norm(to)))

    assert off_target_deg(g_rot, g_pos) < off_target_deg(p_rot, p_pos) - 20.0  # the gaze turns the head to the cup


def test_a_walk_ends_a_lasting_posture(pack_cache):
    scene, motion = play("xbot", SHIFT.format(id="p1", start=0.2, lexeme="ARMS_CROSSED")
                         + '<locomotion id="w1" target="0 3" start="3"/>', pack_cache)
    posture = scene.activities[("b1", "p1")]
    assert posture.end_s is not None and 3.0 < posture.end_s < 3.0 + 2.0
    state = posture.state_of(PostureState)  # where it stood, and when the hips walked off from there
    assert state.footprints is not None and state.leave_s is not None
    assert 3.0 < state.leave_s and posture.end_s == state.leave_s + posture.blend_out_s
    rig = scene.runtime.rig("bob")
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    assert np.linalg.norm(g_pos[-1, rig.joint("base"), [0, 2]] - g_pos[0, rig.joint("base"), [0, 2]]) > 2.0
    assert feet_travel_m(rig, motion, np.arange(int(3.0 * FPS))) < 0.003
    # Walking, the arms swing again: the wrist leaves the crossed place.
    wrist = chest_frame(rig, motion, "l_wrist")
    assert np.linalg.norm(wrist[-1] - wrist[int(2.5 * FPS)]) > 0.15


# -- the arms and the body ----------------------------------------------------------------------------------
def _descendants(parents, roots) -> set[int]:
    out = set(roots)
    for j in range(len(parents)):
        p = j
        while p >= 0 and p not in out:
            p = parents[p]
        if p >= 0:
            out.add(j)
    return out


def _skinned(mesh, g_rot, g_pos) -> tuple[np.ndarray, np.ndarray]:
    """Vertex positions (V, 3) and unit normals (V, 3) of ``mesh`` posed by one frame's global joints."""
    m = skinning_matrices(mesh, g_rot, g_pos)[0].astype(np.float64)
    blended = np.einsum("vk,vkij->vij", mesh.weights.astype(np.float64), m[mesh.joints])
    v = np.einsum("vij,vj->vi", blended[:, :, :3], mesh.positions.astype(np.float64)) + blended[:, :, 3]
    n = np.einsum("vij,vj->vi", blended[:, :, :3], mesh.normals.astype(np.float64))
    return v, n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)


TORSO = ("base", "spine1", "spine2", "spine3", "spine4")
THIGHS = ("l_hip", "r_hip", "l_knee", "r_knee")


def penetration_m(character, motion, frame: int, body=TORSO) -> float:
    """How deep (metres) any forearm or hand vertex lies inside the skin of the ``body`` joints (the torso) at
    ``frame``: beneath the nearest such vertex (within 5 cm) along that vertex's normal."""
    sk = character.skeleton
    index = character.mapping.indices(sk)
    g_rot, g_pos = forward_kinematics(sk, motion.local_rotations[frame:frame + 1], motion.root_translations[frame:frame + 1])
    arms = _descendants(sk.parents, [index["l_elbow"], index["r_elbow"]])
    torso = [index[n] for n in body if n in index]
    torso_v, torso_n, arm_v = [], [], []
    for mesh in character.asset.meshes:
        owner = mesh.bind_joints[mesh.joints[np.arange(len(mesh.joints)), np.argmax(mesh.weights, axis=1)]]
        v, n = _skinned(mesh, g_rot, g_pos)
        torso_v.append(v[np.isin(owner, torso)])
        torso_n.append(n[np.isin(owner, torso)])
        arm_v.append(v[np.isin(owner, list(arms))])
    torso_v, torso_n, arm_v = (np.concatenate(a) for a in (torso_v, torso_n, arm_v))
    distance, nearest = cKDTree(torso_v).query(arm_v)
    depth = -np.einsum("ij,ij->i", arm_v - torso_v[nearest], torso_n[nearest])
    return float(np.max(depth[(depth > 0) & (distance < 0.05)], initial=0.0))


ROUND = "".join(SHIFT.format(id=f"p{k}", start=0.5 + 2.5 * k, lexeme=lexeme) for k, lexeme in enumerate(
    ("ARMS_CROSSED", "HANDS_ON_HIP", "HANDS_BEHIND_BACK", "HANDS_CLASPED", "ARMS_CROSSED", "NEUTRAL")))


@pytest.mark.parametrize("key", ["xbot", "rpm"])
def test_forearms_and_hands_stay_out_of_the_torso_through_transitions(key, pack_cache):
    # Crossed, on the hips, behind the back, clasped in front, crossed, neutral: the arms pass by the sides
    # and the hands come round the hips to and from the back.
    _, motion = play(key, ROUND, pack_cache, seconds=15.0)
    character = corpus_character(key)
    depths = [penetration_m(character, motion, f) for f in range(0, motion.num_frames, 3)]
    assert max(depths) < 0.025, (np.argmax(depths) * 3 / FPS, max(depths))


@pytest.mark.parametrize("key", ["xbot", "rpm"])
def test_forearms_and_hands_stay_out_of_the_torso(key):
    character = corpus_character(key)
    rt = Runtime(fps=FPS)
    rt.add_character(character, "bob")
    rig = rt.rig("bob")
    for name in space_on(rig, "postures").clips:
        motion = Posture(name).bind(rig, None).motion  # as it plays: a hand resting on a thigh put there
        deepest = max(penetration_m(character, motion, f) for f in range(0, motion.num_frames, 40))
        assert deepest < 0.025, (name, deepest)  # skin against skin at most: hands on the hips, clasped, crossed arms
        if name.startswith("sitting"):  # hands and forearms on the thighs, not through them
            deepest = max(penetration_m(character, motion, f, THIGHS) for f in range(0, motion.num_frames, 40))
            assert deepest < 0.025, (name, deepest)


SIT = ('<postureShift id="p1" start="0.5"><stance type="SITTING"/></postureShift>'
       '<postureShift id="p2" start="4"><stance type="SITTING"/><pose part="ARMS" lexeme="HANDS_ON_LAP"/></postureShift>'
       '<postureShift id="p3" start="6.5"><stance type="SITTING"/><pose part="ARMS" lexeme="FOREARMS_ON_THIGHS"/>'
       '</postureShift><postureShift id="p4" start="9.5"><stance type="STANDING"/></postureShift>')


@pytest.mark.parametrize("key", ["xbot", "rpm", "utah"])
def test_sitting_down_shifting_and_standing_up_with_the_feet_planted(key, pack_cache):
    scene, motion = play(key, SIT, pack_cache, seconds=12.0)
    rig = scene.runtime.rig("bob")
    assert feet_travel_m(rig, motion, np.arange(motion.num_frames)) < 0.003
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    hips, knees = g_pos[:, [rig.joint("l_hip"), rig.joint("r_hip")]], g_pos[:, [rig.joint("l_knee"), rig.joint("r_knee")]]
    ankles = g_pos[:, [rig.joint("l_ankle"), rig.joint("r_ankle")]]
    assert np.ptp(ankles[:, :, 1], axis=0).max() < 0.003  # the feet stay on the ground
    for t in (3.0, 5.5, 8.5):  # seated: the thighs level on a seat of knee height
        assert np.abs(hips[int(t * FPS), :, 1] - knees[int(t * FPS), :, 1]).max() < 0.02, t
    height = hips[:, :, 1].mean(axis=1)
    down, up = np.diff(height[int(0.5 * FPS):int(1.5 * FPS) + 1]), np.diff(height[int(9.5 * FPS):int(10.5 * FPS) + 1])
    assert height[0] - height[int(3 * FPS)] > 0.3 and abs(height[-1] - height[0]) < 0.01  # down a seat's depth, back up
    assert down.max() < 1e-3 and up.min() > -1e-3  # the hips go down, then up, without a jolt back
    assert np.abs(np.diff(height)).max() < 0.03 and np.abs(np.diff(height, 2)).max() < 0.005  # smoothly (m per frame)
