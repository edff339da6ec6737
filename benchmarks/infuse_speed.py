"""Infusing speed: the built-in packs onto a 65-joint character (Mixamo's X Bot), cold and from the cache.

Prints: seconds to infuse locomotion-male, locomotion-female and reaching (map, retarget every clip,
blend spaces), the cached load, and the realized root speed of the locomotion controller over each
locomotion pack's range. Run: ``python benchmarks/infuse_speed.py`` (corpus from ``INFUSE_CORPUS``).
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

import infuse
from infuse.packs import infuse_character, load_pack
from infuse.runtime import Runtime

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
PACKS = ["locomotion-male", "locomotion-female", "reaching"]


def main() -> int:
    xbot = infuse.load(CORPUS / "runxaway-models/Xbot.glb")
    for name in PACKS:
        load_pack(name)
    infuse_character(xbot, PACKS[:1])  # first use imports scipy and the plugins; not part of the figure
    best = min(infuse_character(xbot, PACKS).seconds for _ in range(3))
    frames = sum(c.motion.num_frames for s in infuse_character(xbot, PACKS).spaces.values() for c in s.clips.values())
    with tempfile.TemporaryDirectory() as tmp:
        infuse_character(xbot, PACKS, cache=tmp)
        cached = min(infuse_character(xbot, PACKS, cache=tmp).seconds for _ in range(3))
    print(f"character: Xbot.glb, {xbot.skeleton.num_joints} joints; packs: {', '.join(PACKS)} ({frames} frames)")
    print(f"infuse (map + retarget + blend spaces): {best:.3f} s  (target < 1 s)")
    print(f"load from the cache:                    {cached:.3f} s")
    from infuse_locomotion import Locomotion

    for pack in PACKS[:2]:
        space = infuse_character(xbot, [pack]).spaces[pack]
        lo, hi = space.range("forward_speed")
        rows = []
        for v in np.linspace(max(lo, 0.3), hi, 6):
            rt = Runtime(fps=30)
            c = rt.add_character(infuse.Character("x", xbot))
            rt.activate(c, Locomotion(space, speed=float(v), max_accel=50.0), 0.0)
            rt.run(4.0)
            g = infuse.motion_fk(rt.motion(c))[1][:, rt.rig(c).joint("base")]
            realized = np.hypot(*(g[-1] - g[30])[[0, 2]]) / ((len(g) - 31) / 30.0)
            rows.append(f"{v:.2f}->{realized:.2f}")
        print(f"{pack}: requested -> realized root speed (m/s): {'  '.join(rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
