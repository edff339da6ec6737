"""Batch throughput: clip-frames retargeted per second, on 1 and 2 pool workers and on Dask.

The job: every Bandai BVH clip of the corpus (both data sets) and every SmartBody locomotion clip
(MaleLocomotion and FemaleLocomotion ``.skm``) onto three characters (Mixamo's X Bot, SmartBody's
Utah skeleton, three.js's RobotExpressive), each result written to a fresh output tree (glb for
the glTF characters, bvh for Utah). A clip-frame is one source frame retargeted onto one character,
loading, mapping, planning and writing included.

Configurations: the local process pool with 1 and with 2 workers, and a ``dask.distributed``
LocalCluster of 2 worker processes (one thread each) on loopback, once as Dask starts its workers
and once without the ``MALLOC_TRIM_THRESHOLD_`` its nanny sets in their environment (with it, glibc
returns every large numpy temporary to the system at once, which costs CPU; see docs/batch.md).
Pools and clusters are started
and have run a first, smaller job (the first Bandai folder) before the clock starts, so their
workers have loaded the plugins and the characters. The configurations run in turn, ``--rounds``
times; the best round of each counts.

Columns: wall seconds and clip-frames per wall second; the CPU-bound time, the CPU seconds of the
busiest worker (each worker's units summed: the job's length had every worker a core to itself,
uneven units and per-worker character loading included) and clip-frames per CPU-bound second; the
CPU seconds of all units; the parallelism actually obtained (unit CPU seconds over wall seconds:
2.0 means two cores busy all along); the 1-minute load average when the run started. On a machine
shared with other work the wall figures fall with the share of the cores the job gets (the
parallelism column), while the CPU-bound figures hold; the speedup lines compare 2 workers to 1
both ways. Each figure is the best of its configuration's rounds.

Run: ``python benchmarks/batch.py [--rounds N]`` (corpus from ``INFUSE_CORPUS``).
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import multiprocessing
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from infuse_batch import run_batch
from infuse_batch import work

CORPUS = Path(os.environ.get("INFUSE_CORPUS", Path(__file__).resolve().parents[1].parent / "shared" / "corpus"))
MOTIONS = ["bandai/Bandai-Namco-Research-Motiondataset-1/data", "bandai/Bandai-Namco-Research-Motiondataset-2/data",
           "smartbody/behaviorsets/MaleLocomotion/motions", "smartbody/behaviorsets/FemaleLocomotion/motions"]
CHARACTERS = ["runxaway-models/Xbot.glb", "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk",
              "adibkn1-robot/RobotExpressive.glb"]


def pool(workers: int) -> cf.ProcessPoolExecutor:
    """A warm pool like the one ``run_batch`` starts: fork server with infuse imported, plugins loaded."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["infuse_batch.work"])
    executor = cf.ProcessPoolExecutor(workers, mp_context=context, initializer=work.warm)
    list(executor.map(time.sleep, [0.2] * workers * 2))  # every worker started and initialized
    return executor


def measure(name: str, scratch: Path, motions=MOTIONS, **backend) -> dict:
    out = scratch / name
    load = os.getloadavg()[0]
    result = run_batch([str(CORPUS / c) for c in CHARACTERS], motions=[str(CORPUS / m) for m in motions], out=out,
                       resume=False, progress=False, **backend)
    if not result.ok:
        for f in result.failures:
            print(f"  failed: {f.file}: {f.reason}", file=sys.stderr)
    shutil.rmtree(out)
    return {"name": name, "units": result.units, "clips": result.clips, "frames": result.frames, "wall": result.seconds,
            "cpu": result.cpu_seconds, "busiest": max(result.worker_cpu.values()), "load": load}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="runs of each configuration (the best counts)")
    args = parser.parse_args()
    if not (CORPUS / "labels").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    import dask
    import distributed

    scratch = Path(tempfile.mkdtemp(prefix="infuse-batch-bench-"))
    one, two = pool(1), pool(2)
    clusters, clients = [], []
    # The cluster without the variable starts first: a nanny also sets its variables in this
    # process's environment, which later workers would inherit.
    for trim in (None, "65536"):
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": trim}):
            clusters.append(distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                                     dashboard_address=None, protocol="tcp", silence_logs=40))
        clients.append(distributed.Client(clusters[-1], set_as_default=False))
        clients[-1].run(work.warm)
        seen = set(clients[-1].run(os.environ.get, "MALLOC_TRIM_THRESHOLD_").values())
        assert seen == {trim}, seen
    configs = [("pool, 1 worker", dict(executor=one)), ("pool, 2 workers", dict(executor=two)),
               ("dask, 2 workers", dict(cluster=clients[1])), ("dask, no malloc trim", dict(cluster=clients[0]))]
    best: dict[str, dict] = {}
    try:
        for name, backend in configs:
            measure("warm-up", scratch, MOTIONS[:1], **backend)
        for r in range(args.rounds):
            for name, backend in configs:
                row = measure(f"{name.replace(', ', '-').replace(' ', '')}-{r}", scratch, **backend)
                row["name"] = name
                print(f"round {r + 1}: {name:<16} {row['frames'] / row['wall']:8.0f} clip-frames/s wall, "
                      f"{row['frames'] / row['busiest']:8.0f} CPU-bound, parallelism {row['cpu'] / row['wall']:.2f}, "
                      f"load {row['load']:.1f}", file=sys.stderr)
                if name not in best:
                    best[name] = dict(row)
                for key in ("wall", "busiest", "cpu"):
                    if row[key] < best[name][key]:
                        best[name][key] = row[key]
                        if key == "wall":
                            best[name]["load"] = row["load"]
    finally:
        for c in clients + clusters:
            c.close()
        one.shutdown()
        two.shutdown()
        shutil.rmtree(scratch, ignore_errors=True)
    first = next(iter(best.values()))
    print(f"{first['clips']} clips ({first['frames']:,} clip-frames) in {first['units']} units; "
          f"{os.cpu_count()} cores; best of {args.rounds} rounds\n")
    print("| configuration | wall s | clip-frames/s | CPU-bound s | clip-frames/s CPU-bound | all units CPU s | "
          "parallelism | load at start |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for row in best.values():
        print(f"| {row['name']} | {row['wall']:.2f} | {row['frames'] / row['wall']:,.0f} | {row['busiest']:.2f} | "
              f"{row['frames'] / row['busiest']:,.0f} | {row['cpu']:.2f} | {row['cpu'] / row['wall']:.2f} | {row['load']:.1f} |")
    p1, p2 = best["pool, 1 worker"], best["pool, 2 workers"]
    print(f"\nspeedup 1 -> 2 pool workers (target 1.7x): {p1['wall'] / p2['wall']:.2f}x wall, "
          f"{p1['busiest'] / p2['busiest']:.2f}x CPU-bound")
    for name in ("dask, 2 workers", "dask, no malloc trim"):
        d = best[name]
        print(f"{name} over the 2-worker pool: {p2['wall'] / d['wall']:.2f}x wall, "
              f"{p2['busiest'] / d['busiest']:.2f}x CPU-bound")
    return 0


if __name__ == "__main__":
    sys.exit(main())
