"""The example controller package (examples/example_controller) is installed, listed and runs in the runtime."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.cli import main as cli_main
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.runtime import Clip, Runtime, controller, controller_components

from corpus_data import corpus_file

CHARACTERS = ("runxaway-models/Xbot.glb",
              "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh")
FPS = 30


def test_listed_by_infuse_plugins(capsys):
    assert cli_main(["plugins"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    assert ["shrug", "controller", "infuse-anim-example-controller", "0.1.0", "ok"] in rows
    assert controller_components()["shrug"].from_bml is not None


def test_shrug_curve_rises_holds_and_falls():
    from infuse_example_controller import shrug_curve

    t = np.linspace(-0.5, 1.5, 401)
    s = shrug_curve(t, 1.0)
    assert np.all((s >= 0.0) & (s <= 1.0))
    assert np.all(s[(t < 0) | (t > 1)] == 0.0)
    assert np.allclose(s[(t >= 0.25) & (t <= 0.65)], 1.0)
    rising = s[(t >= 0) & (t <= 0.25)]
    assert np.all(np.diff(rising) >= 0.0) and rising[0] == 0.0


def _run(asset, mapping, shrug, seconds=2.0):
    """Global joint positions (F, J, 3) of the character playing its first clip, with ``shrug`` on top."""
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("c", asset), mapping=mapping)
    rt.activate(name, Clip(next(iter(asset.motions.values())), loop=True), 0.0)
    if shrug is not None:
        rt.activate(name, shrug, 0.2)
    rt.run(seconds)
    motion = rt.motion(name)
    return motion_fk(motion)[1], motion.skeleton.names


def _shoulder_heights(path, amount, duration_s=1.2):
    """(F, 2) height the shrug adds to the left and right shoulder joints, metres, over its base clip."""
    asset = infuse.load(path)
    mapping = map_skeleton(asset)
    with_shrug, names = _run(asset, mapping, controller("shrug", amount=amount, duration_s=duration_s))
    without, _ = _run(asset, mapping, None)
    joints = [names.index(mapping.joints[n]) for n in ("l_shoulder", "r_shoulder")]
    clavicles = [names.index(mapping.joints.get(f"{s}_sternoclavicular") or mapping.joints[f"{s}_acromioclavicular"])
                 for s in "lr"]
    lengths = np.linalg.norm(without[0, joints] - without[0, clavicles], axis=-1)
    return with_shrug[:, joints, 1] - without[:, joints, 1], lengths


@pytest.mark.parametrize("rel", CHARACTERS)
def test_shoulders_rise_and_return_on_any_character(rel):
    from infuse_example_controller.controller import LIFT_DEG

    rise, clavicle_lengths = _shoulder_heights(corpus_file(rel), 1.0)
    top = int(round((0.2 + 0.45 * 1.2) * FPS))  # in the hold
    # Each shoulder swings up on its clavicle: about length x sin(lift) above where the clip puts it.
    expected = clavicle_lengths * np.sin(np.radians(LIFT_DEG))
    assert np.all(rise[top] > 0.005), rise[top]
    assert np.allclose(rise[top], expected, rtol=0.3), (rise[top], expected)
    assert np.abs(rise[:int(0.2 * FPS)]).max() < 1e-9                     # nothing before the start
    assert np.abs(rise[int(1.45 * FPS):]).max() < 1e-9                    # back at rest after the end


def test_amount_scales_the_shrug():
    path = corpus_file(CHARACTERS[0])
    full, _ = _shoulder_heights(path, 1.0)
    half, _ = _shoulder_heights(path, 0.5)
    top = int(round((0.2 + 0.45 * 1.2) * FPS))
    assert 0.4 < half[top, 0] / full[top, 0] < 0.6


def test_bad_settings_are_usage_errors():
    with pytest.raises(infuse.UsageError):
        controller("shrug", amount=2.0)
    with pytest.raises(infuse.UsageError):
        controller("shrug", duration_s=0.0)
