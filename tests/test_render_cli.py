"""``infuse render`` on the command line: outputs, options and one-line errors with exit codes."""
from __future__ import annotations

import shutil

import numpy as np
import pytest
from PIL import Image

from infuse.cli import main

# A small BVH written here: hips, a spine with a head, two legs; 20 frames walking forward (+Z) in cm.
HIERARCHY = """HIERARCHY
ROOT Hips
{
  OFFSET 0 95 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 30 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head
    {
      OFFSET 0 35 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 20 0
      }
    }
  }
  JOINT LeftUpLeg
  {
    OFFSET 10 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -45 0
      }
    }
  }
  JOINT RightUpLeg
  {
    OFFSET -10 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT RightLeg
    {
      OFFSET 0 -45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -45 0
      }
    }
  }
}
"""


@pytest.fixture(scope="module")
def bvh(tmp_path_factory):
    frames = 20
    t = np.arange(frames) / 20.0
    swing = 30 * np.sin(2 * np.pi * t)
    rows = []
    for k in range(frames):
        values = [0, 95, 100 * t[k], 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -swing[k], 0, 0, 0, 0, 0, swing[k], 0, 0, 0, 0]
        rows.append(" ".join(f"{v:.4f}" for v in values))
    path = tmp_path_factory.mktemp("bvh") / "walk.bvh"
    path.write_text(HIERARCHY + f"MOTION\nFrames: {frames}\nFrame Time: 0.05\n" + "\n".join(rows) + "\n")
    return path


def run(capsys, *argv):
    code = main(["render", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def test_png_gif_and_strip(tmp_path, capsys, bvh):
    code, out, _ = run(capsys, bvh, "-o", tmp_path / "a.png", "--size", "200x300", "--names", "--frame", "5")
    assert code == 0 and "wrote" in out
    assert Image.open(tmp_path / "a.png").size == (200, 300)
    code, _, err = run(capsys, bvh, "-o", tmp_path / "a.gif", "--size", "160x120", "--fps", "10", "--progress")
    img = Image.open(tmp_path / "a.gif")
    assert code == 0 and img.size == (160, 120) and img.n_frames == 10  # 0.95 s at 10 fps
    assert "10/10 left" in err and "frames/s" in err  # the progress bar, asked for although stderr is not a terminal
    code, _, _ = run(capsys, bvh, "-o", tmp_path / "s.png", "--strip", "4", "--size", "100x150", "--view", "side")
    assert code == 0 and Image.open(tmp_path / "s.png").size[0] == 400


def test_side_by_side_files(tmp_path, capsys, bvh):
    code, _, _ = run(capsys, bvh, bvh, "-o", tmp_path / "two.png", "--size", "400x200", "--highlight", "Head")
    img = np.asarray(Image.open(tmp_path / "two.png")).astype(int)
    assert code == 0 and img.shape[:2] == (200, 400)
    # both halves hold a figure
    background = img[2, 2]
    for half in (img[:, :200], img[:, 200:]):
        assert (np.abs(half - background).sum(axis=-1) > 80).sum() > 200


@pytest.mark.parametrize("argv, message", [
    (["-o", "out.jpg"], "use .png, .gif or .mp4"),
    (["-o", "out"], "use .png, .gif or .mp4"),
    (["-o", "out.gif", "--frame", "2"], "--frame"),
    (["-o", "out.gif", "--strip", "3"], "--strip"),
    (["-o", "out.png", "--size", "big"], "WIDTHxHEIGHT"),
    (["-o", "out.png", "--size", "4x4"], "between 16"),
    (["-o", "out.png", "--frame", "99"], "out of range"),
    (["-o", "out.png", "--frame", "1", "--start", "0.2"], "exclude"),
    (["-o", "out.png", "--clip", "nope"], "no such clip"),
    (["-o", "out.png", "--highlight", "Tail"], "Tail"),
    (["-o", "out.gif", "--start", "5"], "past the end"),
])
def test_usage_errors_exit_2_with_one_line(tmp_path, capsys, bvh, argv, message):
    argv = [a if not a.startswith("out") else str(tmp_path / a) for a in argv]
    code, _, err = run(capsys, bvh, *argv)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written, no temporary file left


def test_missing_input_file_exit_2(tmp_path, capsys):
    code, _, err = run(capsys, tmp_path / "absent.bvh", "-o", tmp_path / "x.png")
    assert code == 2 and "absent.bvh" in err and len(err.strip().splitlines()) == 1


def test_mp4_without_ffmpeg_exit_3(tmp_path, capsys, bvh, monkeypatch):
    monkeypatch.setenv("INFUSE_FFMPEG", str(tmp_path / "no-ffmpeg"))
    code, _, err = run(capsys, bvh, "-o", tmp_path / "x.mp4")
    assert code == 3 and "ffmpeg" in err and "install" in err
    assert not (tmp_path / "x.mp4").exists()


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed (scripts/setup.sh installs it)")
def test_mp4(tmp_path, capsys, bvh):
    code, _, _ = run(capsys, bvh, "-o", tmp_path / "x.mp4", "--size", "160x120", "--perspective", "--follow")
    assert code == 0 and (tmp_path / "x.mp4").stat().st_size > 1000
    assert (tmp_path / "x.mp4").read_bytes()[4:8] == b"ftyp"


def test_canonical_names_and_low_confidence_rings(tmp_path, capsys, bvh, monkeypatch):
    from infuse.mapping import Mapping
    from infuse.render import command

    def fake_map(asset, mapper=None, saved_map=None):
        joints = {"base": "Hips", "skullbase": "Head", "l_hip": "LeftUpLeg", "r_hip": "RightUpLeg"}
        return Mapping.build(asset.skeleton, joints, {"l_hip": 0.2, "base": 0.9, "skullbase": 0.9, "r_hip": 0.9})

    seen = {}
    real_render = command.render

    def spy(figures, out, **kw):
        seen["figure"] = figures[0]
        return real_render(figures, out, **kw)

    monkeypatch.setattr(command, "map_skeleton", fake_map)
    monkeypatch.setattr(command, "render", spy)
    code, _, _ = run(capsys, bvh, "-o", tmp_path / "c.png", "--canonical", "--size", "200x300")
    fig = seen["figure"]
    sk = fig.skeleton
    assert code == 0
    assert fig.names[sk.index["Head"]] == "skullbase" and fig.names[sk.index["LeftUpLeg"]] == "l_hip"
    assert list(sk.names[i] for i in fig.highlight.nonzero()[0]) == ["LeftUpLeg"]
    # sides come from the mapping: the left leg and its child are left, the head centre
    assert fig.sides[sk.index["LeftLeg"]] == 1 and fig.sides[sk.index["RightLeg"]] == -1 and fig.sides[sk.index["Head"]] == 0


def test_canonical_without_a_mapper_is_a_usage_error(tmp_path, capsys, bvh, monkeypatch):
    from infuse import registry

    installed = registry.table
    monkeypatch.setattr(registry, "table", lambda kind: {} if kind == "mapper" else installed(kind))
    code, _, err = run(capsys, bvh, "-o", tmp_path / "c.png", "--canonical")
    assert code == 2 and "mapper" in err and not (tmp_path / "c.png").exists()
