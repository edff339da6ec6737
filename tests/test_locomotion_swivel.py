"""A foot lying flat, held by its heel, does not swivel: while its ball is down too its heading (the
heel-to-ball direction about the vertical) holds, so the blend's or the take's turn of the foot about
its heel does not sweep the ball along the ground. Measured on the output with FK: SmartBody's
FemaleLocomotion set walking straight on Xbot."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.contacts import foot_contacts, sole_positions
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file, require_corpus
from pack_support import smartbody_space

pytest.importorskip("infuse_locomotion")
FPS = 30
#: A sole point counts as down while within this height (m) of its planted height.
LOW_M = 0.003


def flat_feet(asset, **walk) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's sole slide (F - 1, P) in metres (a sole point's horizontal move while within
    :data:`LOW_M` of its planted height at both ends of the frame) and each foot's swivel (F - 1, 2)
    in degrees (its heel-to-ball heading's change over frames whose first and last sole points, heel
    and ball, are both down at both ends; zero elsewhere), of a walk ``walk`` (the locomotion
    controller's settings) run for 8 s."""
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("x", asset))
    rt.activate(name, controller("locomotion", **walk), 0.0)
    rt.run(8.0)
    m, rig = rt.motion(name), rt.rig(name)
    g_rot, g_pos = infuse.motion_fk(m)
    found = foot_contacts(m, rig.mapping, fk=(g_rot, g_pos))
    sole = sole_positions(found, g_pos[:, found.points])
    height = sole[..., 1]
    planted = np.nanpercentile(np.where(found.flags, height, np.nan), 5.0, axis=0)
    low = height - planted < LOW_M
    both = low[1:] & low[:-1]
    slide = np.linalg.norm(np.diff(sole[..., [0, 2]], axis=0), axis=-1) * both
    swivel = np.zeros((len(sole) - 1, 2))
    for k in (0, 1):
        heel, ball = np.flatnonzero(found.foot_of_point == k)[[0, -1]]
        along = sole[:, ball, [0, 2]] - sole[:, heel, [0, 2]]
        heading = np.degrees(np.arctan2(along[:, 0], along[:, 1]))
        turn = (np.diff(heading) + 180.0) % 360.0 - 180.0
        swivel[:, k] = np.abs(turn) * (both[:, heel] & both[:, ball])
    return slide, swivel


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


@pytest.fixture(scope="module")
def female_space(xbot, tmp_path_factory):
    """SmartBody's FemaleLocomotion set imported, built and infused onto Xbot."""
    return smartbody_space(xbot, "FemaleLocomotion", tmp_path_factory.mktemp("packs"))


def test_a_flat_foot_held_by_its_heel_keeps_its_heading(xbot, female_space):
    """Walking straight at 0.58 m/s, after the first 2 s: each foot lands on its heel and rolls down
    onto a ball its blend turns about the heel by 2-3 degrees (the left toe slid 2.3 and 1.1 mm in
    the two frames after it came down, 1.5 cm over 6 s). A flat foot turns at most 0.2 degrees a
    frame, no sole point slides 1 mm in a frame, and none more than 3 mm in all."""
    slide, swivel = flat_feet(xbot, pack=female_space, speed=0.58)
    steady = slice(2 * FPS, None)
    assert swivel[steady].max() < 0.2
    assert slide[steady].max() < 0.001
    assert slide[steady].sum(axis=0).max() < 0.003

