"""Locomotion packs from motion sets nobody prepared: variants of real takes, imported, built and walked.

Each source set (takes of the corpus read in place: the Bandai dataset-1 ``normal`` and dataset-2
``masculine`` takes, and SmartBody's MaleLocomotion ``.skm`` motions, 41 of them with its idle, starts,
stops, turns and steps, which a BVH import must recognize by what they do, the file names telling it
nothing) is varied by ``tests/motion_variants.py`` (frame
rates, unit, up axis, joint names, rest pose, facing and curving takes, trimmed takes, rotation noise,
fewer speeds, no runs, mirrored takes, different cadences, a calibration T-pose opening each take, one
forward walk); every variant is written as a folder of BVH
files, imported with ``infuse pack import bvh`` (:func:`infuse.packs.importers.import_bvh_folder`) and
built into a temporary folder, infused onto X Bot (or ``--on`` another character) and measured with
:func:`infuse.packs.walk_test.trial_pack` (speeds over the pack's forward range, heading drift over 8 s,
walks to targets, foot skate), every figure by FK on the output. The table shows the worst figure of
each measure (foot skate on the straight walks in cm/m, and over a whole walk to a target in cm);
``original`` is the set as recorded.

Targets (the issue's): speed within 5%, drift at most 3 degrees, miss at most 5 cm, path at most 1.15x,
no loops, foot skate at most 1.5 cm/m.

Run: ``.venv/bin/python benchmarks/pack_variants.py [--quick] [--only NAME] [--set NAME] [--full] [--on FILE]``
(needs the corpus, ``INFUSE_CORPUS``; ``--on``: a character file, a path or relative to the corpus, such as
``smartbody/ChrRachel/ChrRachel.sk``). ``--quick``: one source set, walks to targets 4 m away at 0, 90 and 180
degrees.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import infuse
from infuse.packs import build_pack
from infuse.packs.importers import import_bvh_folder
from infuse.packs.walk_test import ANGLES, DISTANCES, report, trial_pack

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import motion_variants  # noqa: E402

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
XBOT = "runxaway-models/Xbot.glb"
#: Source set name -> (folder in the corpus, file pattern).
SOURCES = {"d1-normal": ("bandai/Bandai-Namco-Research-Motiondataset-1/data", "dataset-1_*_normal_*.bvh"),
           "d2-masculine": ("bandai/Bandai-Namco-Research-Motiondataset-2/data", "dataset-2_*_masculine_*.bvh"),
           "sb-male": ("smartbody/behaviorsets/MaleLocomotion/motions", "*.skm")}
QUICK_TARGETS = ((4.0,), (0.0, 90.0, 180.0))


def measure(folder: Path, work: Path, name: str, character, targets) -> tuple[dict, object]:
    """Import and build the BVH folder as a pack, walk it on ``character``: (worst figures, trial)."""
    manifest = build_pack(import_bvh_folder(folder, work / name, name=name))
    trial = trial_pack(character, manifest, distances=targets[0], angles=targets[1])
    return trial.worst(), trial


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one source set, three walks to targets")
    p.add_argument("--only", help="variants whose name holds this")
    p.add_argument("--full", action="store_true", help="print every trial")
    p.add_argument("--set", help="source sets whose name holds this")
    p.add_argument("--on", default=XBOT, help="character file (a path, or relative to the corpus; default X Bot)")
    args = p.parse_args()
    if not (CORPUS / "bandai").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    on = Path(args.on) if Path(args.on).is_file() else CORPUS / args.on
    character = infuse.Character(on.stem, infuse.load(on))
    targets = QUICK_TARGETS if args.quick else (DISTANCES, ANGLES)
    sources = dict(list(SOURCES.items())[:1]) if args.quick else SOURCES
    sources = {k: v for k, v in sources.items() if not args.set or args.set in k}
    print(f"{'set':<13} {'variant':<15} {'clips':>5} {'speed err':>9} {'drift':>6} {'miss':>7} {'path':>5} {'loops':>5} "
          f"{'skate':>6} {'to tgt':>6} {'s':>5}")
    print(f"{'':<13} {'':<15} {'':>5} {'%':>9} {'deg':>6} {'m':>7} {'x':>5} {'':>5} {'cm/m':>6} {'cm':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for source, (folder, pattern) in sources.items():
            original = motion_variants.read_set(sorted((CORPUS / folder).glob(pattern)), source)
            names = ["original"] + [v for v in motion_variants.VARIANTS if not args.only or args.only in v]
            for name in names:
                start = time.perf_counter()
                motion_set = original if name == "original" else motion_variants.variant(original, name)
                written = motion_variants.write_set(motion_set, work / "sets" / source / name)
                try:
                    w, trial = measure(written, work / "packs" / source, name, character, targets)
                except infuse.InfuseError as e:
                    print(f"{source:<13} {name:<15} {len(motion_set.takes):5d}  refused: {e}", flush=True)
                    continue
                print(f"{source:<13} {name:<15} {len(motion_set.takes):5d} {100 * w['speed_error']:9.1f} {w['drift_deg']:6.1f} "
                      f"{w['miss_m']:7.3f} {w['path_ratio']:5.2f} {w['loops']:5d} {w['skate_cm_m']:6.2f} {w['target_skate_cm']:6.1f} "
                      f"{time.perf_counter() - start:5.1f}", flush=True)
                if args.full:
                    print(report(trial))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
