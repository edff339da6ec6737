"""Reach controller on Xbot: wrist at the target at the stroke, grab and put down an object."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.runtime import Runtime

from corpus_data import corpus_file, require_corpus

infuse_reach = pytest.importorskip("infuse_reach")
ReachState = infuse_reach.controller.ReachState
Locomotion = pytest.importorskip("infuse_locomotion").Locomotion


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


def inside_targets(rig, hand, count, seed):
    """Points inside the hand's examples' hull (convex combinations of the examples' body-frame wrist
    points, pulled 10% toward their centre), used as world points: the character stands near the origin."""
    from infuse.packs import space_on

    space = space_on(rig, "reaching")
    pts = space.tessellations[hand].points
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        w = rng.dirichlet(np.ones(4))
        p = w @ pts[rng.choice(len(pts), 4, replace=False)]
        out.append(0.9 * p + 0.1 * pts.mean(axis=0))
    return out


def test_reach_error_inside_the_hull(xbot):
    rt = Runtime(fps=30)
    c = rt.add_character(infuse.Character("x", xbot))
    rig = rt.rig(c)
    rt.activate(c, Locomotion("locomotion-male", speed=0.0), 0.0)
    jobs = []
    start = 0.3
    for hand in ("left", "right"):
        for p in inside_targets(rig, hand, 4, 3):
            reach = infuse_reach.Reach(tuple(p), hand=hand)
            act = rt.activate(c, reach, start)
            jobs.append((act, hand, p))
            start = act.end_s + 0.8
    rt.run(start + 0.5)
    m = rt.motion(c)
    g = infuse.motion_fk(m)[1]
    ix = rig.mapping.indices(m.skeleton)
    errors = []
    for act, hand, p in jobs:
        f = int(round((act.start_s + act.binding.stroke) * 30))
        errors.append(np.linalg.norm(g[f, ix[f"{hand[0]}_wrist"]] - p))
        assert not act.state_of(ReachState).outside  # in the reach's own body frame, the target is inside the examples' hull
    print("reach errors (cm):", np.round(np.array(errors) * 100, 4))
    assert max(errors) <= 0.01


def test_grab_carries_the_object_and_put_leaves_it(xbot):
    rt = Runtime(fps=30)
    c = rt.add_character(infuse.Character("x", xbot))
    rig = rt.rig(c)
    rt.activate(c, Locomotion("locomotion-male", speed=0.0), 0.0)
    cup, place = inside_targets(rig, "right", 2, 7)
    rt.add_target("cup", tuple(cup))
    grab = rt.activate(c, infuse_reach.Reach("cup", hand="right", action="grab", obj="cup"), 0.2)
    put = rt.activate(c, infuse_reach.Reach(tuple(place), hand="right", action="put", obj="cup"), grab.end_s + 0.2)
    rt.run(put.end_s + 0.5)
    assert isinstance(rt.target("cup"), infuse.runtime.PointTarget)
    assert np.allclose(rt.target("cup").point, place, atol=1e-9)
    m = rt.motion(c)
    g = infuse.motion_fk(m)[1]
    wrist = g[:, rig.mapping.indices(m.skeleton)["r_wrist"]]
    f = int(round((put.start_s + put.binding.stroke) * 30))
    assert np.linalg.norm(wrist[f] - place) < 0.01  # the hand brought the cup to the place
    with pytest.raises(infuse.UsageError):
        infuse_reach.Reach((0, 1, 0.4), action="grab")
