"""Locomotion from packs beyond the built-in ones: the hull of what a pack realizes, requests outside it,
packs imported from real motion sets (SmartBody, Bandai), and scenes whose walks end when they arrive.
Measured on the output with FK."""
from __future__ import annotations

import math

import numpy as np
import pytest

import infuse
from infuse.packs.analysis import LOCOMOTION_COORDINATES, resolution_of
from infuse.packs.coverage import Hull, SpeedLimit, coverage, describe_coverage, speed_limits
from infuse.packs.infusion import BlendSpace
from infuse.packs.tessellation import Tessellation
from infuse.runtime import Runtime

from corpus_data import corpus_file, require_corpus

infuse_locomotion = pytest.importorskip("infuse_locomotion")
Locomotion = infuse_locomotion.Locomotion


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


def square_space():
    """A 3D tessellation over forward speeds 0.5-2 m/s, lateral -0.5-0.5 m/s, turn rates -1-1 rad/s."""
    corners = [(f, s, w) for f in (0.5, 2.0) for s in (-0.5, 0.5) for w in (-1.0, 1.0)]
    return Tessellation.build(("forward_speed", "lateral_speed", "turn_rate"), [str(c) for c in corners], corners)


def test_hull_intervals_are_exact():
    t = square_space()
    lo, hi = Hull(t).interval(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0]]), np.array([1.0, 0.0, 0.0]))
    assert lo[0] == pytest.approx(0.5, abs=1e-6) and hi[0] == pytest.approx(2.0, abs=1e-6)
    assert lo[1] > hi[1]  # turning at 2 rad/s is outside at every speed
    top, low = speed_limits(t, [0.0, math.pi / 2, math.pi])
    assert top[0] == pytest.approx(2.0, abs=1e-6) and low[0] == pytest.approx(0.5, abs=1e-6)
    assert top[1] == 0.0 and top[2] == 0.0  # nothing sideways (0.5 m/s across needs 0.5 along) or back
    turns, ok = Hull(t).nearest_turns(np.array([[1.0, 0.0], [3.0, 0.0]]), np.array([1.7, 0.3]))
    assert ok.tolist() == [True, False] and turns[0] == pytest.approx(1.0, abs=1e-5) and turns[1] == 0.3
    limit = SpeedLimit(t)
    assert limit(0.0) == pytest.approx(2.0, abs=1e-6) and limit.lowest(0.0) == pytest.approx(0.5, abs=1e-6)
    table = coverage(t)
    assert table["top"][0] == pytest.approx(2.0, abs=1e-6)
    assert any("deg/s" in line for line in describe_coverage(table))


def turning_space() -> BlendSpace:
    """A locomotion blend space (no clips) of an idle, walks forward turning left, straight and right,
    strafes, a walk back and turns on the spot (m/s, m/s, rad/s)."""
    examples = {"idle": (0.0, 0.0, 0.0), "walk": (1.2, 0.0, 0.0), "walk_left": (1.0, 0.05, 0.9),
                "walk_right": (1.0, -0.05, -0.9), "strafe_left": (0.1, 0.7, 0.0), "strafe_right": (0.1, -0.7, 0.0),
                "back": (-0.8, 0.0, 0.0), "spin_left": (0.0, 0.0, 1.4), "spin_right": (0.0, 0.0, -1.4)}
    t = Tessellation.build(LOCOMOTION_COORDINATES, list(examples), list(examples.values()),
                           resolution=resolution_of("locomotion"))
    return BlendSpace("turning", "1", "locomotion", {}, {"locomotion": t})


def test_requests_outside_are_weighed_once_at_their_nearest_turn():
    space = turning_space()
    t = space.tessellations["locomotion"]
    hull = space.speed_limit().hull
    query = np.array([
        [1.1, 0.0, 0.2],     # inside
        [1.1, 0.0, 2.5],     # turning harder than any walk: outside, turned back in
        [0.0, 0.0, 3.0],     # turning on the spot faster than the spins
        [0.0, 0.0, -1.4],    # on the spot, on the boundary (an example's point)
        [1.0, 0.05, 0.9],    # on the boundary (an example's point)
        [0.5, 0.025, 1.15],  # on the boundary (halfway along the edge between a turning walk and a spin)
        [3.0, 0.0, 0.0],     # faster than every example: no turn rate holds it, the hull's nearest point
        [-0.4, 0.3, -2.0],   # back and to the side, turning hard
    ])
    w, inside = space.locomotion_weights(query)
    assert inside.tolist() == [True, False, False, True, True, True, False, False]
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    turned = _as_alone(space, query, w, inside)
    np.testing.assert_allclose(w[turned] @ t.points[:, 2], hull.nearest_turns(query[turned, :2], query[turned, 2])[0],
                               atol=1e-6)  # shows the nearest turn the hull holds
    assert turned.tolist() == [1, 2, 7]  # the request faster than every example has no turn rate held
    np.testing.assert_allclose(w[:3] @ t.points[:, :2], query[:3, :2], atol=1e-9)  # the velocity asked, shown


def _as_alone(space: BlendSpace, query: np.ndarray, w: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Checks locomotion weights ``w`` (Q, N) and flags ``inside`` (Q,) of ``query`` (Q, 3) against each request
    weighed alone (:meth:`BlendSpace.weights`), at its nearest turn rate where it lies outside and the hull
    holds its velocity; returns the indices of those turned."""
    hull = space.speed_limit().hull
    turned = []
    for i, q in enumerate(query):
        alone, flag = space.weights("locomotion", q[None])
        assert flag[0] == inside[i]
        turns, ok = hull.nearest_turns(q[None, :2], q[None, 2])
        if not flag[0] and ok[0]:
            alone = space.weights("locomotion", np.array([[q[0], q[1], turns[0]]]))[0]
            turned.append(i)
        np.testing.assert_allclose(w[i], alone[0], rtol=0.0, atol=1e-12)
    return np.array(turned, dtype=np.int64)


@pytest.mark.parametrize("examples", [
    {"idle": (0.0, 0.0, 0.0), "walk": (1.2, 0.0, 0.0), "left": (0.1, 0.7, 0.0), "right": (0.1, -0.7, 0.0),
     "back": (-0.8, 0.0, 0.0)},                                               # no turning clips: 2D
    {"idle": (0.0, 0.0, 0.0), "walk": (1.2, 0.0, 0.0), "run": (3.0, 0.0, 0.0)},  # straight ahead only: 1D
    {"walk": (1.2, 0.0, 0.0)},                                                 # one clip: a point
], ids=["2d", "1d", "point"])
def test_spaces_of_fewer_dimensions_weigh_requests_as_alone(examples):
    t = Tessellation.build(LOCOMOTION_COORDINATES, list(examples), list(examples.values()),
                           resolution=resolution_of("locomotion"))
    space = BlendSpace("flat", "1", "locomotion", {}, {"locomotion": t})
    query = np.array([[0.5, 0.1, 0.0], [0.5, 0.1, 2.0], [4.0, 0.0, 0.3], [0.0, 0.0, -3.0], [-1.0, 0.5, 0.2]])
    w, inside = space.locomotion_weights(query)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    _as_alone(space, query, w, inside)
    assert inside[:2].all() and (t.dimension == 0 or not inside[2])  # a turn rate no clip shows is spun at the root


def test_nearest_turns_are_the_hull_intervals_along_the_turn_rate():
    for t in (turning_space().tessellations["locomotion"], square_space()):
        hull = Hull(t)
        rng = np.random.default_rng(3)
        velocity = rng.uniform(-2.5, 2.5, (300, 2))
        turn = rng.uniform(-4.0, 4.0, 300)
        base = np.concatenate((velocity, np.zeros((300, 1))), axis=1)
        lo, hi = hull.interval(base, np.array([0.0, 0.0, 1.0]))
        turns, ok = hull.nearest_turns(velocity, turn)
        assert ok.tolist() == (lo <= hi).tolist() and 0 < ok.sum() < 300
        np.testing.assert_allclose(turns[ok], np.clip(turn[ok], lo[ok], hi[ok]), rtol=0.0, atol=1e-5)
        assert np.array_equal(turns[~ok], turn[~ok])
        assert t.contains(np.concatenate((velocity[ok], turns[ok, None]), axis=1)).all()  # just inside


def test_located_points_weigh_as_the_points():
    t = turning_space().tessellations["locomotion"]
    rng = np.random.default_rng(5)
    query = rng.uniform((-1.0, -1.0, -2.0), (1.5, 1.0, 2.0), (40, 3))
    at = t.locate(query)
    w, inside = t.weights(query)
    assert np.array_equal(t.weights(query, at)[0], w) and np.array_equal(at.inside, inside)
    assert np.array_equal(t.contains(query), inside) and 0 < inside.sum() < 40
    rows = np.flatnonzero(~inside)[:5]
    moved = query.copy()
    moved[rows, 2] *= 0.1
    merged = at.replaced(rows, t.locate(moved[rows]))
    np.testing.assert_allclose(t.weights(moved, merged)[0], t.weights(moved)[0], rtol=0.0, atol=1e-12)
    assert np.array_equal(merged.inside, t.contains(moved)) and not inside[rows].any()


def test_a_single_walk_limits_speed_to_its_own():
    walk = Tessellation.build(("forward_speed", "lateral_speed", "turn_rate"), ["walk"], [(1.3, 0.0, 0.0)])
    top, low = speed_limits(walk, [0.0, math.pi / 2])
    assert top[0] == pytest.approx(1.3) and low[0] == pytest.approx(1.3) and top[1] == 0.0


def test_a_speed_beyond_the_pack_is_reported_once_and_walked_at_the_top_speed(xbot):
    notes = []
    rt = Runtime(fps=30, report=lambda who, message: notes.append(message))
    c = rt.add_character(infuse.Character("x", xbot))
    rt.activate(c, Locomotion("locomotion-female", speed=6.0, max_accel=50.0), 0.0)
    rt.run(4.0)
    top = rt.activities[0].binding.limit(0.0)
    assert 3.0 < top < 3.5
    (note,) = notes
    assert "asked 6.00 m/s forward" in note and f"at most {top:.2f} m/s" in note and f"walking at {top:.2f} m/s" in note
    m = rt.motion(c)
    _, g = infuse.motion_fk(m)
    base = g[:, rt.rig(c).joint("base")]
    realized = np.hypot(*(base[-1] - base[45])[[0, 2]]) / ((len(base) - 1 - 45) / 30.0)
    assert realized == pytest.approx(top, rel=0.02)


@pytest.fixture(scope="module")
def sb_female(tmp_path_factory):
    """SmartBody's FemaleLocomotion set imported and built as a pack (copied to a temporary folder)."""
    from infuse.packs import build_pack, import_smartbody

    source = corpus_file("smartbody/behaviorsets/FemaleLocomotion")
    return build_pack(import_smartbody(source, tmp_path_factory.mktemp("packs") / "female", name="sb-female")).manifest.path.parent


def test_a_scene_lasts_until_its_walks_have_arrived(xbot, sb_female):
    from infuse.scene import Scene

    scene = Scene(fps=30, quiet=True)
    scene.add_character(infuse.Character("x", xbot), "ann", packs=[str(sb_female)])
    block = scene.walk_to("ann", (1.5, 4.0), at=0.0)
    nominal = scene.scheduler.blocks[block].end_s
    scene.run()
    assert scene.end_time > nominal  # the pack walks slower than the nominal 1.2 m/s
    rig = scene.runtime.rig("ann")
    _, pos = infuse.motion_fk(scene.motion("ann"))
    end = pos[-15:, rig.joint("base")][:, [0, 2]].mean(axis=0)
    assert np.linalg.norm(end - (1.5, 4.0)) < 0.05
    assert not [e for e in scene.feedback.log if e.kind == "warningFeedback" and "short" in e.description]


def test_a_run_faster_than_the_pack_is_reported(xbot):
    from infuse.scene import Scene

    scene = Scene(fps=30, quiet=True)
    scene.add_character(infuse.Character("x", xbot), "bob", packs=["locomotion-male"])
    scene.walk_to("bob", (0.0, 12.0), at=0.0, manner="run", speed=6.0)
    (warning,) = [e for e in scene.feedback.log if e.kind == "warningFeedback" and "m/s" in e.description]
    top = scene.pack_space("bob", "locomotion").speed_limit()(0.0)
    assert "asked 6.00 m/s (run)" in warning.description and f"walking at {top:.2f} m/s" in warning.description
    scene.run()
    assert [e for e in scene.feedback.log if e.kind == "warningFeedback" and "m/s" in e.description] == [warning]


def test_pack_test_prints_the_trials_and_draws_them(tmp_path, capsys):
    from infuse.cli import main

    xbot_file = corpus_file("runxaway-models/Xbot.glb")
    out = tmp_path / "male.png"
    assert main(["pack", "test", "locomotion-male", "--on", str(xbot_file), "--speeds", "1.0,2.0", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    rows = [line.split() for line in printed.splitlines() if "->" in line and "%" in line]
    assert [float(r[0]) for r in rows] == [1.0, 2.0]
    assert all(abs(float(r[2]) / float(r[0]) - 1.0) < 0.05 for r in rows)  # realized within 5%
    assert "heading drift over 8 s" in printed and "walk to a target" in printed
    (parts,) = [line for line in printed.splitlines() if "foot skate of the walks to a target by part" in line]
    cm = {p.rsplit(" ", 1)[0].strip(): float(p.rsplit(" ", 1)[1]) for p in parts.split(": ", 1)[1].split(",")}
    assert list(cm) == ["on the spot", "start", "walk", "stop", "settle"], cm
    # measured 0.1-1.1 cm (the walk part 0.7, 14.4 while the pinning held the ankle from each heel strike)
    assert all(0.0 <= v < 3.0 for v in cm.values()), cm
    for name in ("male.png", "male-straight.png", "male-target.png"):
        from PIL import Image

        with Image.open(tmp_path / name) as image:
            assert image.size[0] >= 400 and len(np.unique(np.asarray(image.convert("L")))) > 10  # drawn, not blank


def test_a_walk_to_a_target_is_split_into_its_parts():
    """A pelvis path (30 fps) turning on the spot for 1 s, speeding up to 1.3 m/s over 1 s, walking 2 s,
    slowing down over 1 s and standing 1 s: each part found where it is, give or take the 0.3 s window."""
    from infuse.packs.walk_test import PARTS, walk_parts

    t = np.arange(180) / 30.0
    speed = np.interp(t, [0.0, 1.0, 2.0, 4.0, 5.0, 6.0], [0.0, 0.0, 1.3, 1.3, 0.0, 0.0])
    ground = np.stack((np.zeros_like(t), np.cumsum(speed) / 30.0), axis=-1)
    parts = np.array(PARTS)[walk_parts(ground)]
    for part, (a, b) in {"on the spot": (0.0, 1.0), "start": (1.2, 1.8), "walk": (2.0, 4.0), "stop": (4.2, 4.8),
                         "settle": (5.2, 6.0)}.items():
        assert (parts[(t >= a) & (t < b)] == part).all(), (part, parts[(t >= a) & (t < b)])


def test_a_pack_slower_than_a_third_of_a_metre_per_second_is_tried_at_its_own_speeds():
    """On a short-legged rig (KayKit's knight, legs of 0.38 m) SmartBody female walks at 0.296 m/s at most:
    the trial asked 0.30 m/s, 1.6% beyond what the pack realizes there, and counted it as a speed error."""
    from types import SimpleNamespace

    from infuse.packs.walk_test import SPEEDS, forward_speeds

    points = np.array([[0.296, 0.0, 0.0], [0.0, 0.0, 0.0], [0.234, 0.0, -0.787], [0.056, -0.104, 0.0]])
    space = SimpleNamespace(tessellations={"locomotion": SimpleNamespace(points=points)})
    np.testing.assert_allclose(forward_speeds(space), np.full(SPEEDS, 0.296))
    space.tessellations["locomotion"].points = np.concatenate((points, [[0.2, 0.0, 0.0], [1.4, 0.0, 0.0]]))
    np.testing.assert_allclose(forward_speeds(space), np.linspace(0.3, 1.4, SPEEDS))  # from 0.3 m/s, as before


def test_a_swaying_path_is_no_loop_and_a_circle_is():
    """A slow walk (0.3 m/s, 30 fps) whose pelvis path keeps a sway of 2 cm every 1.2 s (a stride the
    one-second smoothing leaves) swings its direction 19 degrees to either side: summed over 20 s, as
    the measure did, about a thousand degrees, a "loop"; its direction goes round 38 degrees. A path
    circling at 1 m/s on a 2 m radius for 20 s goes round 573 degrees."""
    from infuse.packs.walk_test import LOOP_DEG, path_turn_deg

    t = np.arange(600) / 30.0
    sway = np.stack((0.02 * np.sin(2 * np.pi * t / 1.2), 0.3 * t), axis=-1)
    swings = np.diff(np.unwrap(np.arctan2(*np.diff(sway, axis=0).T)))
    assert np.degrees(np.abs(swings).sum()) > LOOP_DEG  # the measure before: a loop
    assert path_turn_deg(sway) == pytest.approx(2.0 * np.degrees(np.arctan(2 * np.pi * 0.02 / 1.2 / 0.3)), abs=1.0)
    circle = np.stack((np.cos(t / 2.0), np.sin(t / 2.0)), axis=-1) * 2.0
    assert path_turn_deg(circle) == pytest.approx(360.0 * 20.0 / (4.0 * np.pi), rel=0.02)


def test_walking_at_the_speed_asked_is_walking_between_faster_clips():
    """A start clip speeding up to 0.7 m/s, then the walk asked at 0.54 m/s for 3 s and its stop
    (SmartBody's female set): the walk after the start is walking (it was split as the stop, being
    slower than 90% of the start's speed)."""
    from infuse.packs.walk_test import PARTS, walk_parts

    t = np.arange(240) / 30.0
    speed = np.interp(t, [0.0, 1.0, 1.5, 2.0, 5.0, 6.0, 8.0], [0.0, 0.7, 0.7, 0.54, 0.54, 0.0, 0.0])
    ground = np.stack((np.zeros_like(t), np.cumsum(speed) / 30.0), axis=-1)
    walking = (t >= 2.2) & (t < 4.8)
    assert (np.array(PARTS)[walk_parts(ground, cruise=0.54)][walking] == "walk").all()
    assert not (np.array(PARTS)[walk_parts(ground)][walking] == "walk").any()  # by the top speed alone


@pytest.mark.parametrize("argv, says", [
    (["pack", "test", "reaching"], "a reach pack"),
    (["pack", "test", "locomotion-male", "--speeds", "fast"], "--speeds takes numbers"),
    (["pack", "test", "locomotion-male", "--speeds", "-1"], "--speeds takes speeds above 0"),
    (["pack", "test", "locomotion-male", "-o", "top.gif"], "the top view is a .png"),
])
def test_pack_test_refuses_what_it_cannot_walk(argv, says, capsys):
    from infuse.cli import main

    pictures = [] if "-o" in argv else ["--no-pictures"]
    assert main(argv + ["--on", str(corpus_file("runxaway-models/Xbot.glb"))] + pictures) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err


@pytest.fixture(scope="module")
def bandai_masculinity(tmp_path_factory):
    """Bandai dataset-1's masculinity style (walks forward, back, left and right, a run and a dash, all
    recorded takes) imported and built as a pack."""
    from infuse.packs import build_pack, import_bvh_folder

    source = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data")
    folder = tmp_path_factory.mktemp("packs") / "masculinity"
    return build_pack(import_bvh_folder(source, folder, pattern="dataset-1_*_masculinity_*.bvh")).manifest.path.parent


@pytest.mark.parametrize("which", ["sb_female", "bandai_masculinity"])
def test_imported_packs_steer_exactly(xbot, which, request):
    """Speeds over the pack's forward range within 5%, heading drift within 3 degrees over 8 s, walks to
    targets 2 and 5 m away in six directions within 5 cm, paths at most 1.15x the straight line, no loops."""
    from infuse.packs.walk_test import trial_pack

    trial = trial_pack(infuse.Character("xbot", xbot), request.getfixturevalue(which), distances=(2.0, 5.0))
    worst = trial.worst()
    assert len(trial.speeds) == 5 and worst["speed_error"] < 0.05, [(s.asked, s.realized) for s in trial.speeds]
    assert worst["drift_deg"] < 3.0
    assert worst["miss_m"] < 0.05 and worst["path_ratio"] < 1.15 and worst["loops"] == 0
    assert all(t.arrival_s is not None for t in trial.targets)


def test_a_walk_taken_over_before_it_arrives_is_reported(xbot):
    from infuse.scene import Scene

    scene = Scene(fps=30, quiet=True)
    scene.add_character(infuse.Character("x", xbot), "bob", packs=["locomotion-male"])
    first = scene.walk_to("bob", (0.0, 6.0), at=0.0)
    scene.walk_to("bob", (2.0, 0.0), at=2.0)  # replaces nothing: a second walk, two seconds into the first
    scene.run()
    (short,) = [e for e in scene.feedback.log if e.kind == "warningFeedback" and "short of its target" in e.description]
    assert short.id.startswith(first)
    metres = float(short.description.split(":")[1].split()[0])
    assert 2.0 < metres < 5.5  # two seconds of walking from standing covered at most 2.6 m of the 6


def test_feet_of_an_imported_pack_stay_planted(xbot, bandai_masculinity):
    """Straight walks over the forward range of recorded takes (Bandai masculinity) on Xbot: foot skate
    at most 1.1 cm/m at every speed (measured 0.14-1.01, the fastest the dash; counting the joints'
    travel 0.08-1.31; the takes' heels land and their balls push off moving, a few frames beyond
    their detected contacts: pinned from where they reach the ground to where they leave it); a
    planted foot does not twist: the ankle-to-ball line turns less than 1.5 degrees a frame (95th
    percentile) while the ball is down."""
    from dataclasses import replace

    from infuse.contacts import foot_contacts
    from infuse.metrics import foot_skate
    from infuse.packs import infuse_character
    from infuse.packs.walk_test import forward_speeds

    character = infuse.Character("x", xbot)
    infusion = infuse_character(character, [bandai_masculinity])
    space = next(iter(infusion.spaces.values()))
    speeds = forward_speeds(space)
    rt = Runtime(fps=30)
    names = [rt.add_character(character, name=f"w{k}", mapping=infusion.mapping) for k in range(len(speeds))]
    for name, v in zip(names, speeds):
        rt.activate(name, Locomotion(space, speed=float(v), max_accel=50.0), 0.0)
    rt.run(5.0)
    base = infusion.mapping.indices(character.skeleton)["base"]
    skates, twists = [], []
    for name in names:
        m = rt.motion(name)
        g_rot, g_pos = infuse.motion_fk(m)
        found = foot_contacts(m, infusion.mapping, fk=(g_rot, g_pos))
        cut = replace(found, flags=found.flags[45:], lowest=found.lowest[45:])
        skates.append(foot_skate(g_pos[45:], cut, base).per_metre)
        for k in range(2):
            lever = g_pos[:, found.points[2 * k + 1]] - g_pos[:, found.points[2 * k]]
            turn = np.abs(np.diff(np.degrees(np.unwrap(np.arctan2(lever[:, 0], lever[:, 2])))))
            down = found.flags[1:, 2 * k + 1] & found.flags[:-1, 2 * k + 1]
            twists.append(float(np.percentile(turn[down], 95)) if down.any() else 0.0)
    assert max(skates) <= 1.1, skates
    assert max(twists) < 1.5, twists
