"""The gestures pack's authoring (tools/motion_authoring/gestures.py), measured by FK on its clips: the wrist
reaches each key pose at its phase, the hand points as the key says, and the clip starts and ends at rest."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tools.motion_authoring.body import Body  # noqa: E402
from tools.motion_authoring.gait import gait_motion  # noqa: E402
from tools.motion_authoring.gestures import PALMS, SPECS, gesture_motion  # noqa: E402
from tools.motion_authoring.make_packs import locomotion_clips  # noqa: E402


@pytest.fixture(scope="module")
def body_and_stand():
    body = Body.canonical()
    stand, _ = gait_motion(body, locomotion_clips("male")["idle"][0], "stand")
    return body, stand


@pytest.mark.parametrize("spec", [s for s in SPECS if s.oscillation is None], ids=lambda s: s.name)
@pytest.mark.parametrize("hand", ["left", "right"])
def test_the_wrist_reaches_each_key_at_its_phase(body_and_stand, spec, hand):
    body, stand = body_and_stand
    assert hand in spec.hands
    motion = gesture_motion(body, stand, spec, hand, "probe")
    g_rot, g_pos = forward_kinematics(body.skeleton, motion.local_rotations, motion.root_translations)
    side = hand[0]
    mirror = np.array([1.0 if side == "l" else -1.0, 1.0, 1.0])
    wrist, shoulder = g_pos[:, body.i(f"{side}_wrist")], g_pos[:, body.i(f"{side}_shoulder")]
    for phase in ("ready", "stroke", "stroke_end"):
        f = int(round(spec.times[phase] * motion.fps))
        key = spec.keys[phase]
        assert np.linalg.norm((wrist[f] - shoulder[f]) - np.asarray(key.wrist) * mirror) < 0.005, (phase, key)
        fingers = quat.rotate(g_rot[f, body.i(f"{side}_wrist")], body.offset(f"{side}_middle1"))
        wanted = np.asarray(PALMS[key.palm][0]) * mirror
        cos = np.dot(fingers, wanted) / np.linalg.norm(fingers) / np.linalg.norm(wanted)
        assert np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) < 5.0, (phase, key.palm)
    # It starts and ends in the standing pose.
    assert np.linalg.norm(wrist[0] - wrist[-1]) < 1e-6
    _, stand_pos = forward_kinematics(body.skeleton, stand.local_rotations[:1], stand.root_translations[:1])
    assert np.linalg.norm(wrist[0] - stand_pos[0, body.i(f"{side}_wrist")]) < 0.005
