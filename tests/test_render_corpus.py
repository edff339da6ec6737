"""Renders of real corpus files: a Bandai BVH walk, a SmartBody walk, Xbot.glb, one file of every convention."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import infuse
from corpus_data import REPO, corpus_file, labels, require_corpus
from infuse.render import Camera, Figure, Renderer, render

BANDAI_WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
SMARTBODY_WALK = "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"
XBOT = "runxaway-models/Xbot.glb"


def figure_pixels_at(image: Image.Image, pixels: np.ndarray, radius: int = 2) -> np.ndarray:
    """(N,) whether each pixel position has something drawn (not background) within ``radius``."""
    a = np.asarray(image.convert("RGB")).astype(int)
    background = a[a.shape[0] // 2, 2]  # the left edge of the middle row: empty in these renders
    out = []
    for x, y in np.rint(pixels).astype(int):
        patch = a[max(y - radius, 0):y + radius + 1, max(x - radius, 0):x + radius + 1]
        out.append(bool(np.any(np.abs(patch - background).sum(axis=-1) > 60)))
    return np.array(out)


@pytest.fixture(scope="module")
def bandai():
    return infuse.load(corpus_file(BANDAI_WALK))


def test_bandai_walk_gif_follows_the_walker(tmp_path, bandai):
    motion = next(iter(bandai.motions.values()))
    fig = Figure.from_motion(motion)
    # the file's root joint stays at the origin while the hips walk 8 m: that link is not drawn
    assert fig.root == bandai.skeleton.index["Hips"] and not fig.visible[0]
    out = render([fig], tmp_path / "walk.gif", end=2.0, fps=10, size=(200, 200))
    img = Image.open(out)
    assert img.n_frames == 21 and img.size == (200, 200)
    renderer = Renderer([fig], np.array([0.0, 3.0, 6.0]), size=(200, 200), camera=Camera())
    hips = np.array([renderer.joint_pixels(0, t)[fig.root] for t in range(3)])
    assert np.ptp(hips[:, 0]) < 30  # the camera follows the 8 m walk
    for t in range(3):
        drawn = figure_pixels_at(renderer.image(t), renderer.joint_pixels(0, t)[fig.visible])
        assert drawn.mean() > 0.9


def test_smartbody_walk_strip(tmp_path):
    asset = infuse.load(corpus_file(SMARTBODY_WALK))
    motion = next(iter(asset.motions.values()))
    out = render([Figure.from_motion(motion)], tmp_path / "strip.png", strip=4, size=(150, 220))
    img = Image.open(out)
    assert img.size == (600, 220)  # four tiles in a row, no title row
    tiles = np.asarray(img.convert("RGB"))[-220:].reshape(220, 4, 150, 3)
    assert not np.array_equal(tiles[:, 0], tiles[:, 3])  # the walker moved


def test_xbot_front_view_faces_the_camera():
    asset = infuse.load(corpus_file(XBOT))
    sk = asset.skeleton
    fig = Figure.from_skeleton(sk)
    renderer = Renderer([fig], [0.0], size=(400, 500), camera=Camera(view="front"))
    pix = renderer.joint_pixels(0, 0)
    left, right = pix[sk.index["mixamorig:LeftHand"]], pix[sk.index["mixamorig:RightHand"]]
    head, hips = pix[sk.index["mixamorig:Head"]], pix[sk.index["mixamorig:Hips"]]
    assert left[0] > 200 > right[0] and head[1] < hips[1]
    assert fig.sides[sk.index["mixamorig:LeftHand"]] == 1 and fig.sides[sk.index["mixamorig:RightFoot"]] == -1
    assert figure_pixels_at(renderer.image(0), pix[fig.visible]).mean() > 0.95


def _one_per_convention() -> list[str]:
    chosen: dict[tuple, str] = {}
    for doc in labels():
        if doc["meta"].get("plain_python"):
            chosen.setdefault((doc.get("convention"), doc["meta"].get("format")), doc["file"])
    return sorted(chosen.values())


def test_one_file_of_every_convention_renders_inside_the_frame():
    require_corpus()
    files = _one_per_convention()
    assert len(files) > 20
    readable = {ext for r in infuse.registry.readers().values() for ext in r.extensions}
    rendered = 0
    for rel in files:
        path = corpus_file(rel)
        if path.suffix.lower() not in readable and not path.name.lower().endswith(".skeleton.xml"):
            continue  # a format whose reader is not installed here (e.g. Acclaim)
        asset = infuse.load(path)
        motion = next(iter(asset.motions.values()), None)
        fig = Figure.from_motion(motion) if motion is not None else Figure.from_skeleton(asset.skeleton)
        renderer = Renderer([fig], [fig.duration / 2], size=(160, 200))
        pix = renderer.joint_pixels(0, 0)[fig.visible]
        assert np.all((pix >= 0) & (pix < [160, 200])), rel
        assert figure_pixels_at(renderer.image(0), pix, radius=1).mean() > 0.8, rel
        rendered += 1
    assert rendered >= len(files) - 3


def test_demo_writes_a_preview_and_a_walk(tmp_path, monkeypatch, capsys):
    require_corpus()
    spec = importlib.util.spec_from_file_location("infuse_demo", REPO / "examples" / "demo.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    monkeypatch.setattr(demo, "OUT", tmp_path)
    assert demo.main() == 0
    out = capsys.readouterr().out
    for name in ("character.png", "walk.gif", "walk_strip.png"):
        assert (tmp_path / name).stat().st_size > 1000 and str(tmp_path / name) in out
    assert Image.open(tmp_path / "walk.gif").n_frames > 10
    assert "joints" in out and Path(out.split("preview:")[1].split()[0]).exists()


def test_demo_without_corpus_exits_2(monkeypatch, capsys):
    spec = importlib.util.spec_from_file_location("infuse_demo_nocorpus", REPO / "examples" / "demo.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    monkeypatch.setenv("INFUSE_CORPUS", str(REPO / "no-such-corpus"))
    assert demo.main() == 2
    assert "INFUSE_CORPUS" in capsys.readouterr().err


def test_bandai_sides_from_the_first_frame_match_the_names(bandai):
    """Bandai's rest pose lies along X, so the sides come from the first frame; its names say the truth."""
    fig = Figure.from_motion(next(iter(bandai.motions.values())))
    names = bandai.skeleton.names
    for suffix, side in (("_L", 1), ("_R", -1)):
        limbs = [i for i, n in enumerate(names) if n.endswith(suffix) and not n.startswith("Shoulder")]
        assert len(limbs) >= 7 and all(fig.sides[i] == side for i in limbs), suffix
