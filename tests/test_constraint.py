"""``sbm:constraint`` (the ``ik_constraint`` controller) in a scene, measured by forward kinematics on the
written motion: a wrist, an ankle and the head held on objects, moving targets and points (with an
offset) while the constraint is fully in, untouched outside its span, approaching over the fade-in; held
while a gaze turns the body; and two-joint limb IK exact in one step on an arm bent out of its goal's
plane (the Ready Player Me avatar's rest)."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk
from infuse.scene import Scene

from corpus_data import require_corpus
from runtime_characters import corpus_character

pytest.importorskip("infuse_manipulation")

FPS = 30.0
CUP = (-0.25, 1.2, 0.35)


def _fly(times):
    """A point circling in front of the character's right shoulder, metres."""
    t = np.asarray(times, dtype=np.float64)
    return np.stack((-0.3 + 0.1 * np.cos(2.0 * t), 1.3 + 0.1 * np.sin(2.0 * t), 0.2 + 0.0 * t), axis=-1)


def _scene(key: str, bml: str, seconds: float):
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character(key), name="bob")
    scene.add_object("cup", CUP)
    scene.add_object("lamp", (-2.0, 1.6, -1.0))
    scene.add_target("fly", _fly)
    scene.bml("bob", '<act><bml id="b1">' + bml + "</bml></act>", at=0.0)
    scene.run(seconds)
    motion = scene.motion("bob")
    return scene, warnings, infuse.motion_fk(motion)[1], scene.runtime.rig("bob").mapping.indices(motion.skeleton)


@pytest.mark.parametrize("key", ["xbot", "utah"])
def test_wrist_held_on_an_object_with_offset_and_faded(key):
    scene, warnings, g, ix = _scene(key, '<sbm:constraint id="c" effector="r_wrist" target="cup" sbm:offset="0 0.05 0" '
                                         'sbm:fade-in="0.4" sbm:fade-out="0.4" start="1" end="3"/>', 4.0)
    assert not warnings, [w.description for w in warnings]
    goal = np.array(CUP) + (0.0, 0.05, 0.0)
    wrist = g[:, ix["r_wrist"]]
    held = np.linalg.norm(wrist[int(1.4 * FPS):int(2.6 * FPS) + 1] - goal, axis=1)
    print(key, f"wrist off its goal while held: at most {held.max() * 1000:.3f} mm")
    assert held.max() < 1e-3
    rest = wrist[0]
    assert np.allclose(wrist[:int(1.0 * FPS) + 1], rest, atol=1e-9)
    assert np.allclose(wrist[int(3.0 * FPS):], rest, atol=1e-9)
    approach = np.linalg.norm(wrist[int(1.0 * FPS):int(1.4 * FPS) + 1] - goal, axis=1)
    assert np.all(np.diff(approach) < 0)


def test_wrist_follows_a_moving_target_while_a_gaze_turns_the_body():
    scene, warnings, g, ix = _scene("xbot", '<gaze id="look" target="lamp" sbm:joint-range="EYES NECK CHEST BACK" start="0" end="3"/>'
                                            '<sbm:constraint id="c" effector="r_wrist" target="fly" start="0.5" end="3"/>', 3.0)
    assert not [w for w in warnings if "constraint" in w.description]
    frames = np.arange(int(0.8 * FPS), int(2.6 * FPS))
    miss = np.linalg.norm(g[frames, ix["r_wrist"]] - _fly(frames / FPS), axis=1)
    chest = g[frames, ix["spine3"]] - g[0, ix["spine3"]]
    assert np.abs(chest).max() > 0.005  # the gaze moved the chest meanwhile
    print(f"wrist off the moving target: at most {miss.max() * 1000:.3f} mm")
    assert miss.max() < 1e-3


@pytest.mark.parametrize("key", ["xbot", "utah"])
def test_ankle_and_head_held_on_points(key):
    _, _, g0, ix = _scene(key, "", 0.1)
    ankle = g0[0, ix["l_ankle"]] + (0.0, 0.12, 0.2)
    head = g0[0, ix["skullbase"]] + (0.0, -0.05, 0.08)
    bml = (f'<sbm:constraint id="a" effector="l_ankle" sbm:target-pos="{ankle[0]} {ankle[1]} {ankle[2]}" start="0.2" end="2"/>'
           f'<sbm:constraint id="h" effector="skullbase" sbm:target-pos="{head[0]} {head[1]} {head[2]}" start="0.2" end="2"/>')
    scene, warnings, g, ix = _scene(key, bml, 2.0)
    assert not warnings, [w.description for w in warnings]
    frames = slice(int(0.6 * FPS), int(1.6 * FPS))
    ankle_miss = np.linalg.norm(g[frames, ix["l_ankle"]] - ankle, axis=1).max()
    head_miss = np.linalg.norm(g[frames, ix["skullbase"]] - head, axis=1).max()
    print(key, f"ankle {ankle_miss * 1000:.3f} mm, head {head_miss * 1000:.3f} mm off their points")
    assert ankle_miss < 1e-3 and head_miss < 0.01


def test_constraint_warnings_name_the_reason():
    scene, warnings, _, _ = _scene("xbot", '<sbm:constraint id="a" effector="tail" target="cup"/>'
                                           '<sbm:constraint id="b" effector="r_wrist" target="nothing"/>'
                                           '<sbm:constraint id="c" effector="l_wrist" sbm:target-pos="0 1 3"/>', 1.0)
    messages = {w.id: w.description for w in warnings}
    assert "no joint 'tail'" in messages["b1:a"]
    assert "'nothing'" in messages["b1:b"]
    assert any("the constraint on 'l_wrist': the target is out of reach by up to" in m for m in messages.values())
    assert not any("reaching pack" in m for m in messages.values())


def test_limb_ik_is_exact_in_one_step_on_an_arm_bent_out_of_the_goal_plane():
    require_corpus()
    character = corpus_character("rpm")
    sk = character.skeleton
    ix = character.mapping.indices(sk)
    arm = (ix["r_shoulder"], ix["r_elbow"], ix["r_wrist"])
    rot = sk.rest_rotations[None].copy()
    root = sk.rest_translations[None, 0]
    shoulder = chain_fk(sk, rot, root, None, [arm[0]])[1][0, 0]
    goals = shoulder + np.array([[-0.2, -0.1, 0.35], [0.1, -0.3, 0.2], [-0.3, 0.2, 0.1]])
    rots = np.repeat(rot, len(goals), axis=0)
    left = solve_limb(sk, rots, np.repeat(root, len(goals), axis=0), None, arm, goals)
    reached = chain_fk(sk, rots, np.repeat(root, len(goals), axis=0), None, [arm[2]])[1][:, 0]
    assert np.abs(left).max() < 1e-9 and np.linalg.norm(reached - goals, axis=1).max() < 1e-9


def test_smartbody_constraint_document_with_a_clavicle_root():
    """SmartBody's ConstraintDemo (``effector-root="l_sternoclavicular"``, a joint the RPM avatar lacks): the
    wrist held on the pawn by limb IK."""
    from corpus_data import corpus_file

    require_corpus()
    pawn = np.array([0.25, 1.15, 0.3])
    for key in ("rpm", "utah"):
        scene = Scene(fps=FPS, idle=False, quiet=True)
        warnings = []
        scene.on("warningFeedback", warnings.append)
        scene.add_character(corpus_character(key), name="ChrBrad0")
        scene.add_object("pawn3", pawn)
        scene.bml("ChrBrad0", corpus_file("bml/smartbody/sb09_constraint_lwrist.xml"), at=0.0)
        scene.run(2.0)
        assert not warnings, [w.description for w in warnings]
        g = infuse.motion_fk(scene.motion("ChrBrad0"))[1]
        ix = scene.runtime.rig("ChrBrad0").mapping.indices(scene.runtime.rig("ChrBrad0").skeleton)
        assert np.linalg.norm(g[int(1.0 * FPS):, ix["l_wrist"]] - pawn, axis=1).max() < 1e-3, key


def test_a_constraint_of_the_same_handle_replaces_the_last():
    """SmartBody's ``sbm:handle``: the second constraint named ``h`` takes the wrist elsewhere, the first fades out."""
    scene, warnings, g, ix = _scene("xbot", '<sbm:constraint id="a" effector="r_wrist" target="cup" sbm:handle="h"/>'
                                            '<sbm:constraint id="b" effector="r_wrist" target="fly" sbm:handle="h" start="1.5"/>'
                                            '<sbm:constraint id="c" effector="l_wrist" target="cup" sbm:offset="0.4 0 0" '
                                            'sbm:handle="other" start="1.5"/>', 3.0)
    assert not warnings, [w.description for w in warnings]
    first = scene.activities[("b1", "a")]
    assert first.end_s == pytest.approx(1.5 + first.blend_out_s)
    assert scene.activities[("b1", "c")].end_s is None
    frames = np.arange(int(2.0 * FPS), int(3.0 * FPS))
    assert np.linalg.norm(g[frames, ix["r_wrist"]] - _fly(frames / FPS), axis=1).max() < 1e-3
