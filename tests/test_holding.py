"""What each hand holds is the stage's: an object one plugin's hand took another's lets go. Measured by
forward kinematics on the written motion and the recorded object track: ``sbm:grab`` then ``sbm:reach
action="put-down"`` on a shelf (the holding hand brings the object, where it holds it, to the put-down
target, lets go there and opens), and ``sbm:reach action="pick-up"`` then an ``sbm:grab`` release (the object stays where the hand
let it go)."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.scene import Scene
from infuse.stage import Held

from corpus_data import require_corpus
from runtime_characters import corpus_character

pytest.importorskip("infuse_manipulation")
pytest.importorskip("infuse_reach")

FPS = 30.0
CUP = (-0.2, 1.3, 0.3)  # in front of X Bot, to his right: inside the reaching pack's right-hand examples
SHELF = (-0.35, 1.3, 0.25)  # where the cup is put down, also inside them
SBM = '<act><bml id="{id}">{body}</bml></act>'


def _scene():
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob", packs=("locomotion-male", "reaching"))
    scene.add_object("cup", CUP, size=0.08)
    scene.add_object("shelf", SHELF, size=0.5)
    return scene, warnings


def _span(g_pos, ix, side: str) -> np.ndarray:
    """(F,) middle finger's base-to-tip distance, metres: smaller when the hand is closed."""
    return np.linalg.norm(g_pos[:, ix[f"{side}_middle4"]] - g_pos[:, ix[f"{side}_middle1"]], axis=1)


def test_a_grabbed_object_is_put_down_by_a_reach():
    scene, warnings = _scene()
    scene.bml("bob", SBM.format(id="take", body='<sbm:grab id="g" target="cup"/>'), at=0.3)
    assert [(h.hand, h.obj) for h in scene.stage.held("bob")] == [("right", "cup")]
    scene.bml("bob", SBM.format(id="put", body='<sbm:reach id="r" target="shelf" sbm:action="put-down"/>'), at=2.5)
    assert scene.stage.held("bob") == ()
    scene.bml("bob", SBM.format(id="again", body='<sbm:grab id="g" target="cup" sbm:grab-state="release"/>'), at=5.0)
    scene.run(6.0)
    got = {w.id: w.description for w in warnings}
    assert "put:r" not in got, got  # it holds the cup: nothing to say
    assert "holds no 'cup'" in got["again:g"]  # put down already
    put = scene.activities[("put", "r")]
    stroke = int(round((put.start_s + put.controller.stroke_s) * FPS))
    motion = scene.motion("bob")
    g_rot, g_pos = infuse.motion_fk(motion)
    ix = scene.runtime.rig("bob").mapping.indices(motion.skeleton)
    wrist = ix["r_wrist"]
    cup = scene.object_track("cup")
    # carried in the right hand up to the put-down's stroke...
    grab = scene.activities[("take", "g")].source
    taken = int(round(grab.time("stroke") * FPS))
    in_hand = quat.rotate(quat.conjugate(g_rot[taken:stroke, wrist]), cup[taken:stroke] - g_pos[taken:stroke, wrist])
    assert np.abs(in_hand - in_hand[0]).max() < 1e-6
    # ...which brings it, where it holds it, onto the shelf: no jump when it lets go, and there it stays
    steps = np.linalg.norm(np.diff(cup[stroke - 5:stroke + 5], axis=0), axis=1)
    print(f"cup {np.linalg.norm(cup[stroke - 1] - SHELF) * 100:.3f} cm from the shelf a frame before the stroke, "
          f"{steps.max() * 100:.3f} cm at most a frame around it; the wrist "
          f"{np.linalg.norm(g_pos[stroke, wrist] - SHELF) * 100:.1f} cm from the shelf (the cup is in the palm)")
    assert np.linalg.norm(cup[stroke - 1] - SHELF) < 0.002 and steps.max() < 0.005
    assert np.allclose(cup[stroke:], SHELF, atol=1e-6)
    # the fingers closed on the cup, and open again once it is put down
    span = _span(g_pos, ix, "r")
    assert span[stroke - 1] < 0.85 * span[0] and span[-1] == pytest.approx(span[0], abs=1e-4)


def test_a_picked_up_object_is_let_go_by_a_grab_release():
    scene, warnings = _scene()
    scene.bml("bob", SBM.format(id="pick", body='<sbm:reach id="r" target="cup" sbm:action="pick-up"/>'), at=0.3)
    (held,) = scene.stage.held("bob")
    assert isinstance(held, Held) and (held.hand, held.obj) == ("right", "cup")
    scene.bml("bob", SBM.format(id="drop", body='<sbm:grab id="g" target="cup" sbm:grab-state="release"/>'), at=1.4)
    assert scene.stage.held("bob") == ()
    scene.run(4.0)
    assert not [w for w in warnings if w.id.startswith(("pick", "drop"))], [w.description for w in warnings]
    motion = scene.motion("bob")
    g_rot, g_pos = infuse.motion_fk(motion)
    wrist = scene.runtime.rig("bob").joint("r_wrist")
    cup = scene.object_track("cup")
    taken, release = int(round(held.since_s * FPS)), int(round(1.4 * FPS))
    in_hand = quat.rotate(quat.conjugate(g_rot[taken:release, wrist]), cup[taken:release] - g_pos[taken:release, wrist])
    assert np.abs(in_hand - in_hand[0]).max() < 1e-6  # carried until the release
    let_go = g_pos[release, wrist] + quat.rotate(g_rot[release, wrist], in_hand[0])
    assert np.allclose(cup[release:], let_go, atol=1e-6)  # then left where the hand was
    assert np.linalg.norm(g_pos[-1, wrist] - cup[-1]) > 0.1  # while the arm goes back without it


def test_the_frames_do_not_depend_on_the_block_size():
    """A grab and a reach's put-down give the same frames and object track in blocks of 1, 7 and 150."""
    results = []
    for block in (1, 7, 150):
        require_corpus()
        scene = Scene(fps=FPS, idle=False, quiet=True, block_frames=block)
        scene.add_character(corpus_character("xbot"), name="bob", packs=("locomotion-male", "reaching"))
        scene.add_object("cup", CUP, size=0.08)
        scene.add_object("shelf", SHELF, size=0.5)
        scene.bml("bob", SBM.format(id="take", body='<sbm:grab id="g" target="cup"/>'), at=0.3)
        scene.bml("bob", SBM.format(id="put", body='<sbm:reach id="r" target="shelf" sbm:action="put-down"/>'), at=2.5)
        scene.run(5.0)
        results.append((quat.canonical_sign(scene.motion("bob").local_rotations), scene.object_track("cup")))
    assert np.allclose(results[0][1][-1], SHELF, atol=1e-6)
    for rotations, cup in results[1:]:
        assert np.abs(rotations - results[0][0]).max() < 1e-9 and np.abs(cup - results[0][1]).max() < 1e-9


def test_a_hand_that_holds_something_takes_nothing_else():
    scene, warnings = _scene()
    scene.add_object("pen", (CUP[0] - 0.05, CUP[1], CUP[2]), size=0.02)
    scene.bml("bob", SBM.format(id="take", body='<sbm:grab id="g" target="cup"/>'), at=0.3)
    scene.bml("bob", SBM.format(id="grab2", body='<sbm:grab id="g" target="pen"/>'), at=2.0)
    scene.bml("bob", SBM.format(id="pick2", body='<sbm:reach id="r" target="pen" sbm:action="pick-up"/>'), at=2.0)
    scene.bml("bob", SBM.format(id="left", body='<sbm:grab id="g" target="pen" sbm:reach-type="left"/>'), at=2.0)
    got = {w.id: w.description for w in warnings}
    assert "the right hand holds 'cup'" in got["grab2:g"] and "the right hand holds 'cup'" in got["pick2:r"]
    assert "left:g" not in got  # the other hand is free
    assert [(h.hand, h.obj) for h in scene.stage.held("bob")] == [("right", "cup"), ("left", "pen")]
