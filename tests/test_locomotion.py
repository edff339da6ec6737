"""Locomotion controller on Xbot (65 joints): realized root speed, foot skate, turning, paths and stops."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.contacts import FootContacts, foot_contacts
from infuse.metrics import foot_skate
from infuse.packs.analysis import phase_contacts
from infuse.runtime import Runtime

from corpus_data import corpus_file, require_corpus

infuse_locomotion = pytest.importorskip("infuse_locomotion")
Locomotion = infuse_locomotion.Locomotion


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


def walk(asset, pack, seconds=5.0, **settings):
    rt = Runtime(fps=30)
    c = rt.add_character(infuse.Character("x", asset))
    rt.activate(c, Locomotion(pack, **settings), 0.0)
    rt.run(seconds)
    m = rt.motion(c)
    g_rot, g_pos = infuse.motion_fk(m)
    return rt.rig(c).mapping, m, g_rot, g_pos


@pytest.mark.parametrize("pack", ["locomotion-male", "locomotion-female"])
def test_realized_speed_matches_request_over_the_range(xbot, pack):
    from infuse_locomotion.controller import infusion_for

    rt = Runtime(fps=30)
    rig = rt.rig(rt.add_character(infuse.Character("x", xbot)))
    lo, hi = infusion_for(rig, pack).range("forward_speed")
    for v in np.linspace(max(lo, 0.3), hi, 5):
        mapping, m, _, g = walk(xbot, pack, 4.0, speed=float(v), max_accel=50.0)
        base = g[:, mapping.indices(m.skeleton)["base"]]
        d = base[-1] - base[30]
        realized = np.hypot(d[0], d[2]) / ((len(base) - 1 - 30) / 30.0)
        assert realized == pytest.approx(v, rel=0.05), (pack, v, realized)


def skate(mapping, m, g_rot, g_pos, phases: bool) -> float:
    """cm of foot skate per metre walked after the first second, with the default contact detector or
    with each point's flags narrowed to when it is on the ground (heel down, ball down)."""
    found = foot_contacts(m, mapping, fk=(g_rot, g_pos))
    if phases:
        found = phase_contacts(found, g_pos)
    cut = FootContacts(found.points, found.foot_of_point, found.flags[30:], found.ground, found.leg_length, found.lowest[30:])
    return foot_skate(g_pos[30:], cut, mapping.indices(m.skeleton)["base"]).per_metre


@pytest.mark.parametrize("pack", ["locomotion-male", "locomotion-female"])
def test_foot_skate_in_blended_walks(xbot, pack):
    detected, grounded = {}, {}
    # 0.5 and 0.8: the slow walk at a slower cadence with shorter steps; the others blend two clips
    # (1.7 and 2.0 m/s: walk_fast with jog for the male pack, whose contact timings differ most).
    for v in (0.5, 0.8, 1.2, 1.7, 2.0, 3.0):
        run = walk(xbot, pack, 5.0, speed=v, max_accel=50.0)
        detected[v], grounded[v] = skate(*run, phases=False), skate(*run, phases=True)
    print(pack, {k: round(v, 2) for k, v in detected.items()}, {k: round(v, 2) for k, v in grounded.items()})
    # On the ground (heel down, ball down): the legs step together and the planted points hold.
    assert max(g for v, g in grounded.items() if v >= 0.8) <= 1.5, grounded
    assert grounded[0.5] <= 2.5, grounded  # the slow foot lands gently: the detector sees it down early
    # The default detector also counts the ankle rising about the ball at heel off (docs/packs.md).
    assert detected[2.0] <= 2.0 and detected[3.0] <= 2.0, detected
    assert max(detected[0.8], detected[1.2], detected[1.7]) <= 3.5 and detected[0.5] <= 6.0, detected


def test_turning_and_path_following_stop_at_the_end(xbot):
    mapping, m, _, g = walk(xbot, "locomotion-female", 8.0, path=[(0.0, 2.0), (2.0, 4.0)], speed=1.2)
    base = g[:, mapping.indices(m.skeleton)["base"]]
    end = base[-1]
    assert np.hypot(end[0] - 2.0, end[2] - 4.0) < 0.35
    assert np.linalg.norm(base[-1, [0, 2]] - base[-10, [0, 2]]) < 0.02  # stopped
    mapping, m, _, g = walk(xbot, "locomotion-male", 4.0, speed=1.0, turn_rate=np.radians(40.0))
    left = g[:, mapping.indices(m.skeleton)["l_hip"]] - g[:, mapping.indices(m.skeleton)["r_hip"]]
    heading = np.unwrap(np.arctan2(-left[:, 2], left[:, 0]))
    rate = np.degrees(np.polyfit(np.arange(len(heading))[30:] / 30.0, heading[30:], 1)[0])
    assert rate == pytest.approx(40.0, abs=4.0)


def test_acceleration_is_limited(xbot):
    mapping, m, _, g = walk(xbot, "locomotion-male", 3.0, speed=2.0, max_accel=1.0)
    base = g[:, mapping.indices(m.skeleton)["base"]]
    v = np.hypot(*np.diff(base[:, [0, 2]], axis=0).T) * 30.0
    smooth = np.convolve(v, np.ones(15) / 15, mode="valid")
    assert smooth[0] < 0.6 and smooth[-1] > 1.6
