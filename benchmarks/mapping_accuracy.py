"""Mapping accuracy on the labelled corpus, and on generated variants of every labelled skeleton.

    python benchmarks/mapping_accuracy.py [--mapper heuristic] [--no-variants] [--markdown] [FILTER...]

A prediction is right when it equals the label or one of its alternatives (``null`` counts as a
label). Body joints are base, spine1, spine3, spine4, skullbase, clavicle to wrist and hip to the
ball of the foot. Non-humanoid files must be refused (NotHumanoidError). Times are the mapper call
alone (the file is read before the clock starts), median over files, as CPU time of this process
(steady on a busy machine) and as wall-clock time. The corpus is read from
``INFUSE_CORPUS`` (default ``../shared/corpus`` beside the repository).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

import infuse  # noqa: E402
from infuse.canonical import BODY_NAMES, CANONICAL_NAMES  # noqa: E402
from infuse.mapping import map_skeleton, sample_poses  # noqa: E402

import skeleton_variants  # noqa: E402

CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()


def score(mapping: dict, expected: dict, alternatives: dict, names=CANONICAL_NAMES) -> tuple[int, int, list]:
    """(right, total, wrong entries) of a canonical -> joint dict against a label."""
    right, wrong = 0, []
    for k in names:
        got, want = mapping.get(k), expected.get(k)
        if got == want or got in (alternatives or {}).get(k, []):
            right += 1
        else:
            wrong.append((k, got, want))
    return right, len(names), wrong


def load_labels(filters: list[str]) -> list[dict]:
    docs = [json.loads(p.read_text()) for p in sorted((CORPUS / "labels").glob("*.json"))]
    return [d for d in docs if not filters or any(f in d["file"] for f in filters)]


def run(mapper: str, filters: list[str], variants: bool, markdown: bool, verbose: bool) -> dict:
    rows, times, walls = [], [], []
    total_right = total = 0
    body_perfect = humanoid_files = 0
    refused_ok = non_humanoid = 0
    variant_stats: dict[str, list[int]] = {}
    variant_times = []
    failures = []
    for label in load_labels(filters):
        path = CORPUS / label["file"]
        try:
            asset = infuse.load(path)
        except infuse.InfuseError as exc:
            failures.append(f"{label['file']}: cannot be read: {exc}")
            continue
        t0, w0 = time.process_time(), time.perf_counter()
        try:
            mapping = map_skeleton(asset, mapper=mapper)
            refused = None
        except infuse.NotHumanoidError as exc:
            mapping, refused = None, exc.reason
        times.append(time.process_time() - t0)
        walls.append(time.perf_counter() - w0)
        if not label["humanoid"]:
            non_humanoid += 1
            refused_ok += refused is not None
            rows.append((label["file"], asset.skeleton.num_joints, "refused" if refused else "NOT REFUSED", "", times[-1]))
            continue
        humanoid_files += 1
        joints = mapping.joints if mapping is not None else {}
        right, n, wrong = score(joints, label["mapping"], label.get("alternatives"))
        b_right, b_n, b_wrong = score(joints, label["mapping"], label.get("alternatives"), BODY_NAMES)
        total_right += right
        total += n
        body_perfect += b_right == b_n
        rows.append((label["file"], asset.skeleton.num_joints, f"{right / n:.3f}", f"{b_right}/{b_n}", times[-1]))
        if verbose and wrong:
            print(f"  {label['file']}: {wrong}", file=sys.stderr)
        if refused:
            failures.append(f"{label['file']}: refused: {refused}")
        if variants:
            pose = sample_poses(asset)
            meta = {"channel_joints": asset.meta.get("channel_joints")} if asset.meta.get("channel_joints") else {}
            for v in skeleton_variants.all_variants(asset.skeleton, pose, label):
                meta_v = _variant_meta(asset.skeleton, v, meta) if meta else {}
                t0 = time.process_time()
                try:
                    vm = map_skeleton(v.skeleton, mapper=mapper, pose=v.poses, meta=meta_v).joints
                except infuse.NotHumanoidError:
                    vm = {}
                variant_times.append(time.process_time() - t0)
                r, n, w = score(vm, v.mapping, v.alternatives)
                acc = variant_stats.setdefault(v.name, [0, 0])
                acc[0] += r
                acc[1] += n
                if verbose and w:
                    print(f"  variant {v.name} {label['file']}: {w[:8]}", file=sys.stderr)
    summary = {
        "overall": total_right / max(total, 1),
        "body_perfect_files": body_perfect,
        "humanoid_files": humanoid_files,
        "non_humanoid_refused": refused_ok,
        "non_humanoid": non_humanoid,
        "median_ms": 1000 * statistics.median(times) if times else float("nan"),
        "median_wall_ms": 1000 * statistics.median(walls) if walls else float("nan"),
        "median_ms_40_120_joints": 1000 * statistics.median(
            [t for t, (_, j, *_) in zip(times, rows) if 40 <= j <= 120] or [float("nan")]),
        "variants": {k: v[0] / max(v[1], 1) for k, v in variant_stats.items()},
        "variants_overall": (sum(v[0] for v in variant_stats.values()) / max(sum(v[1] for v in variant_stats.values()), 1))
        if variant_stats else None,
        "variant_median_ms": 1000 * statistics.median(variant_times) if variant_times else None,
    }
    _print(rows, summary, failures, markdown)
    return summary


def _variant_meta(original, variant, meta):
    """The animated-joint list of a motion file, in the variant's joint names."""
    return {"channel_joints": variant.translate(meta["channel_joints"])}


def _print(rows, summary, failures, markdown):
    if markdown:
        print("| file | joints | accuracy | body joints | ms |")
        print("|---|---:|---:|---:|---:|")
        for f, j, acc, body, t in rows:
            print(f"| {f} | {j} | {acc} | {body} | {1000 * t:.1f} |")
    else:
        for f, j, acc, body, t in rows:
            print(f"{acc:>11} {body:>6} {1000 * t:7.1f} ms  {j:4d}  {f}")
    print()
    print(f"overall accuracy: {summary['overall']:.4f}")
    print(f"files with every body joint right: {summary['body_perfect_files']}/{summary['humanoid_files']}")
    print(f"non-humanoids refused: {summary['non_humanoid_refused']}/{summary['non_humanoid']}")
    print(f"median time per skeleton: {summary['median_ms']:.2f} ms CPU ({summary['median_wall_ms']:.2f} ms wall); "
          f"skeletons of 40-120 joints: {summary['median_ms_40_120_joints']:.2f} ms CPU")
    if summary["variants"]:
        for k, v in summary["variants"].items():
            print(f"variant {k:<22} {v:.4f}")
        print(f"variants overall: {summary['variants_overall']:.4f} (median {summary['variant_median_ms']:.2f} ms CPU)")
    for f in failures:
        print(f"FAILED {f}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("filters", nargs="*", help="only label files whose path contains one of these")
    parser.add_argument("--mapper", default="heuristic")
    parser.add_argument("--no-variants", action="store_true")
    parser.add_argument("--markdown", action="store_true", help="print the per-file table as markdown")
    parser.add_argument("-v", "--verbose", action="store_true", help="list wrong predictions on stderr")
    args = parser.parse_args(argv)
    if not (CORPUS / "labels").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    run(args.mapper, args.filters, not args.no_variants, args.markdown, args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
