"""The peer side of benchmarks/io_fk.py: load + FK with bvhio and upc-pymotion, run in benchmarks/.venv.

Usage (io_fk.py calls it): ``python io_fk_worker.py JOB.json``. The job names the peer, the
files, the number of passes, the clock (``cpu`` or ``wall``), an output folder for the global
positions (one ``.npz`` per file, for the correctness check) and optionally an FK-only batch.
Prints one JSON document on stdout. Each peer is used the way its documentation shows: pymotion's
``BVH.load`` + ``get_data`` + ``fk``; bvhio's ``readAsHierarchy`` + ``loadPose`` per frame +
``PositionWorld`` per joint. It lives in a subfolder so ``make bench`` does not run it on its own.
"""
from __future__ import annotations

import json
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np


def pymotion_load_fk(path: str):
    from pymotion.io.bvh import BVH
    from pymotion.ops.skeleton_np import fk

    bvh = BVH()
    bvh.load(path)
    rots, pos, parents, _offsets, _, _ = bvh.get_data()
    # pos holds every joint's local translation per frame (offsets, or position channels), so
    # files with position channels on inner joints (Bandai) come out right.
    positions, _ = fk(rots, pos[:, 0], pos, parents)
    return positions, [str(n) for n in bvh.data["names"]]


def bvhio_load_fk(path: str):
    import bvhio

    root = bvhio.readAsHierarchy(path)
    joints = [j for j, _, _ in root.layout()]
    frames = len(root.Keyframes)
    out = np.empty((frames, len(joints), 3))
    for f in range(frames):
        root.loadPose(f)
        for k, joint in enumerate(joints):
            p = joint.PositionWorld
            out[f, k] = (p.x, p.y, p.z)
    return out, [j.Name for j in joints]


def pymotion_batch_fk(batch: dict):
    from pymotion.ops.skeleton_np import fk

    rots = batch["rotations_xyzw"][..., [3, 0, 1, 2]]  # pymotion stores quaternions w first
    positions, _ = fk(rots, batch["translations"][:, 0], batch["translations"], batch["parents_pymotion"])
    return positions


LOADERS = {"upc-pymotion": pymotion_load_fk, "bvhio": bvhio_load_fk}
BATCH_FK = {"upc-pymotion": pymotion_batch_fk}


def main(job_path: str) -> None:
    job = json.loads(Path(job_path).read_text())
    peer, files, passes = job["peer"], job["files"], job["passes"]
    clock = time.process_time if job.get("clock", "cpu") == "cpu" else time.perf_counter
    out_dir = Path(job["out"]) if job["out"] else None
    load_fk = LOADERS[peer]
    result: dict = {"peer": peer, "version": metadata.version(peer), "errors": {}}
    times = []
    for run in range(passes):
        total = 0.0
        for k, path in enumerate(files):
            t0 = clock()
            try:
                positions, names = load_fk(path)
            except Exception as exc:  # a peer failing on a file counts against its correctness
                result["errors"][path] = f"{type(exc).__name__}: {exc}"
                continue
            total += clock() - t0
            if run == 0 and out_dir is not None:
                np.savez(out_dir / f"{peer}-{k}.npz", positions=positions, names=np.array(names))
        times.append(total)
    result["seconds"] = min(times)
    result["passes"] = len(times)
    batch_path = job.get("batch")
    if batch_path and peer in BATCH_FK:
        batch = dict(np.load(batch_path))
        best = float("inf")
        for _ in range(job.get("batch_passes", 3)):
            t0 = clock()
            positions = BATCH_FK[peer](batch)
            best = min(best, clock() - t0)
        np.save(Path(job["out"] or ".") / f"{peer}-batch.npy", positions)
        result["batch_seconds"] = best
    json.dump(result, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])
