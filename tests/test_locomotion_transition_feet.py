"""The feet of played transition clips do not slide: SmartBody's FemaleLocomotion set on Brad, whose
takes swivel and drag their feet on the floor (lifted while they do, :mod:`infuse_locomotion.swivels`),
measured on the output with FK and the project's foot skate (:func:`infuse.metrics.foot_skate`, split
by the parts of :func:`infuse.packs.walk_test.walk_parts`)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import infuse
from infuse.contacts import foot_contacts
from infuse.metrics import foot_skate
from infuse.packs.walk_test import PARTS, walk_parts
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file, require_corpus
from pack_support import smartbody_space

infuse_locomotion = pytest.importorskip("infuse_locomotion")
transitions = infuse_locomotion.transitions
FPS = 30


@pytest.fixture(scope="module")
def brad():
    require_corpus()
    return infuse.load(corpus_file("smartbody/ChrBrad/ChrBrad.sk"))


@pytest.fixture(scope="module")
def female_space(brad, tmp_path_factory):
    """SmartBody's FemaleLocomotion set imported, built and infused onto Brad."""
    return smartbody_space(brad, "FemaleLocomotion", tmp_path_factory.mktemp("packs"))


@pytest.fixture(scope="module")
def walks(brad, female_space):
    """Walks 4 m away at -90 and 135 degrees (a turn on the spot played, then a start clip or the
    cycles, then the stop clip): for each, foot skate (cm) on the spot and in the start
    (:func:`~infuse.packs.walk_test.walk_parts`), and from where the stop clip begins to the end."""
    begins: dict[int, tuple[float, float]] = {}
    original = transitions.stop_placement

    def record(clip, fps, x, z, target):
        begins[len(begins)] = (float(x), float(z))
        return original(clip, fps, x, z, target)

    mp = pytest.MonkeyPatch()
    mp.setattr(transitions, "stop_placement", record)
    try:
        rt = Runtime(fps=FPS)
        names = {}
        for angle in (-90.0, 135.0):
            target = (4.0 * math.sin(math.radians(angle)), 4.0 * math.cos(math.radians(angle)))
            names[angle] = rt.add_character(infuse.Character(f"b{angle:g}", brad))
            rt.activate(names[angle], controller("locomotion", pack=female_space, speed=0.54, target=target), 0.0)
        rt.run(12.0)
    finally:
        mp.undo()
    assert len(begins) == 2  # both walks end with the stop clip
    out = {}
    for angle, name in names.items():
        m, rig = rt.motion(name), rt.rig(name)
        g_rot, g_pos = infuse.motion_fk(m)
        found = foot_contacts(m, rig.mapping, fk=(g_rot, g_pos))
        base = rig.joint("base")
        ground = g_pos[:, base][:, [0, 2]]
        parts = walk_parts(ground, 0.54)[1:]
        # The stop clip begins with its pelvis on the point recorded (one of the two, the nearer).
        near = min(np.linalg.norm(ground - np.array(p), axis=-1).min() for p in begins.values())
        first = min(int(np.argmin(np.linalg.norm(ground - np.array(p), axis=-1))) for p in begins.values()
                    if np.linalg.norm(ground - np.array(p), axis=-1).min() == near)
        assert near < 0.01
        stop = np.arange(len(ground) - 1) >= first
        skate = {part: 100.0 * foot_skate(g_pos, found, base, steps=parts == k).travel for k, part in enumerate(PARTS)}
        skate["stop clip"] = 100.0 * foot_skate(g_pos, found, base, steps=stop).travel
        out[angle] = skate
    return out


@pytest.mark.parametrize("angle", [-90.0, 135.0])
def test_turns_and_starts_played_keep_their_feet_still(walks, angle):
    """On the spot (Turn90Rt01, Turn180Lf01) and in the start (the turn's last steps, the start clip
    Idle01_ToWalk01 or the cycles) at most 1 cm of foot skate each (1.1 / 4.4 cm at -90 degrees and
    3.2 / 1.3 at 135 while a lifted foot's contacts were let go as it began to rise and taken again
    only once it was down: the take's slow turns and drags went on a few millimetres up)."""
    assert walks[angle]["on the spot"] < 1.0
    assert walks[angle]["start"] < 1.0


@pytest.mark.parametrize("angle", [-90.0, 135.0])
def test_the_stop_clip_keeps_its_feet_still(walks, angle):
    """From where Walk01_ToIdle01 begins to the end of the walk (the clip, its fade into the idle, the
    idle) at most 1 cm of foot skate (3.4 cm before)."""
    assert walks[angle]["stop clip"] < 1.0


@pytest.fixture(scope="module")
def male_space(brad, tmp_path_factory):
    """SmartBody's MaleLocomotion set (turns on the spot and a stop, no start) on Brad."""
    return smartbody_space(brad, "MaleLocomotion", tmp_path_factory.mktemp("packs"))


def test_stepping_off_after_a_turn_on_the_spot_keeps_the_feet_still(brad, male_space):
    """4 m at 135 degrees: Turn180Lf01, then the cycles step off from the idle, whose fading share holds
    the right foot down while the blend already swings it. Let go where the share falls under a half,
    10 cm from where the blend has it, the ball went on with the swing 3.4 cm a frame for two frames
    1.5-2.3 cm above the floor (2.3 cm of foot skate in the start); held along the ground until it is
    clear of it, at most 1.2 cm."""
    target = (4.0 * math.sin(math.radians(135.0)), 4.0 * math.cos(math.radians(135.0)))
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("b", brad))
    rt.activate(name, controller("locomotion", pack=male_space, speed=1.3, target=target), 0.0)
    rt.run(12.0)
    m, rig = rt.motion(name), rt.rig(name)
    g_rot, g_pos = infuse.motion_fk(m)
    found = foot_contacts(m, rig.mapping, fk=(g_rot, g_pos))
    base = rig.joint("base")
    parts = walk_parts(g_pos[:, base][:, [0, 2]], 1.3)[1:]
    assert (parts == PARTS.index("on the spot")).sum() > 30  # it turned on the spot first
    assert 100.0 * foot_skate(g_pos, found, base, steps=parts == PARTS.index("start")).travel < 1.2
    assert np.linalg.norm(g_pos[-15:, base][:, [0, 2]].mean(axis=0) - target) < 0.05


def test_short_walks_after_a_turn_on_the_spot_end_with_the_stop_clip(brad, male_space, monkeypatch):
    """Walks 2 m away at 90, 135, 180 and -90 degrees: a turn on the spot leaves 1.7-1.8 m, most of it
    walked speeding up, and the stop (1.08 m from 1.2 m/s) begins at one gait phase; paced for the
    steps it takes as it speeds up, quicker and shorter, each walk ends with the clip, on its target
    (the walk at 135 degrees needed its steps 1.3-1.45 times quicker, and stopped from the cycles)."""
    stopped = []
    original = transitions.stop_placement

    def record(clip, fps, x, z, target):
        stopped.append(tuple(np.round(target, 3)))
        return original(clip, fps, x, z, target)

    monkeypatch.setattr(transitions, "stop_placement", record)
    rt = Runtime(fps=FPS)
    targets = {}
    for angle in (90.0, 135.0, 180.0, -90.0):
        name = rt.add_character(infuse.Character(f"m{angle:g}", brad))
        targets[name] = (2.0 * math.sin(math.radians(angle)), 2.0 * math.cos(math.radians(angle)))
        rt.activate(name, controller("locomotion", pack=male_space, speed=1.3, target=targets[name]), 0.0)
    rt.run(10.0)
    assert len(set(stopped)) == len(targets)
    for name, target in targets.items():
        _, pos = infuse.motion_fk(rt.motion(name))
        assert np.linalg.norm(pos[-15:, rt.rig(name).joint("base")][:, [0, 2]].mean(axis=0) - target) < 0.05
