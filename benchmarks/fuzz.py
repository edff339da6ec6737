"""The long fuzz run: mutated files of every format through infuse, counted by outcome class.

Seeds are the small files built by the tests' builders and the files of the corpus (``INFUSE_CORPUS``)
and the wild set (``INFUSE_WILD``) read in place; each case is one seed after one to four random
mutations (see ``tests/fuzz_support.py``), run in a child process with a memory and a time limit.
Prints cases per format and outcome class (typed error, load, untyped, hang, memory, non-finite),
then each distinct finding once with a reproducer's seed and operations. Exits 1 when any case ended
in a bad class.

    python benchmarks/fuzz.py                      # 20,000 cases, seed 0, two workers
    python benchmarks/fuzz.py --cases 2000 --formats bvh,glb --seed 7
"""
from __future__ import annotations

import argparse
import os
import random
import sys
import threading
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

from fuzz_support import BAD, FORMATS, OUTCOMES, Worker, built_seeds, corpus_seeds, mutate, random_ops  # noqa: E402

CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
WILD = Path(os.environ.get("INFUSE_WILD", REPO.parent / "shared" / "wild")).resolve()


def seeds_by_format(formats: list[str], max_seed_bytes: int) -> dict:
    roots = [root for root in (CORPUS, WILD) if root.is_dir()]
    table = {fmt: built_seeds(fmt) + corpus_seeds(fmt, roots, max_seed_bytes) for fmt in formats}
    missing = [fmt for fmt, seeds in table.items() if not seeds]
    if missing:
        raise SystemExit(f"no seeds for {', '.join(missing)} (set INFUSE_CORPUS)")
    return table


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--formats", default=",".join(FORMATS), help="comma-separated (default: all)")
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds a case may take")
    parser.add_argument("--memory-mb", type=int, default=1024, help="address space a case may add, MiB")
    parser.add_argument("--max-seed-bytes", type=int, default=300_000)
    args = parser.parse_args(argv)

    formats = args.formats.split(",")
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown:
        parser.error(f"unknown formats {unknown}; known: {', '.join(FORMATS)}")
    seeds = seeds_by_format(formats, args.max_seed_bytes)
    print("seeds: " + ", ".join(f"{fmt} {len(s)}" for fmt, s in seeds.items()))

    counts: dict[str, Counter] = defaultdict(Counter)
    findings: dict[tuple, list] = {}
    seconds: Counter = Counter()
    lock = threading.Lock()
    local = threading.local()
    workers: list[Worker] = []

    def one(index: int) -> None:
        if not hasattr(local, "worker"):
            local.worker = Worker(timeout_s=args.timeout, memory_bytes=args.memory_mb << 20)
            with lock:
                workers.append(local.worker)
        fmt = formats[index % len(formats)]
        rng = random.Random(f"{args.seed}:{index}")
        seed = rng.choice(seeds[fmt])
        ops = random_ops(rng, FORMATS[fmt].text)
        started = time.perf_counter()
        outcome = local.worker.run(fmt, seed, mutate(seed.data, ops))
        with lock:
            counts[fmt][outcome.kind] += 1
            seconds[fmt] += time.perf_counter() - started
            if outcome.kind in BAD:
                signature = (fmt, outcome.kind, outcome.detail.split(":")[0] if outcome.kind == "hang" else outcome.detail[-90:])
                if signature not in findings:  # shown as found, so a long run can be acted on before it ends
                    print(f"  found: {outcome.kind} [{fmt}] {outcome.detail[:300]} (case {index})", flush=True)
                findings.setdefault(signature, []).append((index, seed.label, ops, outcome.detail))

    started = time.perf_counter()
    with ThreadPoolExecutor(args.jobs) as pool:
        for done, _ in enumerate(pool.map(one, range(args.cases)), start=1):
            if done % 1000 == 0:
                print(f"  {done} cases, {time.perf_counter() - started:.0f} s", flush=True)
    for worker in workers:
        worker.close()

    print(f"\n{'format':<9}{'cases':>7}" + "".join(f"{k:>13}" for k in OUTCOMES) + f"{'ms/case':>9}")
    total = Counter()
    for fmt in formats:
        c = counts[fmt]
        n = sum(c.values())
        total.update(c)
        print(f"{fmt:<9}{n:>7}" + "".join(f"{c[k]:>13}" for k in OUTCOMES) + f"{1000 * seconds[fmt] / max(n, 1):>9.1f}")
    print(f"{'total':<9}{sum(total.values()):>7}" + "".join(f"{total[k]:>13}" for k in OUTCOMES))
    print(f"{time.perf_counter() - started:.0f} s with {args.jobs} workers")
    for (fmt, kind, _), cases in sorted(findings.items()):
        index, label, ops, detail = cases[0]
        print(f"\n{kind} x{len(cases)} [{fmt}] {detail}\n  reproduce: --seed {args.seed}, case {index}, seed file {label}, ops {ops}")
    return 1 if any(total[k] for k in BAD) else 0


if __name__ == "__main__":
    sys.exit(main())
