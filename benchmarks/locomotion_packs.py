"""Locomotion packs from real motion sets: how exactly they steer, measured on the output.

Packs are imported as a new user would (``infuse pack import``, read in place, built into a temporary
folder): SmartBody's MaleLocomotion and FemaleLocomotion behaviour sets, and one pack per style of the
Bandai Namco dataset-1 (feminine, masculinity, normal) and dataset-2 (feminine, masculine, normal)
folders; with the built-in ``locomotion-male`` and ``locomotion-female``. Each is tried on Xbot and on
SmartBody's Brad with :func:`infuse.packs.walk_test.trial_pack` (speeds over the pack's forward range,
heading drift over 8 s straight, walks to targets 2, 4 and 6 m away at 0, 45, 90, 135, 180 and -90
degrees, foot skate on the straight walks and on the walks to targets, all of each and apart in its
parts: on the spot (standing, turning on the spot), start, stop and settling): the table shows the
worst figure of each measure; ``--full`` prints every trial.

Targets: speed within 5%, drift at most 3 degrees, miss at most 5 cm, path at most 1.15x the straight
line, no loops, foot skate at most 1.5 cm/m.

Run: ``.venv/bin/python benchmarks/locomotion_packs.py [--full] [--only NAME]`` (needs the corpus,
``INFUSE_CORPUS``).
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
from infuse.packs.importers import import_bvh_folder, import_smartbody
from infuse.packs.walk_test import report, trial_pack

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
CHARACTERS = {"Xbot": "runxaway-models/Xbot.glb", "Brad": "smartbody/ChrBrad/ChrBrad.sk"}
SMARTBODY = {"sb-male": "MaleLocomotion", "sb-female": "FemaleLocomotion"}
BANDAI = {f"d{n}-{style}": (f"Bandai-Namco-Research-Motiondataset-{n}", f"dataset-{n}_*_{style}_*.bvh")
          for n, styles in ((1, ("feminine", "masculinity", "normal")), (2, ("feminine", "masculine", "normal")))
          for style in styles}
BUILT_IN = ("locomotion-male", "locomotion-female")


def packs(folder: Path, only: str | None) -> dict[str, object]:
    """Pack name -> what :func:`trial_pack` takes (a built folder, or a built-in name)."""
    out = {}
    for name, source in SMARTBODY.items():
        if not only or only in name:
            out[name] = build_pack(import_smartbody(CORPUS / "smartbody" / "behaviorsets" / source, folder / name, name=name))
    for name, (source, pattern) in BANDAI.items():
        if not only or only in name:
            out[name] = build_pack(import_bvh_folder(CORPUS / "bandai" / source / "data", folder / name, name=name, pattern=pattern))
    for name in BUILT_IN:
        if not only or only in name:
            out[name] = name
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--full", action="store_true", help="print every trial")
    p.add_argument("--only", help="packs whose name holds this")
    args = p.parse_args()
    if not (CORPUS / "bandai").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    characters = {n: infuse.load(CORPUS / f) for n, f in CHARACTERS.items()}
    print(f"{'pack':<18} {'character':<6} {'speed err':>9} {'drift':>6} {'miss':>7} {'path':>5} {'loops':>5} "
          f"{'skate':>6} {'to tgt':>6} {'spot':>5} {'start':>5} {'stop':>5} {'settle':>6} {'s':>5}")
    print(f"{'':<18} {'':<6} {'%':>9} {'deg':>6} {'m':>7} {'x':>5} {'':>5} {'cm/m':>6} {'cm':>6} {'cm':>5} {'cm':>5} {'cm':>5} "
          f"{'cm':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, pack in packs(Path(tmp), args.only).items():
            for who, asset in characters.items():
                start = time.perf_counter()
                trial = trial_pack(infuse.Character(who, asset), pack)
                w = trial.worst()
                parts = w["part_skate_cm"]
                print(f"{name:<18} {who:<6} {100 * w['speed_error']:9.1f} {w['drift_deg']:6.1f} {w['miss_m']:7.3f} "
                      f"{w['path_ratio']:5.2f} {w['loops']:5d} {w['skate_cm_m']:6.2f} {w['target_skate_cm']:6.1f} "
                      f"{parts['on the spot']:5.1f} {parts['start']:5.1f} {parts['stop']:5.1f} {parts['settle']:6.1f} "
                      f"{time.perf_counter() - start:5.1f}",
                      flush=True)
                if args.full:
                    print(report(trial))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
