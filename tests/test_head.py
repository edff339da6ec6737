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
