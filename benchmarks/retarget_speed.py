"""Retargeting speed: frames per second onto a 65-joint character (Mixamo's X Bot).

The source is every Bandai clip of the corpus, joined into one long clip (22 joints) and repeated
to at least 10,000 frames. Each stage runs several times; the best run is reported, both as wall
time and as this process's CPU time (numpy runs these stages on one thread, so on an idle machine
the two agree; on a shared machine the CPU figure is the one that does not count other jobs).

- ``transfer``: source FK, rotations through the canonical frame, root scaling, the target Motion.
- ``paper IK``: plus the paper's warped feet enforced by the two-bone leg IK.
- ``contact IK``: plus contact detection and pinned feet (the default).
- ``+ limb scaling``: the default plus arm IK by extension.

Run: ``python benchmarks/retarget_speed.py [--frames N]`` (corpus from ``INFUSE_CORPUS``).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import infuse
from infuse.mapping import map_skeleton
from infuse_retarget import RetargetPlan, retarget_clip

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data"
TARGET = "runxaway-models/Xbot.glb"


def long_clip(frames: int) -> infuse.Motion:
    """Every Bandai clip joined end to end, repeated to at least ``frames`` frames."""
    clips = [next(iter(infuse.load(p).motions.values())) for p in sorted((CORPUS / BANDAI).glob("*.bvh"))]
    repeat = -(-frames // sum(c.num_frames for c in clips))
    clips = clips * repeat
    first = clips[0]
    return infuse.Motion(first.skeleton, first.fps, np.concatenate([c.local_rotations for c in clips]),
                         np.concatenate([c.root_translations for c in clips]),
                         np.concatenate([c.local_translations() for c in clips]), name="bandai")


def best_of(run, times: int) -> tuple[float, float]:
    """Shortest (wall, CPU) seconds of ``times`` calls."""
    wall = cpu = float("inf")
    for _ in range(times):
        w, c = time.perf_counter(), time.process_time()
        run()
        wall = min(wall, time.perf_counter() - w)
        cpu = min(cpu, time.process_time() - c)
    return wall, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000, help="at least this many source frames")
    parser.add_argument("--repeat", type=int, default=5, help="runs per stage (the best counts)")
    args = parser.parse_args()
    if not (CORPUS / "labels").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    clip = long_clip(args.frames)
    character = infuse.load(CORPUS / TARGET)
    t0 = time.process_time()
    plan = RetargetPlan(clip.skeleton, map_skeleton(clip.skeleton), character.skeleton, map_skeleton(character),
                        source_motion=clip)
    build = time.process_time() - t0
    frames = clip.num_frames
    print(f"{frames} frames of {clip.skeleton.num_joints}-joint Bandai motion onto {TARGET} "
          f"({character.skeleton.num_joints} joints); plan built in {1000 * build:.0f} CPU ms (mapping included)")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores\n")
    print(f"{'stage':<16} {'wall ms':>8} {'frames/s':>10} {'CPU ms':>8} {'frames/s':>10}")
    stages = [("transfer", dict(ik="none")), ("paper IK", dict(ik="paper")), ("contact IK", dict(ik="contacts")),
              ("+ limb scaling", dict(ik="contacts", limb_scaling=True))]
    for name, options in stages:
        wall, cpu = best_of(lambda: retarget_clip(plan, clip, **options), args.repeat)
        print(f"{name:<16} {1000 * wall:8.1f} {frames / wall:10.0f} {1000 * cpu:8.1f} {frames / cpu:10.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
