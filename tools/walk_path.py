"""Render a character walking a path at changing speed (locomotion controller), e.g.::

    python tools/walk_path.py Xbot.glb -o walk_path.png --pack locomotion-female

The speed rises from 0.8 to 2.2 m/s and falls again while the character follows a winding path and
stops at its end; the result is saved as BVH beside the image and drawn with ``infuse render``, the
camera following the walker so the figure stays large.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np

import infuse
from infuse.runtime import Runtime
from infuse_locomotion import Locomotion

PATH = [(0.0, 3.0), (2.5, 6.0), (0.5, 9.5), (3.0, 12.0)]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("character")
    p.add_argument("-o", "--output", required=True, help=".png (a filmstrip), .gif or .mp4")
    p.add_argument("--pack", default="locomotion-male")
    p.add_argument("--seconds", type=float, default=12.0)
    args = p.parse_args()
    rt = Runtime(fps=30)
    c = rt.add_character(infuse.Character("walker", infuse.load(args.character)))
    speed = lambda t: 0.8 + 1.4 * np.sin(np.pi * min(t / 9.0, 1.0))  # noqa: E731
    rt.activate(c, Locomotion(args.pack, path=PATH, speed=speed), 0.0)
    rt.run(args.seconds)
    bvh = Path(args.output).with_suffix(".bvh")
    infuse.save(rt.export(c, "walk_path"), bvh)
    extra = ["--strip", "8"] if Path(args.output).suffix == ".png" else []
    return subprocess.call([sys.executable, "-c", "from infuse.cli import run; run()", "render", str(bvh), "-o", args.output, "--follow", "--view", "three-quarter", *extra])


if __name__ == "__main__":
    raise SystemExit(main())
