"""SmartBody's ``<sbm:noise>`` (the ``noise`` controller): the named joints turn by smooth noise of the size
asked, measured on the written motion against the same scene without it; a later noise replaces the last;
joints the character lacks are said."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.scene import Scene

from corpus_data import require_corpus
from runtime_characters import corpus_character

infuse_noise = pytest.importorskip("infuse_noise")

FPS = 30.0
NOISE = '<act><bml id="{id}"><sbm:noise id="n" joints="{joints}" frequency="{f}" scale="{s}"/></bml></act>'


def test_gradient_noise_is_smooth_bounded_and_zero_on_the_lattice():
    gradients = np.random.default_rng(3).uniform(-1.0, 1.0, (2, 64))
    u = np.linspace(0.0, 40.0, 40 * 200 + 1)[:, None] + np.array([0.0, 0.5])
    n = infuse_noise.gradient_noise(u, gradients)
    assert n.shape == u.shape and np.abs(n).max() <= 1.0
    assert np.abs(n[::200, 0]).max() < 1e-12  # on the lattice points
    assert np.abs(np.diff(n, axis=0)).max() < 0.02  # continuous: a 1/200 step moves it little
    assert np.std(n[:, 0]) > 0.1 and abs(np.corrcoef(n[:, 0], n[:, 1])[0, 1]) < 0.5  # varied, series independent


def _scene(key: str, blocks):
    require_corpus()
    scene = Scene(fps=FPS, tts=None, quiet=True, idle=False)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character(key), "bob")
    for at, text in blocks:
        scene.bml("bob", text, at=at)
    scene.run(8.0)
    return scene, warnings


@pytest.mark.parametrize("key", ["xbot", "utah"])
def test_noise_turns_the_named_joints_smoothly_and_a_later_one_replaces_it(key):
    scene, warnings = _scene(key, [(0.5, NOISE.format(id="a", joints="skullbase", f="1", s="0.1")),
                                   (4.0, NOISE.format(id="b", joints="spine3", f="2", s="0.05"))])
    base, _ = _scene(key, [])
    assert not warnings, [w.description for w in warnings]
    rig = scene.runtime.rig("bob")
    rot, below = scene.motion("bob").local_rotations, base.motion("bob").local_rotations
    turn = {name: np.degrees(quat.angle_between(rot[:, rig.joint(name)], below[:, rig.joint(name)]))
            for name in ("skullbase", "spine3")}
    at = lambda t: int(round(t * FPS))  # noqa: E731
    head, chest = turn["skullbase"], turn["spine3"]
    print(key, f"head up to {head[at(0.8):at(4.0)].max():.1f} deg, chest up to {chest[at(4.3):].max():.1f} deg")
    assert head[:at(0.5)].max() < 1e-6 and chest[:at(4.0)].max() < 1e-6  # nothing before each
    assert 2.0 < head[at(0.8):at(4.0)].max() <= np.degrees(0.1 * np.sqrt(3.0))  # about the size asked
    assert 1.0 < chest[at(4.3):].max() <= np.degrees(0.05 * np.sqrt(3.0))
    assert head[at(4.3):].max() < 1e-6  # replaced: the head is back on the pose below
    assert np.abs(np.diff(head[at(0.8):at(4.0)])).max() < 1.0  # smooth: under a degree a frame


def test_missing_joints_are_said():
    scene, warnings = _scene("xbot", [(0.2, NOISE.format(id="a", joints="skullbase nosuchjoint", f="1", s="0.1")),
                                      (3.0, NOISE.format(id="b", joints="nosuchjoint", f="1", s="0.1"))])
    said = {w.id: w.description for w in warnings}
    assert "nosuchjoint" in said["a:n"] and "the others move" in said["a:n"]
    assert "nosuchjoint" in said["b:n"] and ("b", "n") not in scene.activities


def test_a_gestures_noise_moves_the_joints_it_names_over_its_span():
    """SmartBody's ``<gesture sbm:joint-range sbm:frequency sbm:scale>``: the gesture as without noise, and
    the named joints (here the left arm, which the right-handed gesture leaves alone) turn over its span."""
    gesture = ('<act><bml id="g"><gesture id="x" lexeme="BEAT" mode="RIGHT_HAND"{extra}/></bml></act>')
    noisy, warnings = _scene("xbot", [(0.5, gesture.format(extra=' sbm:joint-range="l_shoulder l_elbow" '
                                                                 'sbm:frequency="1" sbm:scale="0.1"'))])
    plain, _ = _scene("xbot", [(0.5, gesture.format(extra=""))])
    assert not warnings, [w.description for w in warnings]
    rig = noisy.runtime.rig("bob")
    rot, below = noisy.motion("bob").local_rotations, plain.motion("bob").local_rotations
    turn = np.degrees(quat.angle_between(rot[:, rig.joint("l_shoulder")], below[:, rig.joint("l_shoulder")]))
    right = np.degrees(quat.angle_between(rot[:, rig.joint("r_shoulder")], below[:, rig.joint("r_shoulder")]))
    activity = noisy.activities[("g", "x")]
    start, end = int(round(activity.start_s * FPS)), int(round(activity.end_s * FPS))
    assert turn[start:end].max() > 2.0 and turn[:start].max() < 1e-3 and turn[end + 1:].max() < 1e-3
    assert right.max() < 1e-3  # the gesture's own arm as without noise (degrees)
