"""Walks of characters alike (one asset, one pack) have their feet pinned and kept up together, their
frames stacked in one forward kinematics and one leg IK: each character walks as it does when every
walk is pinned on its own. Likewise the work each walk asks for (blend weights, blends of whichever
clips each walk blends, shorter steps) done once for all of them: each walks as when its own is done alone.

Three X Bots made of one asset walk at once (toward a point ahead, to one behind them, turning on the
spot first, and sideways), frame by frame as a live scene evaluates them and in blocks of 7 frames,
stacked and each on its own; compared by forward kinematics on every frame of the written motions.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

import infuse
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.packs import build_pack, import_smartbody, infuse_character
from infuse.runtime import Runtime, controller as runtime_controller
from infuse.scene import Scene
from infuse_locomotion import Locomotion, controller

from corpus_data import corpus_file

FPS = 30.0
SECONDS = 2.5
#: Where each walker stands and where it walks to from there (x, z metres).
WALKS = {"a": ((0.0, 0.0), (0.4, 2.0)), "b": ((3.0, 0.0), (-0.3, -1.5)), "c": ((-3.0, 1.0), (1.5, 0.5))}


@pytest.fixture(scope="module")
def xbot():
    asset = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    return infuse.Character("Xbot", asset, map_skeleton(asset))


def walked(character, block: int, stacked: list) -> Scene:
    """The walkers of :data:`WALKS` (made of one ``character``) after :data:`SECONDS` in blocks of
    ``block`` frames; ``stacked`` collects how many walks each pinning stacked."""
    scene = Scene(fps=FPS, quiet=True)
    for name, ((x, z), (dx, dz)) in WALKS.items():
        scene.add_character(character, name, position=(x, 0.0, z), facing=0.0, packs=["locomotion-male"])
        scene.walk_to(name, (x + dx, z + dz))
    pin = Locomotion.__dict__["_pin"]

    def counted(b, runs, *args):
        stacked.append(len(runs))
        return pin.__func__(b, runs, *args)

    Locomotion._pin = staticmethod(counted)
    try:
        for _ in range(int(round(SECONDS * FPS)) // block):
            scene.step(block)
    finally:
        Locomotion._pin = pin
    return scene


@pytest.mark.parametrize("block", [1, 7])
def test_walks_pinned_together_walk_as_each_on_its_own(xbot, block, monkeypatch):
    together: list[int] = []
    stacked = walked(xbot, block, together)
    assert max(together) == len(WALKS)  # the three walks were pinned in one stack
    apart: list[int] = []
    monkeypatch.setattr(controller, "_stack_key", lambda b: (object(),))  # every walk a stack of its own
    alone = walked(xbot, block, apart)
    assert max(apart) == 1 and len(apart) == len(WALKS) * len(together)
    for name, (_, (dx, dz)) in WALKS.items():
        a, b = motion_fk(stacked.motion(name))[1], motion_fk(alone.motion(name))[1]
        assert a.shape == b.shape
        assert np.abs(a - b).max() < 1e-9
        # It walked: its hips travelled most of the way to where it was sent.
        assert np.hypot(*(a[-1, 0, [0, 2]] - a[0, 0, [0, 2]])) > 0.5 * np.hypot(dx, dz)


@pytest.mark.parametrize("block", [1, 7])
def test_walks_blended_together_walk_as_each_on_its_own(xbot, block, monkeypatch):
    blends: list[tuple[int, int]] = []  # each blend's frames, and how many clip orders its frames sum in
    blend = Locomotion.__dict__["_blend"]

    def counted(b, w, orders, *args):
        blends.append((len(orders), len(np.unique(orders, axis=0))))
        return blend.__func__(b, w, orders, *args)

    monkeypatch.setattr(Locomotion, "_blend", staticmethod(counted))
    together = walked(xbot, block, [])
    # Blends of several walks summing their clips in other orders were evaluated at once.
    assert max(orders for _, orders in blends) > 1 and max(frames for frames, _ in blends) > block
    blends.clear()
    ask = controller.Ask
    monkeypatch.setattr(controller, "Ask", lambda work, key, shared, rows, walk=(): ask(work, (object(),), shared, rows, walk))  # each alone
    alone = walked(xbot, block, [])
    assert max(frames for frames, _ in blends) <= block
    for name in WALKS:
        a, b = motion_fk(together.motion(name))[1], motion_fk(alone.motion(name))[1]
        assert a.shape == b.shape
        assert np.abs(a - b).max() < 1e-9


@pytest.mark.parametrize("frames", [1, 4])
def test_the_clocks_of_walks_together_tick_as_each_alone(frames):
    """The gait's clocks of walks evaluated together (walking, standing after a stop, stepping into a stop
    and landing or reaching where it holds, turning on the spot, one stopping inside the block) give each
    walk's phase, steps, strides and idle shares and carry its state as its clock alone does, to the bit."""
    rng = np.random.default_rng(7)
    dt, walks = 1.0 / 30.0, 24
    states, slow, stopping, spinning = [], np.empty((walks, frames)), np.zeros((walks, frames), bool), np.zeros((walks, frames), bool)
    for k in range(walks):
        kind = k % 6
        st = controller.LocomotionState(phase=float(rng.uniform(0.0, 1.0)), idle_frames_left=float(rng.integers(0, 16)))
        slow[k] = rng.uniform(0.3, 1.0, frames)
        if kind == 1:  # standing after its stop
            st.settled, slow[k] = True, 0.0
        elif kind in (2, 3):  # stepping into a stop: landing by the body, or holding where it goes to
            st.settled, st.landings, st.floor, st.stop_age = False, int(rng.integers(-1, 3)), 0.8, float(rng.uniform(0.0, 0.3))
            st.phase = float(rng.choice([0.49, 0.99, 0.2]))
            st.to_go = float(rng.uniform(0.0, 0.05)) if kind == 3 else -1.0
            slow[k] = rng.uniform(0.0, 0.009, frames)
            stopping[k] = True
        elif kind == 4:  # turning on the spot
            st.settled, slow[k] = bool(rng.integers(0, 2)), 0.0
            spinning[k] = True
        elif kind == 5 and frames > 1:  # walking, then stopping inside the block: a clock of its own
            stopping[k, frames // 2:] = True
        states.append(st)
    period = rng.uniform(0.9, 1.2, (walks, frames))
    asked: list[int] = []

    def settle_at(i):
        asked.append(i)
        return np.array([0.05, 0.04]) + 1e-3 * (i % 3)

    alone_states = copy.deepcopy(states)
    together = controller._clocks(states, slow.ravel(), stopping.ravel(), spinning.ravel(), period.ravel(), dt, True,
                                  settle_at, [None] * walks, [frames] * walks)
    for k, st in enumerate(alone_states):
        a = k * frames
        alone = controller._clock(st, slow[k], stopping[k], spinning[k], period[k], dt, True, lambda i, a=a: settle_at(a + i))
        for mine, its in zip(together, alone):
            assert np.array_equal(mine[a:a + frames], its)
        for field in ("phase", "settled", "landings", "to_go", "floor", "stop_age", "idle_frames_left"):
            assert getattr(st, field) == getattr(states[k], field), field
    assert asked and any(st.settled for st in states[2::6] + states[3::6])  # stops landed, some came to hold


def test_walks_starting_apart_and_settling_apart_walk_together_as_each_alone(xbot, monkeypatch):
    """Walks of one binding stacked in blocks of 7 frames, started at other times, one settling into the
    idle while the others still walk (placed with them, the idle faded in on its rows only): each walks as
    when its work is done alone."""
    starts = {"a": (0.0, (0.0, 0.6)), "b": (0.1, (1.0, 1.5)), "c": (0.37, (-0.8, 1.2))}  # start (s), target (x, z) m
    seen = {"fading with others": 0}
    driven = controller._driven

    def counting_driven(*args):
        out = driven(*args)
        fading = out[-1]
        seen["fading with others"] += bool(fading.any() and not fading.all())
        return out

    monkeypatch.setattr(controller, "_driven", counting_driven)

    def scene_of() -> Scene:
        scene = Scene(fps=FPS, quiet=True)
        for k, (name, (at, target)) in enumerate(starts.items()):
            scene.add_character(xbot, name, position=(2.0 * k, 0.0, 0.0), facing=0.0, packs=["locomotion-male"])
            scene.walk_to(name, (2.0 * k + target[0], target[1]), at=at)
        for _ in range(int(round(3.5 * FPS)) // 7):
            scene.step(7)
        return scene

    together = scene_of()
    assert seen["fading with others"]
    ask = controller.Ask
    monkeypatch.setattr(controller, "Ask", lambda work, key, shared, rows, walk=(): ask(work, (object(),), shared, rows, walk))
    alone = scene_of()
    for name in starts:
        a, b = motion_fk(together.motion(name))[1], motion_fk(alone.motion(name))[1]
        assert a.shape == b.shape
        assert np.abs(a - b).max() < 1e-9


@pytest.fixture(scope="module")
def transitions_space(xbot, tmp_path_factory):
    """SmartBody's FemaleLocomotion set (starts, turns on the spot and stops played whole) infused onto X Bot."""
    folder = import_smartbody(corpus_file("smartbody/behaviorsets/FemaleLocomotion"), tmp_path_factory.mktemp("packs") / "female",
                              name="sb-female")
    build_pack(folder)
    return next(iter(infuse_character(xbot, [str(folder)]).spaces.values()))


def test_walks_handing_over_inside_a_block_walk_together_as_each_alone(xbot, transitions_space, monkeypatch):
    """Walks of one binding whose steered frames in a block of 7 are not as many (a start or a turn on the spot
    handing over inside it, a stop taking over, the last strides paced for it): each walks as when its work
    is done alone."""
    counts_seen: list[list[int]] = []
    walked = controller._walked

    def counting(b, dt, times, req, states, walks, begun, counts):
        counts_seen.append(list(counts))
        return walked(b, dt, times, req, states, walks, begun, counts)

    monkeypatch.setattr(controller, "_walked", counting)

    def run() -> list[np.ndarray]:
        rt = Runtime(fps=FPS, block_frames=7)
        out = []
        for k, (at, target) in enumerate(((0.0, (0.3, 2.5)), (0.2, (-2.0, -1.0)), (0.45, (1.5, 0.5)))):
            name = rt.add_character(infuse.Character(f"x{k}", xbot.asset))
            rt.activate(name, runtime_controller("locomotion", pack=transitions_space, speed=0.6, target=target), at)
            out.append(name)
        rt.run(7.0)
        return [motion_fk(rt.motion(name))[1] for name in out]

    together = run()
    assert any(len(set(c)) > 1 for c in counts_seen)  # stacked walks of unequal lengths
    ask = controller.Ask
    monkeypatch.setattr(controller, "Ask", lambda work, key, shared, rows, walk=(): ask(work, (object(),), shared, rows, walk))
    for a, b, target in zip(together, run(), ((0.3, 2.5), (-2.0, -1.0), (1.5, 0.5))):
        assert a.shape == b.shape
        assert np.abs(a - b).max() < 1e-9
        # It walked: its hips ended near where it was sent.
        assert np.hypot(*(a[-1, 0, [0, 2]] - a[0, 0, [0, 2]] - target)) < 0.25 * np.hypot(*target)


def test_work_kept_by_blend_weights_is_the_work_done_afresh(xbot, monkeypatch):
    """What the walks work out from blend weights alone, kept on the binding by those weights (a few pieces
    at most here, the oldest going as one comes), read only: the walks are the same to the bit as with all of
    it worked out afresh at each block."""
    kept: list = []
    keep = controller._kept

    def watched(b, key, make):
        if b not in kept:  # what earlier walks of this binding left is let go first
            b.by_weights.clear()
            kept.append(b)
        return keep(b, key, make)

    monkeypatch.setattr(controller, "_WEIGHTS_KEPT", 5)
    monkeypatch.setattr(controller, "_kept", watched)
    keeping = walked(xbot, 1, [])
    binding = kept[0]
    assert 0 < len(binding.by_weights) <= 5
    pieces = [x for known in binding.by_weights.values() for x in known if isinstance(x, np.ndarray)]
    assert pieces and not any(x.flags.writeable for x in pieces)
    monkeypatch.setattr(controller, "_kept", lambda b, key, make: make())
    afresh = walked(xbot, 1, [])
    for name in WALKS:
        assert np.array_equal(motion_fk(keeping.motion(name))[1], motion_fk(afresh.motion(name))[1])
