"""Every BML document of the corpus through parse and schedule.

Prints, per source folder: documents parsed and scheduled without a warning, with warnings, and invalid
(refused with a clear error); the time taken; and how many of the expected timings stated in the
OpenBMLParser documents' header comments the scheduler reproduces.

    python benchmarks/bml_corpus.py [--verbose]

The corpus is read from INFUSE_CORPUS (default ../shared/corpus from the repository root).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from pathlib import Path

from infuse.bml import Scheduler, parse_bml_file
from infuse.bml.expectations import check, expectations_from_comments
from infuse.errors import InputError

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()


def run(corpus: Path, verbose: bool = False) -> dict:
    """Counts per folder, oracle outcomes and timings; also printed."""
    files = sorted((corpus / "bml").glob("*/*.xml"))
    if not files:
        raise SystemExit(f"no BML documents under {corpus / 'bml'} (set INFUSE_CORPUS)")
    counts: dict[str, Counter] = {}
    outcomes = []
    started = time.perf_counter()
    for path in files:
        folder = path.parent.name
        tally = counts.setdefault(folder, Counter())
        try:
            document = parse_bml_file(path)
        except InputError as exc:
            tally["invalid"] += 1
            if verbose:
                print(f"  invalid  {exc}")
            continue
        scheduler = Scheduler()
        records = scheduler.submit(document)
        scheduler.flush()
        warnings = [e for e in scheduler.feedback.log if e.kind == "warningFeedback"]
        tally["warnings" if warnings else "ok"] += 1
        tally["behaviours"] += sum(len(r.activations) for r in records)
        if verbose:
            for w in warnings:
                print(f"  warning  {folder}/{path.name}: {w.id} {w.type}: {w.description}")
        if folder == "openbmlparser":
            expectations = expectations_from_comments(document.comments)
            outcomes += [(path.name, o) for o in check(expectations, document.blocks[0], records[0])]
    elapsed = time.perf_counter() - started

    print(f"{'folder':<15}{'documents':>10}{'ok':>6}{'warnings':>10}{'invalid':>9}{'behaviours':>12}")
    for folder, tally in sorted(counts.items()):
        total = tally["ok"] + tally["warnings"] + tally["invalid"]
        print(f"{folder:<15}{total:>10}{tally['ok']:>6}{tally['warnings']:>10}{tally['invalid']:>9}{tally['behaviours']:>12}")
    print(f"{len(files)} documents parsed and scheduled in {elapsed * 1000:.0f} ms "
          f"({elapsed / len(files) * 1000:.2f} ms per document)")

    status = Counter(o.status for _, o in outcomes)
    checkable = status["matched"] + status["mismatched"]
    print(f"OpenBMLParser header expectations: {len(outcomes)} stated, {status['matched']} matched, "
          f"{status['mismatched']} not matched, {status['conflict']} contradict their own document")
    if checkable:
        print(f"share matched: {status['matched'] / checkable:.1%} of those consistent with their document "
              f"({status['matched'] / len(outcomes):.1%} of all)")
    for name, o in outcomes:
        if o.status != "matched":
            print(f"  {o.status:<10} {name}: {o.expectation.text!r}: {o.detail}")
    return {"counts": counts, "outcomes": outcomes, "seconds": elapsed}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--verbose", action="store_true", help="print every warning and error")
    args = parser.parse_args(argv)
    run(CORPUS, args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
