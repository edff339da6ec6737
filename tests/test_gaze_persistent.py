"""Persistent gazes (``gazeShift``) that a later one takes over from end, and the frames stay the same.

A scene of one hundred gaze shifts at points, a few timed gazes among them and a second character
looking at the first one's face, is evaluated as is and with the superseded gazes kept running (as
the gaze controller did before it ended them): the forward kinematics of both agree, and only the
last few gazes are still evaluated at the end.
"""
from __future__ import annotations

import numpy as np
import pytest

import infuse_gaze.controller as gaze_controller
from infuse.kinematics import forward_kinematics, motion_fk
from infuse.runtime.controller import Jobs
from infuse.scene import Scene
from infuse_gaze import Gaze

from runtime_characters import synthetic_character

SHIFTS = 100


def gazing_scene() -> Scene:
    """Ann shifts her gaze 100 times, every 0.1 to 0.5 s (blend-ins overlapping or not), at points around
    her, with a 0.6 s look at Bob after every 25th shift; Bob looks at her face throughout."""
    rng = np.random.default_rng(7)
    scene = Scene(fps=30.0, quiet=True, block_frames=45)
    scene.add_character(synthetic_character("ann"), "ann", position=(0.0, 0.0, 0.0), facing=0.0)
    scene.add_character(synthetic_character("bob"), "bob", position=(1.0, 0.0, 1.5), facing=180.0)
    scene.gaze("bob", "ann", at=0.0, influence="SHOULDER")
    at = 0.0
    for k in range(SHIFTS):
        point = (rng.uniform(-2.0, 2.0), rng.uniform(0.5, 2.2), rng.uniform(0.5, 3.0))
        scene.gaze("ann", point, at=at, influence=("HEAD", "SHOULDER", "WAIST")[k % 3])
        if k % 25 == 24:
            scene.gaze("ann", "bob", at=at + 0.2, duration=0.6, influence="HEAD")
            at += 0.6
        at += rng.uniform(0.1, 0.5)
    return scene


def gaze_activities(scene: Scene) -> list:
    """The gaze activities the runtime still evaluates at the scene's current time."""
    now = scene.runtime.time
    return [a for a in scene.runtime.activities if isinstance(a.controller, Gaze) and a.active_between(now, now)]


@pytest.fixture(scope="module")
def runs():
    """The scene with superseded gazes ended, the scene with them kept running (both evaluated to
    5 s after the last gaze: an ended gaze is evaluated up to its settling time), and the FK positions
    (F, J, 3) of each character in both."""
    ended = gazing_scene()
    ended.run()
    ended.run(5.0)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(gaze_controller, "_drop_superseded", lambda row, block: row)
        kept = gazing_scene()
        kept.run()
        kept.run(5.0)
    assert kept.runtime.frame == ended.runtime.frame
    fk = {name: (motion_fk(ended.motion(name))[1], motion_fk(kept.motion(name))[1]) for name in ("ann", "bob")}
    return ended, kept, fk


def test_ending_superseded_gazes_leaves_the_frames_unchanged(runs):
    _, _, fk = runs
    for name, (ended, kept) in fk.items():
        assert ended.shape == kept.shape and len(ended) > 30 * SHIFTS * 0.2
        assert np.abs(ended - kept).max() < 1e-6, name


def test_the_character_did_look_around(runs):
    _, _, fk = runs
    head = synthetic_character().skeleton.index["skullbase"]
    positions = fk["ann"][0][:, head]
    assert np.ptp(positions, axis=0).max() > 0.05, "ann's head hardly moved: the comparison would show nothing"


def test_only_the_last_gaze_is_still_evaluated(runs):
    ended, kept, _ = runs
    assert len([a for a in gaze_activities(kept) if a.rig.name == "ann"]) == SHIFTS
    assert [a.source.element for a in gaze_activities(ended) if a.rig.name == "ann"] == ["gazeShift"]
    ended.forget(1.0)
    assert len([a for a in ended.runtime.activities if isinstance(a.controller, Gaze)]) == 2  # ann's last, bob's


def live_gazes(forget: bool) -> tuple[Scene, np.ndarray]:
    """Ann gazes at a new point every 0.5 s, 100 times, the scene run between calls as a live one runs;
    with ``forget``, it keeps 1 s of frames and what ended before then. Returns the scene and the FK
    positions (F, J, 3) of every frame, gathered as they are evaluated."""
    rng = np.random.default_rng(11)
    scene = Scene(fps=30.0, quiet=True)
    scene.add_character(synthetic_character("ann"), "ann")
    skeleton = scene.runtime.rig("ann").skeleton
    positions = []
    for _ in range(SHIFTS):
        scene.gaze("ann", (rng.uniform(-2.0, 2.0), rng.uniform(0.5, 2.2), rng.uniform(0.5, 3.0)), influence="WAIST")
        scene.run(0.5)
        positions.append(forward_kinematics(skeleton, *scene.runtime.last_frames("ann", 15))[1])
        if forget:
            scene.forget(1.0)
    return scene, np.concatenate(positions)


def test_point_targets_of_ended_gazes_are_reused():
    (bounded, reused), (growing, fresh) = live_gazes(forget=True), live_gazes(forget=False)
    assert len(growing.targets) == SHIFTS
    assert len(bounded.targets) <= 12, sorted(bounded.targets)
    assert reused.shape == fresh.shape == (15 * SHIFTS, synthetic_character().skeleton.num_joints, 3)
    assert np.abs(reused - fresh).max() < 1e-6
    assert np.ptp(fresh[:, synthetic_character().skeleton.index["skullbase"]], axis=0).max() > 0.05


@pytest.mark.parametrize("block", [1, 7])
def test_gazes_taking_over_play_as_the_frame_by_frame_settings_make_them(block):
    """While a gaze takes over from another (its blend-in), a block that one gaze leads whole for each
    character keeps its settings, targets and the solver's products from block to block: the frames are
    the same, bit for bit, as with the settings worked out frame by frame, in blocks of one frame (a live
    scene's) and of several."""
    def play() -> Scene:
        rng = np.random.default_rng(3)
        scene = Scene(fps=30.0, quiet=True, block_frames=block)
        for k, name in enumerate(("ann", "bob", "cid")):
            scene.add_character(synthetic_character(name), name, position=(1.2 * k, 0.0, 0.0), facing=0.0)
        scene.gaze("bob", "ann", at=0.0, influence="SHOULDER")
        scene.gaze("cid", "bob", at=0.0)
        at = 0.0
        for k in range(12):
            point = (rng.uniform(-2.0, 2.0), rng.uniform(0.5, 2.2), rng.uniform(0.5, 3.0))
            scene.gaze("ann", point, at=at, influence=("HEAD", "SHOULDER", "WAIST")[k % 3])
            if k % 4 == 3:
                scene.gaze("cid", "ann" if k % 8 == 3 else point, at=at + 0.1)
            at += rng.uniform(0.1, 0.5)
        for _ in range(int(round((at + 1.0) * 30.0)) // block):
            scene.step(block)
        return scene

    kept = play()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(gaze_controller, "_owners", lambda rows, names, block: None)
        worked_out = play()
    with pytest.MonkeyPatch.context() as patch:  # nothing taken over from the chains of the gazes before
        patch.setattr(Jobs, "last", lambda jobs: None)
        afresh = play()
    for name in ("ann", "bob", "cid"):
        assert np.array_equal(kept.motion(name).local_rotations, worked_out.motion(name).local_rotations), name
        assert np.array_equal(kept.motion(name).local_rotations, afresh.motion(name).local_rotations), name
