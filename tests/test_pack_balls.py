"""Infused locomotion clips keep each foot's ball from going under the ground (infuse.packs.balls)."""
from __future__ import annotations

import numpy as np
import infuse
from infuse.contacts import Foot, feet, leg_length
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.packs import balls
from infuse.packs.infusion import infuse_character

from corpus_data import corpus_file
from wild_data import wild_file

LONG_FOOT = "numediart-ofxMotionMachine/mmExampleData/animation.bvh"


def _deepest(space, pair) -> tuple[float, float]:
    """The deepest any locomotion clip's ball goes below its idle's (m), and the idle's ball height."""
    idle = next(c for c in space.clips.values() if c.role == "idle")
    _, p = motion_fk(idle.motion)
    standing = float(p[:, [f.ball for f in pair], 1].min())
    lowest = min(float(motion_fk(c.motion)[1][:, [f.ball for f in pair], 1].min()) for c in space.clips.values())
    return standing - lowest, standing


def test_a_long_foot_pitching_over_its_ball_keeps_the_ball_above_the_ground():
    # A foot 0.4 m from ankle to ball on a 0.67 m leg: the pack's heel rise, copied as a pitch with the
    # ankle raised for the leg, swung the ball 11.6 cm under its standing height.
    asset = infuse.load(wild_file(LONG_FOOT))
    mapping = map_skeleton(asset)
    pair = feet(asset.skeleton, mapping)
    space = infuse_character(infuse.Character("long", asset, mapping), ["locomotion-male"], mapping=mapping).spaces["locomotion-male"]
    depth, _ = _deepest(space, pair)
    assert depth <= balls.DEEPER * leg_length(asset.skeleton, pair) + 0.006  # was 0.116


def test_feet_of_usual_proportions_are_left_as_retargeted(monkeypatch):
    asset = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    character = infuse.Character("x", asset)
    grounded = infuse_character(character, ["locomotion-male"]).spaces["locomotion-male"]
    import infuse.packs.infusion as infusion

    monkeypatch.setattr(infusion, "_balls_grounded", lambda pack, names, out, pair: out)
    plain = infuse_character(character, ["locomotion-male"]).spaces["locomotion-male"]
    for name, clip in grounded.clips.items():
        np.testing.assert_array_equal(clip.motion.local_rotations, plain.clips[name].motion.local_rotations)


def test_only_the_depth_beyond_the_allowed_is_raised():
    asset = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    mapping = map_skeleton(asset)
    pair = feet(asset.skeleton, mapping)
    space = infuse_character(infuse.Character("x", asset, mapping), ["locomotion-male"], mapping=mapping).spaces["locomotion-male"]
    walk = next(c for c in space.clips.values() if c.role == "cycle").motion
    _, p = motion_fk(walk)
    ball_heights = p[:, [f.ball for f in pair], 1]
    planted = ball_heights.min(axis=0) + 0.08  # as if the ground were 8 cm higher
    allowed = np.full((walk.num_frames, 2), 0.02)
    moved, raise_m = balls.balls_above(walk, pair, planted, allowed)
    _, q = motion_fk(moved)
    after = q[:, [f.ball for f in pair], 1]
    floor = planted - 0.02 - balls.DEEPER * leg_length(asset.skeleton, pair)
    under = ball_heights < floor[None]
    assert under.any() and (~under).any()
    np.testing.assert_allclose(after[under], np.broadcast_to(floor, after.shape)[under], atol=1e-3)
    np.testing.assert_allclose(raise_m[under], (floor[None] - ball_heights)[under], atol=1e-9)
    assert np.all(raise_m[~under] == 0.0)
    ankles = [f.ankle for f in pair]
    horizontal = np.linalg.norm((q[:, ankles] - p[:, ankles])[..., [0, 2]], axis=-1)
    assert horizontal.max() < 1e-3  # raised straight up
    untouched = ~under.any(axis=1)
    np.testing.assert_allclose(q[untouched], p[untouched], atol=1e-6)


def test_depths_are_below_the_planted_height_only():
    positions = np.zeros((3, 4, 3))
    positions[:, 1, 1] = [0.05, -0.02, 0.0]
    pair = (Foot("left", 0, 0, 0, 1, (0, 1), ()), Foot("right", 0, 0, 0, None, (0,), ()))
    d = balls.depths(positions, pair, np.array([0.0, 0.01]))
    np.testing.assert_allclose(d, [[0.0, 0.01], [0.02, 0.01], [0.0, 0.01]])


def test_planted_heights_are_the_flat_foot_median():
    positions = np.zeros((4, 2, 3))
    positions[:, 1, 1] = [0.03, 0.02, 0.5, 0.04]
    pair = (Foot("left", 0, 0, 0, 1, (0, 1), ()), Foot("right", 0, 0, 0, 1, (0, 1), ()))
    flat = np.array([[True, False], [True, False], [False, False], [True, False]])
    np.testing.assert_allclose(balls.planted_heights(positions, pair, flat), [0.03, 0.035])
