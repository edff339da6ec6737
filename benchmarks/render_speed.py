"""How fast ``infuse render`` draws: mesh frames against stick-figure frames, in one process.

For each character (the Mixamo Xbot, 49k triangles; the Ready Player Me avatar, 13k triangles,
textured) a BVH walk is retargeted onto it, then the same 640x480 frames of the walk are drawn
one after another (as for a GIF or MP4) as a shaded mesh and as a stick figure. Rows: decoding the
meshes from the file (geometry and textures), and frames per second of each style with the time of
one mesh frame. Times are CPU seconds of this process, best of ``--repeat`` runs (the machine may
be shared).

    python benchmarks/render_speed.py [--frames 60] [--size 640x480] [--repeat 3]

The corpus is read from INFUSE_CORPUS (default ../shared/corpus from the repository root).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import infuse
from infuse.cli import main as infuse_main
from infuse.render import Figure, Renderer

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
CHARACTERS = {"Xbot": "runxaway-models/Xbot.glb", "Ready Player Me avatar": "talkinghead/avatars/brunette-t.glb"}


def best(repeat: int, work) -> float:
    """The least CPU time of ``repeat`` runs of ``work()``."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        work()
        times.append(time.process_time() - start)
    return min(times)


def frames_per_second(figure: Figure, times: np.ndarray, size, repeat: int) -> float:
    def draw():
        renderer = Renderer([figure], times, size=size)
        for t in range(len(times)):
            renderer.image(t)
    return len(times) / best(repeat, draw)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    if not (CORPUS / WALK).is_file():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 1
    print(f"{args.frames} frames of a walk at {size[0]}x{size[1]}, CPU seconds, best of {args.repeat}")
    with tempfile.TemporaryDirectory() as work:
        for label, rel in CHARACTERS.items():
            out = Path(work) / "walk.glb"
            with contextlib.redirect_stdout(io.StringIO()):
                if infuse_main(["retarget", str(CORPUS / WALK), "--to", str(CORPUS / rel), "-o", str(out)]) != 0:
                    return 1
            decode = best(args.repeat, lambda: infuse.load(out).meshes)
            asset = infuse.load(out)
            motion = asset.motions[Path(WALK).stem]
            meshes = asset.meshes
            times = np.arange(args.frames) / motion.fps
            mesh_fps = frames_per_second(Figure.from_motion(motion, meshes=meshes), times, size, args.repeat)
            stick_fps = frames_per_second(Figure.from_motion(motion), times, size, args.repeat)
            triangles = sum(m.num_triangles for m in meshes)
            print(f"{label}: {triangles:,} triangles, {sum(m.num_vertices for m in meshes):,} vertices; "
                  f"meshes decoded in {decode * 1000:.0f} ms")
            print(f"  mesh  {mesh_fps:6.1f} frames/s ({1000 / mesh_fps:.0f} ms a frame)")
            print(f"  stick {stick_fps:6.1f} frames/s ({1000 / stick_fps:.0f} ms a frame); mesh/stick time "
                  f"{stick_fps / mesh_fps:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
