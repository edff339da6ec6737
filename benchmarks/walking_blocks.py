"""What a walking character costs per block of a live scene: locomotion's CPU time in blocks of one frame.

A live scene evaluates blocks of one frame when it can (latency), so what counts is the fixed cost of
each block per character. Ten characters (Mixamo's X Bot and a Ready Player Me avatar in turn, each
with its locomotion pack, in a ring at 60 fps) look at the next one's face with listening saccades
(and blink, breathe, idle); four of them walk across the ring, turning and stopping where they are
sent, and two walk on to the middle. The scene is stepped one frame per block (then in blocks of 8 for
comparison) and the benchmark prints the scene's CPU milliseconds per block and locomotion's (its
controller class's ``evaluate``), per walking character, and how much of that the feet take (pinning
them and keeping them above the ground), the rest being the blend (steering, weights, phase maps, clip
sampling, shorter steps). Times are CPU time of this process, best of ``--rounds``; the load average is
printed with them (the machine is shared).

Run: ``.venv/bin/python benchmarks/walking_blocks.py [--frames 240] [--rounds 3]`` (needs the corpus,
``INFUSE_CORPUS``).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import infuse_locomotion.controller as locomotion
from infuse.scene import Scene
from infuse_locomotion.controller import Locomotion

from controllers_speed import CORPUS, LIVE_CAST, LIVE_FPS as FPS, live_scene

COUNT, WALKING = 10, 4


def walking_scene() -> Scene:
    """:data:`COUNT` characters in the ring of :func:`controllers_speed.live_scene` (radius 4 m, facing its
    centre, each looking at the next); the first :data:`WALKING` walk: toward the middle, across the ring,
    outward and sideways (turning on the spot first), and the first two walk on to the middle 3.5 s in."""
    scene = live_scene(COUNT)
    radius = 1.5 + 0.25 * COUNT
    names = list(scene.characters)
    for k, name in enumerate(names[:WALKING]):
        position = scene.runtime.rig(name).position
        x, z = float(position[0]), float(position[2])
        goals = ((0.2 * x, 0.2 * z), (-0.5 * x, -0.5 * z), (1.6 * x, 1.6 * z), (x + 2.0 * z / radius, z - 2.0 * x / radius))
        scene.walk_to(name, goals[k % len(goals)])
    for name in names[:2]:
        scene.walk_to(name, (0.0, 0.0), at=3.5)
    return scene


def run(frames: int, block: int) -> tuple[float, float, float, float]:
    """CPU seconds per block of the scene, of locomotion and of its feet, and walks evaluated per block,
    stepping :func:`walking_scene` in blocks of ``block`` frames for ``frames`` frames after its first
    half second."""
    scene = walking_scene()
    scene.step(int(FPS // 2))
    spent, walks = {"walks": 0.0, "feet": 0.0}, [0]
    evaluate, pin, keep_up = Locomotion.evaluate.__func__, Locomotion.__dict__["_pin"], locomotion._keep_feet_up
    # The feet held alike, the leg IK and the feet's joints below it, done for all groups at once.
    hold, legs, below = locomotion._hold_all, locomotion.solve_limb_ends_together, locomotion._feet_below

    def timed(function, part):
        def run(*args):
            start = time.process_time()
            out = function(*args)
            spent[part] += time.process_time() - start
            return out
        return run

    def timed_steps(function, part):  # a generator's steps timed as they run
        def run(*args):
            steps = function(*args)
            while True:
                start = time.process_time()
                try:
                    asked = next(steps)
                except StopIteration as done:
                    spent[part] += time.process_time() - start
                    return done.value
                spent[part] += time.process_time() - start
                yield asked
        return run

    def walked(cls, jobs, at):
        timed(evaluate, "walks")(cls, jobs, at)
        walks[0] += sum(1 for job in jobs if job.local_times[-1] >= 0.0)

    own = Locomotion.__dict__.get("evaluate")  # None: the base class's (one walk at a time)
    Locomotion.evaluate = classmethod(walked)
    Locomotion._pin = staticmethod(timed_steps(pin.__func__, "feet"))
    locomotion._keep_feet_up = timed(keep_up, "feet")
    locomotion._hold_all, locomotion.solve_limb_ends_together = timed(hold, "feet"), timed(legs, "feet")
    locomotion._feet_below = timed(below, "feet")
    try:
        start, steps = time.process_time(), frames // block
        for _ in range(steps):
            scene.step(block)
        cpu = time.process_time() - start
    finally:
        if own is None:
            del Locomotion.evaluate
        else:
            Locomotion.evaluate = own
        Locomotion._pin, locomotion._keep_feet_up = pin, keep_up
        locomotion._hold_all, locomotion.solve_limb_ends_together, locomotion._feet_below = hold, legs, below
    return cpu / steps, spent["walks"] / steps, spent["feet"] / steps, walks[0] / steps


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=240, help="frames stepped per round (default 240: 4 s)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds per block size; the best counts (default 3)")
    args = parser.parse_args()
    if not (CORPUS / LIVE_CAST[0][0]).is_file():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    print(f"{COUNT} characters, {WALKING} walking, {FPS:g} fps; CPU ms, best of {args.rounds} rounds of {args.frames} frames; "
          f"load average {os.getloadavg()[0]:.2f}")
    for block in (1, 8):
        scene_s, walk_s, feet_s, walks = min((run(args.frames, block) for _ in range(args.rounds)), key=lambda r: r[1])
        print(f"  blocks of {block}: scene {1e3 * scene_s:.2f} ms per block, locomotion {1e3 * walk_s:.2f} "
              f"({100 * walk_s / scene_s:.0f}%), {1e3 * walk_s / max(walks, 1e-9):.3f} ms per walking character "
              f"({walks:.2f} walks per block): the feet {1e3 * feet_s / max(walks, 1e-9):.3f}, the "
              f"rest (the blend) {1e3 * (walk_s - feet_s) / max(walks, 1e-9):.3f}")
    print(f"  load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
