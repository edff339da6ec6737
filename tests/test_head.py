"""Head movements measured on the output motion: the nod curve against its formula, axes, neck split."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.runtime import Runtime
from infuse.runtime.swing import swing_angles
from infuse_head import HeadMovement

from runtime_characters import corpus_character, synthetic_character


def head_turn_deg(rt, name):
    """(F, 3) heading, pitch, roll in degrees of the head's aligned frame relative to the chest's (spine3)."""
    rig = rt.rig(name)
    g_rot, _ = infuse.motion_fk(rt.motion(name))
    chest, head = rig.joint("spine3"), rig.joint("skullbase")
    w_chest = quat.multiply(g_rot[:, chest], rig.aligned[chest])
    w_head = quat.multiply(g_rot[:, head], rig.aligned[head])
    return np.degrees(np.stack(swing_angles(quat.multiply(quat.conjugate(w_chest), w_head)), axis=-1))


@pytest.mark.parametrize("key", ["utah", "xbot", "rpm"])
def test_nod_angle_follows_the_formula(key):
    rt = Runtime(fps=30)
    rt.add_character(corpus_character(key), name=key)
    amount, repeats, velocity = 0.6, 2.0, 1.25
    activity = rt.activate(key, HeadMovement("NOD", amount, repeats, velocity), 0.5)
    assert activity.end_s == pytest.approx(0.5 + repeats / velocity)
    rt.run(2.5)
    t = np.arange(75) / 30.0 - 0.5
    duration = repeats / velocity
    expected = np.where((t >= 0) & (t <= duration), -amount * 30.0 * np.sin(2 * np.pi * repeats * t / duration), 0.0)
    turn = head_turn_deg(rt, key)
    assert np.abs(turn[:, 1] - expected).max() < 1e-6
    assert np.abs(turn[:, [0, 2]]).max() < 1e-6
    assert turn[20, 1] < -5  # a nod goes down first
    neck = [rt.rig(key).joint(n) for n in ("spine4", "spine5", "skullbase") if rt.rig(key).joint(n) is not None]
    local = rt.motion(key).local_rotations[:, neck]
    rest = rt.rig(key).skeleton.rest_rotations[neck]
    shares = np.degrees(quat.angle_between(local[23], np.broadcast_to(rest, local[23].shape)))
    assert np.allclose(shares, shares[0]) and shares[0] * len(neck) == pytest.approx(abs(expected[23]))


@pytest.mark.parametrize("lexeme,axis,peak", [("SHAKE", 0, 45.0), ("TOSS", 2, 30.0), ("TILT", 2, 30.0)])
def test_shake_toss_and_tilt_use_their_axes(lexeme, axis, peak):
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"))
    rt.activate("a", HeadMovement(lexeme, amount=1.0), 0.0)
    rt.run(1.5)
    turn = head_turn_deg(rt, "a")
    assert np.abs(turn[:, axis]).max() == pytest.approx(peak, abs=0.5)
    others = [k for k in range(3) if k != axis]
    assert np.abs(turn[:, others]).max() < 1e-6
    assert np.abs(turn[30:]).max() < 1e-6  # over after one second


def test_an_odd_repeat_count_fades_out():
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("a"))
    rt.activate("a", HeadMovement("NOD", 1.0, repeats=1.25), 0.0)
    rt.run(2.0)
    pitch = head_turn_deg(rt, "a")[:, 1]
    assert abs(pitch[37]) < 1.0 and np.abs(np.diff(pitch)).max() < 8.0  # no jump at the end (1.25 s)


MOVEMENTS = (("NOD", dict(amount=0.6, repeats=2.0, velocity_hz=1.25), {}), ("SHAKE", dict(repeats=1.25), {}),
             ("TOSS", dict(amount=-0.4), {"mode": "override"}), ("TILT", {}, {}), ("ORIENT", dict(direction="UP_LEFT"), {}),
             ("SPIN", dict(amount=0.3, repeats=0.75, velocity_hz=2.0), {"duration_s": 0.3}))


def test_movements_on_several_characters_play_as_each_alone():
    """Head movements of many characters evaluated together (in blocks of one frame, as a live scene does,
    and of several) move each character exactly as the same movement alone: oscillations that fade out or
    not, cut short, overriding, tilts and orientations, two at once on one character."""
    def play(chosen, block, overlap=False):
        rt = Runtime(fps=30, block_frames=block)
        for k, (lexeme, settings, options) in chosen:
            name = rt.add_character(synthetic_character(f"c{k}"), position=(k, 0.0, 0.0))
            rt.activate(name, HeadMovement(lexeme, **settings), 0.1 * k, **options)
        if overlap:  # a second movement on the first character, overlapping the first
            rt.activate("c0", HeadMovement("SHAKE", 0.3), 0.5)
        for _ in range(int(2.4 * 30) // block):
            rt.step(block)
        return rt

    for block in (1, 7):
        together = play(list(enumerate(MOVEMENTS)), block, overlap=True)
        for k in range(1, len(MOVEMENTS)):
            alone = play([(k, MOVEMENTS[k])], block)
            assert np.array_equal(together.motion(f"c{k}").local_rotations, alone.motion(f"c{k}").local_rotations)
        without_overlap = play(list(enumerate(MOVEMENTS))[1:], block)
        for k in range(1, len(MOVEMENTS)):
            assert np.array_equal(without_overlap.motion(f"c{k}").local_rotations, together.motion(f"c{k}").local_rotations)


def test_a_character_binds_each_angle_once():
    """Head movements bind to their character's neck once per angle they turn (a nod and a wiggle share the
    pitch binding, read-only); another angle, or the same character in another runtime, is bound anew, and
    every binding is the one worked out alone."""
    from infuse_head.controller import AXES, HeadBindings

    runtimes = [Runtime(fps=30), Runtime(fps=30)]
    for rt in runtimes:
        rt.add_character(corpus_character("xbot"), name="x")
    rig, other = (rt.rig("x") for rt in runtimes)
    nod = HeadMovement("NOD").bind(rig, print)
    assert HeadMovement("WIGGLE").bind(rig, print) is nod and not nod.axes.flags.writeable
    shake, orient = HeadMovement("SHAKE").bind(rig, print), HeadMovement("ORIENT", direction="UP").bind(rig, print)
    assert shake is not nod and orient.axes is None
    assert HeadMovement("NOD").bind(other, print) is not nod
    assert set(rig.state_of(HeadBindings)) == {AXES["NOD"], AXES["SHAKE"], AXES["ORIENT"]}
    for lexeme, binding in (("NOD", nod), ("SHAKE", shake), ("ORIENT", orient)):
        other.state_of(HeadBindings).clear()
        alone = HeadMovement(lexeme).bind(other, print)
        for field in ("joints", "aligned", "axes"):
            kept, fresh = getattr(binding, field), getattr(alone, field)
            assert (kept is None and fresh is None) or np.array_equal(kept, fresh), (lexeme, field)
