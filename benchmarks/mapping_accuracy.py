"""Mapping accuracy per rig family on the labelled corpus, on the rigs of unseen families (wild) and on
generated variants of their skeletons; the calibration of confidences and the time per skeleton.

    python benchmarks/mapping_accuracy.py [--mapper heuristic] [--sets corpus,wild,variants] [--files]
                                          [-v] [FILTER...]

A prediction is right when it equals the label or one of its alternatives (``null`` counts as a
label). Body joints are base, spine1, spine3, spine4, skullbase, clavicle to wrist and hip to the
ball of the foot. Non-humanoid files and the non-humanoid variants (legs or arms removed) must be
refused (NotHumanoidError). A family is the label's ``convention`` up to its first parenthesis.
Calibration: of the entries given a confidence of at least 0.9, the share that is right; the share
right per confidence band (< 0.8, 0.8 - 0.9, >= 0.9); and of the wrong entries, the share given
less than 0.8 (flagged for checking). Times are the mapper
call alone (the file is read before the clock starts), as CPU time of this process, the best of
three runs per file. Data are read in place from ``INFUSE_CORPUS`` (default ``../shared/corpus``)
and ``INFUSE_WILD`` (default ``../shared/wild``), both beside the repository.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

import infuse  # noqa: E402
from infuse.canonical import BODY_NAMES, CANONICAL_NAMES  # noqa: E402
from infuse.mapping import animated_joint_names, map_skeleton, sample_poses  # noqa: E402

import skeleton_variants  # noqa: E402

ROOTS = {
    "corpus": Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve(),
    "wild": Path(os.environ.get("INFUSE_WILD", REPO.parent / "shared" / "wild")).resolve(),
}
CONFIDENT = 0.9
BINS = (0.0, 0.8, 0.9, 1.01)  # confidence bands of the calibration table: < 0.8 (check it), 0.8 - 0.9, >= 0.9
FLAG = 0.8  # entries below this confidence are the ones a user should check


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


def family(label: dict) -> str:
    return label.get("convention", "?").split(" (")[0].strip() or "?"


def load_labels(root: Path, filters: list[str]) -> list[dict]:
    docs = [json.loads(p.read_text()) for p in sorted((root / "labels").glob("*.json"))]
    return [d for d in docs if not filters or any(f in d["file"] for f in filters)]


@dataclass
class FileResult:
    """One labelled file: its mapping (or the refusal) against the label."""

    label: dict
    joints: int
    seconds: float
    right: int = 0
    body_right: int = 0
    refused: str | None = None
    wrong: list = field(default_factory=list)
    confident: tuple[int, int] = (0, 0)  # (right, entries) with confidence >= CONFIDENT
    bins: list = field(default_factory=lambda: [[0, 0] for _ in BINS[:-1]])  # (right, entries) per bin


@dataclass
class Tally:
    """Sums over a group of files: labelled joints, body joints, files and verdicts."""

    files: int = 0
    right: int = 0
    total: int = 0
    body_files: int = 0
    humanoids: int = 0
    accepted: int = 0
    others: int = 0
    refused: int = 0

    def add(self, r: FileResult) -> None:
        self.files += 1
        if r.label["humanoid"]:
            self.humanoids += 1
            self.accepted += r.refused is None
            self.right += r.right
            self.total += len(CANONICAL_NAMES)
            self.body_files += r.body_right == len(BODY_NAMES)
        else:
            self.others += 1
            self.refused += r.refused is not None


def map_file(root: Path, label: dict, mapper: str):
    """(asset, FileResult) of one labelled file, or (None, reason) when it cannot be read."""
    try:
        asset = infuse.load(root / label["file"])
    except infuse.InfuseError as exc:
        return None, f"{label['file']}: cannot be read: {exc}"
    runs = []
    for _ in range(3):  # the best of three runs: steady on a busy machine
        t0 = time.process_time()
        try:
            mapping, refused = map_skeleton(asset, mapper=mapper), None
        except infuse.NotHumanoidError as exc:
            mapping, refused = None, exc.reason
        runs.append(time.process_time() - t0)
    r = FileResult(label, asset.skeleton.num_joints, min(runs), refused=refused)
    if label["humanoid"] and mapping is not None:
        alts = label.get("alternatives") or {}
        r.right, _, r.wrong = score(mapping.joints, label["mapping"], alts)
        r.body_right, _, _ = score(mapping.joints, label["mapping"], alts, BODY_NAMES)
        sure = [k for k in CANONICAL_NAMES if mapping.confidence.get(k, 0.0) >= CONFIDENT]
        wrong = {k for k, *_ in r.wrong}
        r.confident = (sum(k not in wrong for k in sure), len(sure))
        count_bins(mapping.confidence, wrong, r.bins)
    return asset, r


def count_bins(confidence: dict, wrong: set, bins: list) -> None:
    """Add each canonical entry to its confidence bin: [right, entries] per bin of :data:`BINS`."""
    for k in CANONICAL_NAMES:
        b = next(i for i in range(len(BINS) - 1) if confidence.get(k, 0.0) < BINS[i + 1])
        bins[b][0] += k not in wrong
        bins[b][1] += 1


def variant_results(asset, label: dict, mapper: str, bins: list, verbose: bool = False) -> list[tuple]:
    """(variant name, humanoid, right joints or 1 when refused, cpu seconds) of every generated
    variant of one skeleton, humanoid ones (scored on their joints) and non-humanoid ones (right
    when refused); the entries of the humanoid variants that were mapped are added to the
    confidence ``bins``."""
    out = []
    poses = sample_poses(asset)
    animated = animated_joint_names(asset)
    variants = (skeleton_variants.all_variants(asset.skeleton, poses, label)
                + skeleton_variants.non_humanoid_variants(asset.skeleton, poses, label))
    for v in variants:
        t0 = time.process_time()
        try:
            mapping = map_skeleton(v.skeleton, mapper=mapper, pose=v.poses,
                                   animated=v.translate(animated) if animated else None)
        except infuse.NotHumanoidError:
            mapping = None
        seconds = time.process_time() - t0
        if not v.humanoid:
            if verbose and mapping is not None:
                print(f"  variant {v.name} of {label['file']}: mapped, not refused", file=sys.stderr)
            out.append((v.name, False, int(mapping is None), seconds))
            continue
        right, _, wrong = score(mapping.joints if mapping else {}, v.mapping, v.alternatives)
        if mapping is not None:
            count_bins(mapping.confidence, {k for k, *_ in wrong}, bins)
        if verbose and wrong:
            print(f"  variant {v.name} of {label['file']}: {len(wrong)} wrong {wrong[:6]}", file=sys.stderr)
        out.append((v.name, True, right, seconds))
    return out


def _pct(a: int, b: int) -> str:
    return f"{100.0 * a / b:.1f}% ({a}/{b})" if b else "-"


def print_families(title: str, results: list[FileResult]) -> Tally:
    groups: dict[str, Tally] = {}
    overall = Tally()
    for r in results:
        groups.setdefault(family(r.label), Tally()).add(r)
        overall.add(r)
    print(f"\n### {title}: {overall.files} files\n")
    print("| family | files | labelled joints right | body joints right on | humanoids accepted | non-humanoids refused |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, t in sorted(groups.items()) + [("**all**", overall)]:
        body = f"{t.body_files}/{t.humanoids}" if t.humanoids else "-"
        acc = f"{t.accepted}/{t.humanoids}" if t.humanoids else "-"
        ref = f"{t.refused}/{t.others}" if t.others else "-"
        print(f"| {name} | {t.files} | {_pct(t.right, t.total)} | {body} | {acc} | {ref} |")
    return overall


def print_files(results: list[FileResult]) -> None:
    print("\n| file | joints | labelled joints | body joints | verdict | ms |")
    print("|---|---:|---:|---:|---|---:|")
    for r in results:
        n = len(CANONICAL_NAMES)
        if r.label["humanoid"]:
            cells = (f"{r.right / n:.3f}", f"{r.body_right}/{len(BODY_NAMES)}", "refused" if r.refused else "mapped")
        else:
            cells = ("", "", "refused" if r.refused else "NOT REFUSED")
        print(f"| {r.label['file']} | {r.joints} | {' | '.join(cells)} | {1000 * r.seconds:.1f} |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("filters", nargs="*", help="only label files whose path contains one of these")
    parser.add_argument("--mapper", default="heuristic")
    parser.add_argument("--sets", default="corpus,wild,variants", help="comma-separated: corpus, wild, variants")
    parser.add_argument("--files", action="store_true", help="also print the per-file tables")
    parser.add_argument("-v", "--verbose", action="store_true", help="list wrong predictions and refusals on stderr")
    args = parser.parse_args(argv)
    sets = [s.strip() for s in args.sets.split(",") if s.strip()]
    unknown = set(sets) - {"corpus", "wild", "variants"}
    if unknown:
        parser.error(f"unknown set(s): {', '.join(sorted(unknown))}")
    data_sets = [s for s in ("corpus", "wild") if s in sets] or ["corpus", "wild"]
    for name in data_sets:
        if not (ROOTS[name] / "labels").is_dir():
            print(f"{name} not found at {ROOTS[name]} (set INFUSE_{name.upper()})", file=sys.stderr)
            return 2
    failures: list[str] = []
    all_results: list[FileResult] = []
    variants: dict[str, list[int]] = {}  # humanoid variant -> [right joints, labelled joints]
    refusals: dict[str, list[int]] = {}  # non-humanoid variant -> [refused, variants]
    variant_seconds: list[float] = []
    variant_bins = [[0, 0] for _ in BINS[:-1]]
    seen: set = set()
    for name in data_sets:
        results = []
        for label in load_labels(ROOTS[name], args.filters):
            asset, r = map_file(ROOTS[name], label, args.mapper)
            if asset is None:
                failures.append(r)
                continue
            results.append(r)
            if args.verbose and (r.wrong or (r.refused and label["humanoid"])):
                print(f"  {label['file']}: {r.refused or r.wrong}", file=sys.stderr)
            key = (asset.skeleton.names, tuple(animated_joint_names(asset) or ()))
            if "variants" in sets and label["humanoid"] and key not in seen:
                seen.add(key)
                for kind, humanoid, right, seconds in variant_results(asset, label, args.mapper, variant_bins,
                                                                      args.verbose):
                    acc = (variants if humanoid else refusals).setdefault(kind, [0, 0])
                    acc[0] += right
                    acc[1] += len(CANONICAL_NAMES) if humanoid else 1
                    variant_seconds.append(seconds)
        if name in sets:
            print_families(name, results)
            if args.files:
                print_files(results)
        all_results += results
    if variants:
        print(f"\n### generated variants of {len(seen)} distinct humanoid skeletons\n")
        print("| variant | labelled joints right |")
        print("|---|---:|")
        for kind, (a, b) in variants.items():
            print(f"| {kind} | {_pct(a, b)} |")
        a, b = sum(v[0] for v in variants.values()), sum(v[1] for v in variants.values())
        print(f"| **all** | {_pct(a, b)} |")
    if refusals:
        print("\n| non-humanoid variant | refused |")
        print("|---|---:|")
        for kind, (a, b) in refusals.items():
            print(f"| {kind} | {_pct(a, b)} |")
    sure_right = sum(r.confident[0] for r in all_results)
    sure = sum(r.confident[1] for r in all_results)
    print(f"\ncalibration: of the entries given confidence >= {CONFIDENT}, {_pct(sure_right, sure)} are right\n")
    print("| confidence | labelled files: entries right | generated variants: entries right |")
    print("|---|---:|---:|")
    file_bins = [[sum(r.bins[i][k] for r in all_results) for k in (0, 1)] for i in range(len(BINS) - 1)]
    for i in range(len(BINS) - 1):
        band = (f"< {BINS[i + 1]:.1f}" if i == 0 else f">= {BINS[i]:.1f}" if i == len(BINS) - 2
                else f"{BINS[i]:.1f} - {BINS[i + 1]:.1f}")
        print(f"| {band} | {_pct(*file_bins[i])} | {_pct(*variant_bins[i])} |")
    flagged = BINS.index(FLAG)  # the bands below FLAG
    for title, bins in (("labelled files", file_bins), ("generated variants", variant_bins)):
        wrong = [b[1] - b[0] for b in bins]
        print(f"{title}: wrong entries given confidence < {FLAG}: {_pct(sum(wrong[:flagged]), sum(wrong))}")
    times = [r.seconds for r in all_results]
    near_70 = [r.seconds for r in all_results if 60 <= r.joints <= 80]
    if times:
        print(f"median time per skeleton: {1000 * statistics.median(times):.2f} ms CPU over {len(times)} files; "
              f"60-80 joints: {1000 * statistics.median(near_70 or [float('nan')]):.2f} ms over {len(near_70)}")
    if variant_seconds:
        print(f"median time per variant: {1000 * statistics.median(variant_seconds):.2f} ms CPU")
    for f in failures:
        print(f"FAILED {f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
