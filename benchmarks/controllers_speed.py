"""Controller runtime speed: 1, 10 and 100 characters gazing, saccading, blinking and breathing over a
looping walk.

Every character is the SmartBody utah skeleton (113 joints) walking ChrUtah_Walk001 in a loop, each
at its own place and phase, breathing, blinking (conversation rate), making talk-mode saccades and
following its own moving gaze target with eyes, head and spine. The figure is frames per second of
the whole scene (every character, one frame) and how many times faster than real time that is at
30 fps. The reference is the same controllers evaluated the simple way: one character and one frame
at a time (no batching over characters, no vectorizing over frames), run in the same process on a
smaller share of the work; its output is checked equal to the batched one. Times are CPU seconds of
this process, best of 3 (other processes on the machine do not count); the wall clock is shown beside.

Then the cost of a live scene's blocks of one frame (``--blocks`` runs only this): 10 and 50 characters
(Mixamo's X Bot and a Ready Player Me avatar in turn, each with its locomotion pack, in a ring at 60 fps)
idle on their pack's idle clip, blink, breathe, look at the next character's face and make listening
saccades, evaluated one frame per block as a live scene does when it can. It prints CPU milliseconds per
block and per character, and each controller class's share (its ``evaluate``), the rest being the
runtime's and the scene's own work per block.

Run: ``.venv/bin/python benchmarks/controllers_speed.py [--blocks]`` (needs the corpus, ``INFUSE_CORPUS``).
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import infuse
from infuse import Character
from infuse.runtime import Clip, Runtime, controller
from infuse.scene import Scene

FPS = 30.0
SECONDS = 10.0
CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
SKELETON = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
WALK = "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"


def load():
    asset = infuse.load(CORPUS / SKELETON)
    walk = next(iter(infuse.load(CORPUS / WALK).motions.values()))
    mapping = infuse.mapping.map_skeleton(asset)
    return Character("utah", asset, mapping=mapping), walk


def populate(rt: Runtime, character, walk, count: int, first: int = 0) -> list[str]:
    """Add characters ``first`` .. ``first + count - 1`` with their controllers; returns their names."""
    names = []
    for i in range(first, first + count):
        name = f"utah{i:03d}"
        x, z = 2.0 * (i % 10), -2.0 * (i // 10)
        rt.add_character(character, name=name, position=(x, 0.0, z))
        rt.activate(name, Clip(walk, offset_s=(i * 0.137) % walk.duration), 0.0)
        rt.activate(name, controller("breathing", phase=(i * 0.31) % 1.0), 0.0)
        rt.activate(name, controller("blink", activity="conversation", seed=i), 0.0)
        rt.activate(name, controller("saccade", mode="talk", seed=i), 0.0)
        speed = 1.3  # the walk's speed, m/s: the target keeps ahead of the walker and sweeps side to side

        def target(t, x=x, z=z, phase=i * 0.7):
            t = np.asarray(t, dtype=np.float64)
            return np.stack((x + 1.5 * np.sin(0.8 * t + phase), 1.5 + 0.3 * np.sin(1.3 * t + phase),
                             z + 2.5 + speed * t), axis=-1)

        rt.activate(name, controller("gaze", target=target), 0.0)
        names.append(name)
    return names


def batched(character, walk, count: int, seconds: float = SECONDS) -> tuple[float, float, Runtime, list[str]]:
    """Wall and CPU seconds to evaluate ``count`` characters for ``seconds``, batched; the runtime and names."""
    rt = Runtime(fps=FPS)
    names = populate(rt, character, walk, count)
    start, cpu = time.perf_counter(), time.process_time()
    rt.run(seconds)
    return time.perf_counter() - start, time.process_time() - cpu, rt, names


def one_at_a_time(character, walk, count: int, frames: int) -> tuple[float, float, list[Runtime]]:
    """Wall and CPU seconds to evaluate ``count`` characters for ``frames`` frames, each alone, frame by frame."""
    runtimes = []
    for i in range(count):
        rt = Runtime(fps=FPS, block_frames=1)
        populate(rt, character, walk, 1, first=i)
        runtimes.append(rt)
    start, cpu = time.perf_counter(), time.process_time()
    for _ in range(frames):
        for rt in runtimes:
            rt.step()
    return time.perf_counter() - start, time.process_time() - cpu, runtimes


LIVE_FPS = 60.0
LIVE_CAST = (("runxaway-models/Xbot.glb", "locomotion-male"), ("talkinghead/avatars/brunette-t.glb", "locomotion-female"))
BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"


def live_scene(count: int) -> Scene:
    """``count`` characters in a ring of radius 1.5 m + 0.25 m per character, facing the centre, each
    looking at the next one's face with listening saccades (and the scene's idle clip, blinks, breathing)."""
    scene = Scene(fps=LIVE_FPS, quiet=True)
    cast = []
    for path, pack in LIVE_CAST:
        asset = infuse.load(CORPUS / path)
        cast.append((Character(Path(path).stem, asset, mapping=infuse.mapping.map_skeleton(asset)), pack))
    radius = 1.5 + 0.25 * count
    for k in range(count):
        character, pack = cast[k % len(cast)]
        angle = 2 * math.pi * k / count
        scene.add_character(character, f"c{k}", position=(radius * math.sin(angle), 0.0, radius * math.cos(angle)),
                            facing=(0.0, 0.0, 0.0), packs=[pack])
    names = list(scene.characters)
    for k, name in enumerate(names):
        scene.bml(name, f'<bml xmlns="{BML_NS}" xmlns:sbm="http://ict.usc.edu" id="look{k}">'
                        f'<gazeShift id="g" target="{names[(k + 1) % count]}"/><sbm:saccade id="s" mode="listen"/></bml>')
    return scene


def one_frame_blocks(count: int, blocks: int) -> tuple[float, dict[str, float]]:
    """CPU seconds per block of one frame of :func:`live_scene` (after a settling second), and each
    controller class's CPU seconds per block in its ``evaluate``."""
    scene = live_scene(count)
    scene.step(int(LIVE_FPS))
    spent: dict[str, float] = {}
    classes = {type(a.controller) for a in scene.runtime.activities}
    originals = {cls: cls.__dict__.get("evaluate") for cls in classes}

    def timed(cls):
        evaluate = cls.evaluate.__func__

        def run(klass, jobs, block):
            start = time.process_time()
            evaluate(klass, jobs, block)
            spent[cls.__name__] = spent.get(cls.__name__, 0.0) + time.process_time() - start
        return classmethod(run)

    for cls in classes:
        cls.evaluate = timed(cls)
    try:
        start = time.process_time()
        for _ in range(blocks):
            scene.step(1)
        cpu = time.process_time() - start
    finally:
        for cls, original in originals.items():
            if original is None:
                del cls.evaluate
            else:
                cls.evaluate = original
    return cpu / blocks, {name: seconds / blocks for name, seconds in spent.items()}


def report_blocks(blocks: int = 600) -> None:
    print(f"one-frame blocks at {LIVE_FPS:g} fps (X Bot and an RPM avatar in turn: idle clip, blinks, breathing, gaze at "
          f"the next one's face, listening saccades), load average {os.getloadavg()[0]:.2f}")
    for count in (10, 50):
        runs = [one_frame_blocks(count, blocks if count <= 10 else blocks // 2) for _ in range(3)]
        cpu, shares = min(runs, key=lambda r: r[0])
        parts = ", ".join(f"{name} {1000 * s / count:.4f}" for name, s in sorted(shares.items(), key=lambda kv: -kv[1]))
        rest = cpu - sum(shares.values())
        print(f"  {count:>3} characters: {1000 * cpu:.2f} CPU ms per block, {1000 * cpu / count:.4f} per character "
              f"(best of 3); per character: {parts}, runtime and scene {1000 * rest / count:.4f}")
    print(f"  load average after: {os.getloadavg()[0]:.2f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--blocks", action="store_true", help="only the one-frame blocks of a live scene")
    args = parser.parse_args()
    if not (CORPUS / SKELETON).is_file():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    if args.blocks:
        report_blocks()
        return 0
    character, walk = load()
    frames = int(SECONDS * FPS)
    print(f"controller runtime: utah skeleton ({character.skeleton.num_joints} joints), walk loop + breathing + blink "
          f"+ saccades + gaze, {SECONDS:g} s at {FPS:g} fps; {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, Python {platform.python_version()}, numpy {np.__version__}")
    batched(character, walk, 2, 1.0)  # warm up imports and caches
    results = {}
    for count in (1, 10, 100):
        wall, cpu, rt, names = min((batched(character, walk, count) for _ in range(3)), key=lambda r: r[1])
        results[count] = (cpu, rt, names)
        print(f"  {count:>3} characters: {frames / cpu:8.1f} frames/s ({count * frames / cpu:7.0f} character-frames/s), "
              f"{SECONDS / cpu:5.1f}x real time  [wall clock: {SECONDS / wall:.1f}x]")
    wall, cpu, _, _ = min((batched(character, walk, 2, 30.0) for _ in range(3)), key=lambda r: r[1])
    print(f"  2 characters, a 30 s scene: {cpu:.2f} s, {30.0 / cpu:.0f}x real time  [wall clock: {30.0 / wall:.0f}x]")
    ref_count, ref_frames = 10, 30
    ref_wall, ref_cpu, runtimes = one_at_a_time(character, walk, ref_count, ref_frames)
    ref_rate = ref_count * ref_frames / ref_cpu
    cpu100 = results[100][0]
    rate100 = 100 * frames / cpu100
    print(f"  reference, one character and one frame at a time ({ref_count} characters x {ref_frames} frames): "
          f"{ref_rate:7.0f} character-frames/s, {ref_rate / 100 / FPS:.2f}x real time for 100 characters")
    print(f"  batched / reference at 100 characters: {rate100 / ref_rate:.0f}x")
    rt100, names100 = results[100][1], results[100][2]
    worst = max(np.abs(rt100.motion(names100[i]).local_rotations[:ref_frames] - runtimes[i].motion(names100[i]).local_rotations).max()
                for i in range(ref_count))
    print(f"  largest difference between the two outputs: {worst:.1e} (quaternion components)")
    ok = SECONDS / cpu100 > 1.0
    print(f"  target (100 characters at 30 fps faster than real time): {'met' if ok else 'NOT met'}")
    report_blocks()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
