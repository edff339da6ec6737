"""Behaviours from infused behaviour packs in a scene, measured on the output with FK: walks reach their
spot in world coordinates, the character stays there and the next walk goes on from it; reaches touch
the object; picked-up objects follow the hand and are put down where asked."""
from __future__ import annotations

import copy

import numpy as np
import pytest

import infuse
from infuse.scene import Scene

from runtime_characters import corpus_character

BML = 'xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu"'


@pytest.fixture(scope="module")
def walked():
    """Bob, placed at (1, 0, -1) and turned to face +X, walks to two spots ahead of him in turn (the
    locomotion controller's steering is only exact for targets nearly ahead)."""
    scene = Scene(fps=30, quiet=True)
    scene.add_character(corpus_character("xbot"), "bob", position=(1.0, 0.0, -1.0), facing=90.0,
                        packs=["locomotion-male"])
    first = scene.walk_to("bob", (3.0, -0.9), at=0.2)
    second = scene.walk_to("bob", (4.5, -0.8), at=5.0)
    scene.run(9.0)
    return scene, first, second


def ground_path(scene, name):
    """(F, 2) x, z of the character's pelvis on the output."""
    rig = scene.runtime.rig(name)
    _, pos = infuse.motion_fk(scene.motion(name))
    return pos[:, rig.joint("base")][:, [0, 2]]


def test_walks_reach_their_spots_in_the_world(walked):
    scene, first, second = walked
    path = ground_path(scene, "bob")
    arrive_first = scene.scheduler.blocks[first].end_s
    stay = slice(int(arrive_first * 30) + 15, int(5.0 * 30))
    assert np.linalg.norm(path[stay] - (3.0, -0.9), axis=1).max() < 0.15  # there, and staying there
    assert np.linalg.norm(path[-20:] - (4.5, -0.8), axis=1).max() < 0.15  # then at the second spot
    assert np.linalg.norm(path[0] - (1.0, -1.0)) < 0.15  # from where it was placed
    first_walk, _ = scene.stagehands["locomotion"].walks["bob"]
    assert first_walk.settled is not None  # it stood on the pack's idle in between
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() < 2.5 / 30  # no jump anywhere: the idle took over there, the second walk went on from it


def test_the_scene_knows_where_a_walk_ends(walked):
    scene, _, _ = walked
    assert scene.locate("bob") == (4.5, 0.0, -0.8)


@pytest.fixture(scope="module")
def reached():
    scene = Scene(fps=30, quiet=True)
    scene.add_character(corpus_character("rpm"), "ann", packs=["reaching"])
    rig = scene.runtime.rig("ann")
    # in front of her, to her right, at chest height: inside the right hand's examples
    scene.add_object("cup", (-0.2, 1.2, 0.3), size=0.08)
    scene.add_object("shelf", (-0.3, 1.35, 0.25), size=0.2)
    touch = scene.reach("ann", "cup", at=0.2, hand="right")
    pick = scene.bml("ann", f'<bml {BML} id="pick"><sbm:reach id="r" target="cup" sbm:action="pick-up" '
                            f'sbm:reach-type="right"/></bml>', at=3.0)
    put = scene.bml("ann", f'<bml {BML} id="put"><sbm:reach id="r" target="shelf" sbm:action="put-down" '
                           f'sbm:reach-type="right"/></bml>', at=6.0)
    scene.run(9.0)
    return scene, rig, touch, pick, put


def test_reach_touches_the_object(reached):
    scene, rig, touch, _, _ = reached
    activity = scene.activities[(touch, "r1")]
    stroke = int(round((activity.start_s + activity.controller.stroke_s) * 30))
    _, pos = infuse.motion_fk(scene.motion("ann"))
    wrist = pos[stroke, rig.joint("r_wrist")]
    assert np.linalg.norm(wrist - (-0.2, 1.2, 0.3)) < 0.02


def test_picked_up_objects_follow_the_hand_and_are_put_down(reached):
    scene, rig, _, pick, put = reached
    assert scene.stage.held("ann") == ()  # put down again
    target = scene.runtime.target("cup")
    assert np.allclose(target.positions(np.zeros(1), None)[0], (-0.3, 1.35, 0.25), atol=1e-6)  # on the shelf now
    warned = [e for e in scene.feedback.log if e.kind == "warningFeedback" and e.id.startswith(("pick", "put"))]
    assert not [e for e in warned if e.type == "CANNOT_CREATE_BEHAVIOR"]


def test_putting_down_nothing_is_reported():
    scene = Scene(fps=30, quiet=True)
    scene.add_character(corpus_character("rpm"), "ann", packs=["reaching"])
    scene.add_object("shelf", (-0.3, 1.35, 0.25))
    scene.bml("ann", f'<bml {BML} id="put"><sbm:reach id="r" target="shelf" sbm:action="put-down"/></bml>')
    (warning,) = [e for e in scene.feedback.log if e.kind == "warningFeedback" and e.id == "put:r"]
    assert "holds nothing" in warning.description


def test_carried_objects_are_tracked(reached):
    scene, rig, _, pick, put = reached
    track = scene.object_track("cup")
    assert track.shape == (scene.runtime.frame, 3)
    assert np.allclose(track[0], (-0.2, 1.2, 0.3)) and np.allclose(track[-1], (-0.3, 1.35, 0.25))
    _, pos = infuse.motion_fk(scene.motion("ann"))
    held = slice(int(4.5 * 30), int(6.3 * 30))  # picked up, not yet put down: it keeps to the wrist
    gap = np.linalg.norm(track[held] - pos[held, rig.joint("r_wrist")], axis=1)
    assert np.ptp(gap) < 1e-6 and gap.max() < 0.1
    assert np.ptp(track[held], axis=0).max() > 0.05  # and the wrist moved it


def test_an_arrived_walk_hands_over_to_the_idle_where_it_stands():
    scene = Scene(fps=30, quiet=True)
    scene.add_character(corpus_character("xbot"), "bob", packs=["locomotion-male"])
    scene.walk_to("bob", (0.2, 2.0), at=0.2)
    scene.run(6.0)
    (walk,) = scene.stagehands["locomotion"].walks["bob"]
    assert walk.settled is not None and walk.activity.end_s is not None  # the idle clip took over
    assert walk.settled.start_s <= walk.end_s + 0.5  # at rest by the end its walk was planned to have
    rig = scene.runtime.rig("bob")
    _, pos = infuse.motion_fk(scene.motion("bob"))
    after = int(round(walk.settled.start_s * 30))
    assert np.linalg.norm(pos[after:, rig.joint("base")][:, [0, 2]] - (0.2, 2.0), axis=1).max() < 0.15
    feet = pos[:, [rig.joint("l_ankle"), rig.joint("r_ankle")]][..., [0, 2]]
    moving = np.nonzero((np.linalg.norm(np.diff(feet, axis=0), axis=2) > 1e-3).any(axis=1))[0]
    assert after <= moving[moving < after].max() + 30  # within a second of the last step
    around = slice(after - 5, after + 20)  # through the crossfade: no jump of the body; the feet step into place
    for joint, most in (("base", 0.01), ("skullbase", 0.02), ("l_ankle", 0.05), ("r_ankle", 0.05)):
        steps = np.linalg.norm(np.diff(pos[around, rig.joint(joint)], axis=0), axis=1)
        assert steps.max() < most, joint


def test_a_walk_settles_into_the_idle_only_once_its_stop_is_over(monkeypatch):
    """Standing still for half a second is not enough: the stop steps and the fade into the pack's idle
    must be over (the locomotion controller's ``at_rest``) when the idle clip takes over."""
    from infuse_locomotion import walks

    checks = []  # (locomotion state when the scene looked, whether the idle took over)
    settle = walks.Walks._settle

    def looked(self, name, walk, after):
        state = copy.deepcopy(walk.activity.state)  # as it is now: the walk goes on changing its own
        settle(self, name, walk, after)
        checks.append((state, walk.settled is not None))

    monkeypatch.setattr(walks.Walks, "_settle", looked)
    scene = Scene(fps=30, quiet=True)
    scene.add_character(corpus_character("xbot"), "bob", packs=["locomotion-male"])
    scene.walk_to("bob", (-2.0, -1.0), at=0.5)
    scene.run(8.0)
    (walk,) = scene.stagehands["locomotion"].walks["bob"]
    controller = walk.activity.controller
    assert walk.settled is not None and checks[-1][1]
    assert controller.at_rest(checks[-1][0])  # at rest when the idle clip took over
    assert not [s for s, took in checks if took and not controller.at_rest(s)]  # never before it was at rest
