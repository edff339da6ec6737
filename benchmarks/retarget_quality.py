"""Retargeting quality on real clips: foot skate, bone directions, ground contact, root speed.

Pairs: Bandai walk, run and dash (normal, feminine, masculinity) onto SmartBody's Utah skeleton,
Mixamo's X Bot, a CMU skeleton and RobotExpressive; SmartBody's MaleLocomotion walk and run onto
the Bandai skeleton and X Bot. Every skeleton is mapped by the installed heuristic mapper.

Columns: skate in cm per metre walked (source / plain transfer / paper's warped IK / final
contact-pinned IK) and the target, source x 1.1 + 0.5; bone-direction error in degrees (mean over
body bones and frames, plain and final); penetration and float of the feet in cm (mean; source /
final); root speed over source speed x leg scale; the largest miss of a reachable IK goal in mm
and the share of goals out of reach; popping: of every mapped joint, the one whose largest turn
between frames comes closest to the bound, 1.5 x the source's + 10 degrees (its source / final
turn in degrees, and the margin left, negative when past the bound).

A second table measures per-limb scaling by extension on SmartBody's reaching clips: how far the
hand's offset from the shoulder, over the arm length, differs from the source's while the source
arm is extended (percent of arm length), for the plain transfer and with limb scaling.

Run: ``python benchmarks/retarget_quality.py`` (reads the corpus from ``INFUSE_CORPUS``, default
``../shared/corpus``).
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

import infuse
from infuse.mapping import map_skeleton, sample_poses
from infuse_retarget import RetargetPlan, retarget_clip
from infuse_retarget.quality import evaluate, reach_error

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_{}_{}_001.bvh"
UTAH = "smartbody/behaviorsets/MaleLocomotion/"
SOURCES_BANDAI = [BANDAI.format(kind, style) for kind in ("walk", "run", "dash") for style in ("normal", "feminine", "masculinity")]
SOURCES_SMARTBODY = [UTAH + "motions/ChrUtah_Walk001.skm", UTAH + "motions/ChrUtah_Run001.skm"]
TARGETS_BANDAI = [UTAH + "skeletons/test_utah.sk", "runxaway-models/Xbot.glb", "bvh11/resources/131_03.bvh",
                  "adibkn1-robot/RobotExpressive.glb"]
TARGETS_SMARTBODY = [BANDAI.format("walk", "normal"), "runxaway-models/Xbot.glb"]
REACHES = "smartbody/behaviorsets/reaching/motions"
TARGETS_REACH = ["bvh11/resources/131_03.bvh", "runxaway-models/Xbot.glb"]


def load(rel: str):
    """(asset, mapping over the whole skeleton, first clip or None)."""
    asset = infuse.load(CORPUS / rel)
    mapping = map_skeleton(asset.skeleton, pose=sample_poses(asset), meta=asset.meta, humanoid=asset.humanoid,
                           file=asset.path)
    return asset, mapping, next(iter(asset.motions.values()), None)


_cache: dict = {}


def get(rel: str):
    if rel not in _cache:
        _cache[rel] = load(rel)
    return _cache[rel]


def rows():
    for sources, targets in ((SOURCES_BANDAI, TARGETS_BANDAI), (SOURCES_SMARTBODY, TARGETS_SMARTBODY)):
        for src in sources:
            s_asset, s_map, clip = get(src)
            for tgt in targets:
                t_asset, t_map, t_clip = get(tgt)
                plan = RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip, target_motion=t_clip)
                yield Path(src).stem, Path(tgt).stem, evaluate(plan, clip)


def main() -> int:
    if not (CORPUS / "labels").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    head = (f"{'source':<34} {'target':<17} {'scale':>5} | {'skate src/plain/paper/final':>28} {'limit':>5} | "
            f"{'bones pl/fin':>12} | {'pen src/fin':>11} {'float src/fin':>13} | {'speed':>5} | {'IK mm':>6} {'out':>4}")
    print(head)
    print("-" * len(head))
    failures = 0
    start = time.perf_counter()
    for src, tgt, q in rows():
        pop = q.popping_final
        ok = q.skate_final <= q.skate_limit() and q.bones_final <= 5.0 and q.residual_mm <= 1.0 and pop.ok
        failures += not ok
        pop_source, pop_final = pop.turns()
        print(f"{src:<34} {tgt:<17} {q.scale:5.2f} | {q.skate_source:6.2f} {q.skate_plain:6.2f} {q.skate_paper:6.2f} "
              f"{q.skate_final:6.2f} {q.skate_limit():5.2f} | {q.bones_plain:5.2f} {q.bones_final:6.2f} | "
              f"{q.penetration_source:5.2f} {q.penetration_final:5.2f} {q.float_source:6.2f} {q.float_final:6.2f} | "
              f"{q.speed_ratio:5.3f} | {q.residual_mm:6.3f} {100 * q.unreachable:3.0f}% | {pop.worst:>16} {pop_source:5.1f} {pop_final:5.1f} "
              f"{-pop.excess:5.1f}" + ("" if ok else "  <- misses a target"))
    print(f"\n{failures} pair(s) miss a target (skate <= source x 1.1 + 0.5 cm/m, bones <= 5 deg, reachable goals <= 1 mm, "
          f"every mapped joint's largest turn <= source's x 1.5 + 10 deg); "
          f"{time.perf_counter() - start:.1f} s")
    print(f"\n{'reaching clips (arm extended > 0.9)':<40} {'target':<10} {'plain %':>8} {'scaled %':>9}")
    for tgt in TARGETS_REACH:
        t_asset, t_map, t_clip = get(tgt)
        errors = []
        for path in sorted((CORPUS / REACHES).glob("*.skm")):
            s_asset, s_map, clip = load(str(path.relative_to(CORPUS)))
            plan = RetargetPlan(clip.skeleton, s_map, t_asset.skeleton, t_map, source_motion=clip, target_motion=t_clip)
            plain = retarget_clip(plan, clip, ik="contacts")
            scaled = retarget_clip(plan, clip, ik="contacts", limb_scaling=True)
            errors.append((reach_error(plan, plain.motion, plain.source_positions),
                           reach_error(plan, scaled.motion, scaled.source_positions)))
        errors = np.array(errors, dtype=float)
        mean = np.nanmean(errors, axis=0)
        print(f"{f'{len(errors)} SmartBody reaching clips':<40} {Path(tgt).stem:<10} {mean[0]:8.2f} {mean[1]:9.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
