"""The example behaviour pack package (examples/example_pack): installed, listed, built from what its
generator makes, infused onto a corpus character, and driving the reach controller."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli import main as cli_main
from infuse.kinematics import motion_fk
from infuse.packs import infuse_character, load_pack
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "example_pack"
FPS = 30


def _generator():
    spec = importlib.util.spec_from_file_location("make_example_pack", EXAMPLE / "make_pack.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def xbot():
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


@pytest.fixture(scope="module")
def infusion(xbot, tmp_path_factory):
    return infuse_character(infuse.Character("xbot", xbot), ["example-wave"], cache=tmp_path_factory.mktemp("cache"))


def test_listed_by_infuse_plugins_and_infuse_packs(capsys):
    assert cli_main(["plugins"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    assert ["example-wave", "behaviour-pack", "infuse-anim-example-pack", "0.1.0", "ok"] in rows
    assert cli_main(["packs", "--json"]) == 0
    (entry,) = [p for p in json.loads(capsys.readouterr().out) if p["name"] == "example-wave"]
    assert entry["kind"] == "reach" and entry["clips"] == 5 and entry["built"] is True
    assert entry["blend_spaces"] == {"right": 3}


def test_committed_clips_are_what_the_generator_makes():
    gen = _generator()
    pack = load_pack("example-wave")
    sk = gen.skeleton()
    assert sorted(pack.skeleton.names) == sorted(sk.names) and len(sk.names) == 29  # BVH lists joints depth first
    for name, (azimuth, elevation) in gen.POSES.items():
        made = gen.wave_clip(sk, azimuth, elevation, name)
        stored = infuse.load(pack.manifest.clip(name).file)
        stored = next(iter(stored.motions.values()))
        order = [stored.skeleton.names.index(n) for n in sk.names]
        _, a = motion_fk(made)
        _, b = motion_fk(stored)
        assert a.shape == b.shape and np.abs(a - b[:, order]).max() < 1e-6, name


def test_built_analysis_measures_the_waves():
    pack = load_pack("example-wave")
    assert pack.built and pack.analysis["report"] == []
    head_height = pack.skeleton.rest_global_positions[pack.skeleton.index["skullbase"]][1]
    for clip in pack.analysis["clips"]:
        p = clip["parameters"]
        assert clip["hand"] == "right" and clip["stroke"] == pytest.approx(0.6, abs=0.05)  # the hand arrives
        assert p["x"] < -0.1 and p["y"] > head_height  # to the character's right, above the head


def test_infused_onto_a_corpus_character(xbot, infusion, tmp_path):
    space = infusion.spaces["example-wave"]
    assert space.kind == "reach" and len(space.clips) == 5
    tessellation = space.tessellations["right"]
    assert tessellation.dimension == 3 and len(tessellation.simplices) >= 2
    # An example's own parameters give it all the weight.
    clip = next(iter(space.clips.values()))
    indices, weights = space.weights("right", [clip.parameters[c] for c in space.coordinates])
    assert np.isclose(weights.sum(), 1.0) and weights.max() == pytest.approx(1.0)
    again = infuse_character(infuse.Character("xbot", xbot), ["example-wave"], cache=infusion.cache_file.parent)
    assert again.cached


def test_the_reach_controller_waves_at_a_target_with_the_pack(xbot, infusion):
    space = infusion.spaces["example-wave"]
    points = np.array([[c.parameters[k] for k in "xyz"] for c in space.clips.values()])
    target = points.mean(axis=0)  # inside the examples' hull; the character stands at the origin
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("xbot", xbot))
    start = 0.5
    rt.activate(name, controller("reach", target=tuple(target), hand="right", pack=space, hold_s=1.0), start)
    rt.run(2.5)
    motion = rt.motion(name)
    _, positions = motion_fk(motion)
    wrist = positions[:, motion.skeleton.names.index(infusion.mapping.joints["r_wrist"])]
    stroke = start + np.mean([c.stroke for c in space.clips.values()])
    error = np.linalg.norm(wrist - target, axis=1)
    assert error[int(round(stroke * FPS))] < 0.01
    assert error[0] > 0.3  # it started far away, hanging at the side
