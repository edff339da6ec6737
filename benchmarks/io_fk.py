"""File loading + forward kinematics, in joint-frames per second: infuse beside bvhio and upc-pymotion.

Rows:
- load + FK of every Bandai BVH file (and of the other corpus BVH files) with infuse, bvhio and
  upc-pymotion, each peer checked against infuse's global joint positions on every file;
- load + FK of the SmartBody .skm corpus files (infuse only, through whichever installed reader
  handles .skm; no peer reads them);
- FK alone on a batch of clips that share one skeleton (``infuse.batch_fk``; pymotion's ``fk``
  on the same arrays).

The peers live in their own environment, ``benchmarks/.venv`` (``benchmarks/setup_peers.sh``, run
on first use); they are never dependencies of infuse. Ratios are against the fastest *correct*
peer: one whose positions agree with infuse's to ``TOLERANCE_M`` on every file of the row.

    .venv/bin/python benchmarks/io_fk.py [--passes 5] [--clock cpu|wall] [--no-peers] [--update-docs]

Times are CPU seconds of the timing process by default (every library here runs on one thread), so
other work on a shared machine does not count; ``--clock wall`` measures elapsed time instead.

``--update-docs`` rewrites the section "File loading and forward kinematics" of docs/performance.md.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import infuse
from infuse import Motion, quaternions as quat, registry
from infuse.conventions import UP_AXIS_ROTATIONS
from infuse.kinematics import batch_fk, motion_fk

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
PEER_PYTHON = HERE / ".venv" / "bin" / "python"
PEERS = ("upc-pymotion", "bvhio")
#: A peer is correct on a file when its global joint positions are within this of infuse's.
TOLERANCE_M = 1e-5
#: A peer pass slower than this (seconds) is not repeated.
PEER_BUDGET_S = 3.0
#: The FK-only batch: every Bandai clip, this many times over.
BATCH_COPIES = 4
SECTION = "## File loading and forward kinematics"


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{os.cpu_count()} cores ({cpu}), Python {platform.python_version()}, numpy {np.__version__}, "
            f"{platform.system()} {platform.release()}")


def corpus_sets() -> dict[str, list[Path]]:
    bvh = sorted(CORPUS.rglob("*.bvh"))
    return {
        "Bandai BVH": [p for p in bvh if "bandai" in p.parts],
        "other corpus BVH": [p for p in bvh if "bandai" not in p.parts],
        "SmartBody .skm": sorted(CORPUS.rglob("*.skm")),
    }


def infuse_load_fk(files: list[Path], keep_positions: bool, clock):
    """(seconds, joint-frames, {file: (positions in file units and axes, joint names)}) for one pass of load + FK."""
    total = 0.0
    joint_frames = 0
    positions: dict[str, tuple[np.ndarray, list[str]]] = {}
    for path in files:
        t0 = clock()
        asset = infuse.load(path)
        results = [motion_fk(m) for m in asset.motions.values()]
        total += clock() - t0
        joint_frames += sum(m.num_frames * m.skeleton.num_joints for m in asset.motions.values())
        if keep_positions and results and asset.format == "bvh":
            positions[str(path)] = (_to_file_frame(asset, results[0][1]), list(asset.skeleton.names))
    return total, joint_frames, positions


def _to_file_frame(asset, positions: np.ndarray) -> np.ndarray:
    """Core-frame metres back to the file's units and axes (to compare with a peer's raw output)."""
    back = quat.rotate(quat.conjugate(UP_AXIS_ROTATIONS[asset.source_up_axis]), positions)
    return back / asset.meta["unit_scale_m"]


def ensure_peers() -> bool:
    if not PEER_PYTHON.exists():
        print("setting up the peers' environment (benchmarks/setup_peers.sh) ...", file=sys.stderr)
        subprocess.run(["bash", str(HERE / "setup_peers.sh")], check=False, stdout=sys.stderr)
    return PEER_PYTHON.exists()


def run_peer(peer: str, files: list[Path], work: Path, save: bool, clock: str, batch: Path | None = None) -> dict:
    """One timed pass of ``peer`` over ``files`` in the peers' environment (positions saved when ``save``)."""
    out = work / peer
    out.mkdir(exist_ok=True)
    job = {"peer": peer, "files": [str(f) for f in files], "passes": 1, "out": str(out) if save else None,
           "batch": str(batch) if batch else None, "clock": clock}
    job_path = work / f"{peer}.json"
    job_path.write_text(json.dumps(job))
    run = subprocess.run([str(PEER_PYTHON), str(HERE / "peers" / "io_fk_worker.py"), str(job_path)], capture_output=True, text=True)
    if run.returncode != 0:
        return {"peer": peer, "failed": run.stderr.strip().splitlines()[-1:] or ["no output"]}
    result = json.loads(run.stdout)
    result["out"] = out
    return result


def peer_error(result: dict, files: list[Path], reference: dict, unit_scale: dict) -> float:
    """Largest distance in metres between a peer's joint positions and infuse's, over all files (inf if it failed one)."""
    worst = 0.0
    if result.get("failed") or result["errors"]:
        return float("inf")
    for k, path in enumerate(files):
        data = np.load(result["out"] / f"{result['peer']}-{k}.npz")
        ref, names = reference[str(path)]
        order = [list(data["names"]).index(n) for n in names] if list(data["names"]) != names else slice(None)
        got = data["positions"][:, order]
        if got.shape != ref.shape:
            return float("inf")
        worst = max(worst, float(np.abs(got - ref).max()) * unit_scale[str(path)])
    return worst


def batch_clips(files: list[Path]) -> list[Motion]:
    """Every Bandai clip on the first file's skeleton (they share names and hierarchy), BATCH_COPIES times."""
    motions = [next(iter(infuse.load(p).motions.values())) for p in files]
    skeleton = motions[0].skeleton
    clips = [Motion(skeleton, m.fps, m.local_rotations, m.root_translations, m.joint_translations, name=m.name)
             for m in motions if m.skeleton.names == skeleton.names]
    return clips * BATCH_COPIES


def rate(joint_frames: int, seconds: float) -> str:
    value = joint_frames / seconds
    return f"{value / 1e6:.2f} M" if value >= 1e6 else f"{value / 1e3:.0f} k"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--passes", type=int, default=5, help="timed passes per row; the best is kept")
    parser.add_argument("--no-peers", action="store_true", help="time infuse only")
    parser.add_argument("--clock", choices=["cpu", "wall"], default="cpu",
                        help="cpu: the process's CPU time, so other work on the machine does not count (default)")
    parser.add_argument("--update-docs", action="store_true", help="rewrite the section in docs/performance.md")
    args = parser.parse_args(argv)
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    if not (CORPUS / "labels").is_dir():
        print(f"io_fk: corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    sets = corpus_sets()
    peers_ok = not args.no_peers and ensure_peers()
    skm_reader = any(".skm" in r.extensions for r in registry.readers().values())
    rows: list[tuple] = []  # (set, library, files, joint-frames, seconds, jf/s, ratio, check)
    notes: list[str] = []
    batch_peers: dict[str, dict] = {}

    with tempfile.TemporaryDirectory(prefix="io_fk-") as tmp:
        work = Path(tmp)
        clips = batch_clips(sets["Bandai BVH"])
        skeleton = clips[0].skeleton
        batch_path = work / "batch.npz"
        translations = np.concatenate([c.local_translations() for c in clips])
        parents = np.array(skeleton.parents)
        parents[parents < 0] = 0  # pymotion marks the root as its own parent
        np.savez(batch_path, rotations_xyzw=np.concatenate([c.local_rotations for c in clips]),
                 translations=translations, parents_pymotion=parents)

        for name in ("Bandai BVH", "other corpus BVH", "SmartBody .skm"):
            files = sets[name]
            if not files:
                notes.append(f"{name}: no files in the corpus")
                continue
            if name == "SmartBody .skm" and not skm_reader:
                notes.append(f"{name}: skipped, no installed reader handles .skm")
                continue
            label = f"{name} load + FK"
            with_peers = peers_ok and name != "SmartBody .skm"
            if name == "SmartBody .skm":
                notes.append(f"{name}: no peer reads SmartBody motions")
            # Passes alternate between infuse and the peers, so a change in the machine's load
            # between them cannot favour either side; each keeps its best pass.
            infuse_best, jf, reference = float("inf"), 0, {}
            peer_runs: dict[str, list[dict]] = {peer: [] for peer in PEERS} if with_peers else {}
            for k in range(args.passes):
                seconds, jf, positions = infuse_load_fk(files, keep_positions=k == 0, clock=clock)
                reference = positions or reference
                infuse_best = min(infuse_best, seconds)
                for peer, runs in peer_runs.items():
                    if runs and (runs[-1].get("failed") or runs[-1]["seconds"] > PEER_BUDGET_S):
                        continue  # a failed or very slow peer is measured once
                    runs.append(run_peer(peer, files, work, save=k == 0, clock=args.clock,
                                         batch=batch_path if (name == "Bandai BVH" and k == 0) else None))
            infuse_row = [label, "infuse", len(files), jf, infuse_best, jf / infuse_best, None, "reference"]
            rows.append(infuse_row)
            if not with_peers:
                continue
            unit_scale = {str(p): infuse.load(p).meta["unit_scale_m"] for p in files}
            fastest = None
            for peer, runs in peer_runs.items():
                first = runs[0]
                if first.get("failed"):
                    rows.append([label, peer, len(files), jf, float("nan"), None, None, f"failed: {first['failed'][0][:60]}"])
                    continue
                seconds = min(r["seconds"] for r in runs)
                error = peer_error(first, files, reference, unit_scale)
                correct = error <= TOLERANCE_M
                check = f"max error {error:.1e} m" if np.isfinite(error) else f"wrong on {len(first['errors']) or 'some'} file(s)"
                rows.append([label, f"{peer} {first['version']}", len(files), jf, seconds, jf / seconds, None,
                             check + ("" if correct else " (incorrect)")])
                if correct and (fastest is None or seconds < fastest[1]):
                    fastest = (peer, seconds)
                if "batch_seconds" in first:
                    batch_peers[peer] = first
            if fastest:
                infuse_row[6] = fastest[1] / infuse_best
            else:
                notes.append(f"{name}: no peer was correct on every file, so no ratio")

        # FK alone on the batch.
        batch_jf = sum(c.num_frames for c in clips) * skeleton.num_joints
        best = float("inf")
        for _ in range(max(args.passes, 5)):
            t0 = clock()
            results = batch_fk(clips)
            best = min(best, clock() - t0)
        label = f"FK alone, batch of {len(clips)} clips"
        infuse_row = [label, "infuse batch_fk", len(clips), batch_jf, best, batch_jf / best, None, "target 4 M jf/s"]
        rows.append(infuse_row)
        reference = np.concatenate([p for _, p in results])
        for peer, result in batch_peers.items():
            got = np.load(result["out"] / f"{peer}-batch.npy")
            error = float(np.abs(got - reference).max())
            rows.append([label, f"{peer} {result['version']} fk", len(clips), batch_jf, result["batch_seconds"],
                         batch_jf / result["batch_seconds"], None, f"max error {error:.1e} m"])
            if error <= TOLERANCE_M:
                infuse_row[6] = result["batch_seconds"] / best

    table = format_table(rows)
    seconds = "CPU seconds of the timing process" if args.clock == "cpu" else "wall-clock seconds"
    header = (f"Machine: {machine()}. Best of {args.passes} passes, in {seconds}; "
              "joint-frames = frames x joints of every clip.")
    print(header)
    print(table)
    for note in notes:
        print(f"note: {note}")
    if args.update_docs:
        update_docs(header, table, notes)
    return 0


def format_table(rows) -> str:
    lines = ["| row | library | clips | joint-frames | seconds | joint-frames/s | x fastest correct peer | check |",
             "|---|---|---:|---:|---:|---:|---:|---|"]
    for label, lib, n, jf, sec, per_s, ratio, check in rows:
        per = rate(jf, sec) if np.isfinite(sec) else "-"
        lines.append(f"| {label} | {lib} | {n} | {jf:,} | {sec:.3f} | {per} | "
                     f"{'' if ratio is None else f'{ratio:.1f}x'} | {check} |")
    return "\n".join(lines)


def update_docs(header: str, table: str, notes: list[str]) -> None:
    path = REPO / "docs" / "performance.md"
    text = path.read_text() if path.exists() else "# Performance\n"
    body = (f"{SECTION}\n\nMeasured with `benchmarks/io_fk.py`; the peers run in their own environment "
            f"(`benchmarks/setup_peers.sh`), never as dependencies of infuse. {header}\n\n"
            "Each row loads every file and computes global joint positions for every frame. A peer counts "
            f"as correct when its positions agree with infuse's to {TOLERANCE_M:g} m on every file of the row, "
            "and the ratio compares infuse with the fastest correct peer (bvhio computes in float32 "
            "through pyglm, hence its micrometre differences). The FK-alone rows time the forward "
            f"kinematics of every Bandai clip, {BATCH_COPIES} times over, as one batch on one skeleton.\n\n"
            f"{table}\n")
    if notes:
        body += "\n" + "\n".join(f"- {n}" for n in notes) + "\n"
    if SECTION in text:
        start = text.index(SECTION)
        end = text.find("\n## ", start + len(SECTION))
        text = text[:start] + body + ("" if end < 0 else text[end:])
    else:
        text = text.rstrip("\n") + "\n\n" + body
    path.write_text(text)
    print(f"updated {path.relative_to(REPO)}")


if __name__ == "__main__":
    sys.exit(main())
