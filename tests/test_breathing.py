"""Breathing measured on the output: its rate, its depth, and a level head."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.runtime import Clip, Runtime
from infuse.runtime.swing import swing_angles
from infuse_breathing import Breathing

from runtime_characters import corpus_character, first_frame, reference_frame


def aligned_pitch_deg(rt, name, joint):
    rig = rt.rig(name)
    g_rot, _ = infuse.motion_fk(rt.motion(name))
    j = rig.joint(joint)
    return np.degrees(swing_angles(quat.multiply(quat.multiply(quat.conjugate(rig.body), g_rot[:, j]), rig.aligned[j]))[1])


@pytest.mark.parametrize("key,rate,depth", [("utah", 12.0, 1.0), ("bandai", 20.0, 0.5)])
def test_rate_depth_and_level_head(key, rate, depth):
    rt = Runtime(fps=30)
    character = corpus_character(key)
    rt.add_character(character, name=key)
    if reference_frame(character)[2]:
        rt.activate(key, Clip(first_frame(next(iter(character.asset.motions.values())))), 0.0)
    rt.activate(key, Breathing(rate_bpm=rate, depth=depth), 0.0, blend_in_s=0.0)
    rt.run(60.0)
    chest = aligned_pitch_deg(rt, key, "spine3")
    chest -= chest[0]
    spectrum = np.abs(np.fft.rfft(chest - chest.mean()))
    frequency = np.fft.rfftfreq(len(chest), 1 / 30.0)[np.argmax(spectrum)]
    assert frequency * 60.0 == pytest.approx(rate, abs=60.0 / 60.0)  # the FFT's resolution over 60 s
    spine = sum(v for k, v in {"spine1": 0.5, "spine2": 1.0, "spine3": 2.0}.items() if rt.rig(key).joint(k) is not None)
    assert chest.max() == pytest.approx(depth * spine, rel=0.02)
    head = aligned_pitch_deg(rt, key, "skullbase")
    assert np.ptp(head) < 0.02 * np.ptp(chest)
    rig = rt.rig(key)  # the sternoclavicular joint when mapped, else the acromioclavicular one
    clavicle = rig.joint("l_sternoclavicular") if rig.joint("l_sternoclavicular") is not None else rig.joint("l_acromioclavicular")
    lift = np.degrees(quat.angle_between(rt.motion(key).local_rotations[:, clavicle],
                                         rt.motion(key).local_rotations[0, clavicle]))
    assert lift.max() == pytest.approx(3.0 * depth, rel=0.02)
