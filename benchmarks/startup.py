"""How long the ``infuse`` command takes to start, beside ``python -c pass``.

Rows (each a whole process, started from outside, timed from its start to its exit):
- ``python -c pass``: the interpreter alone, the floor under every other row;
- ``infuse --version`` and ``infuse --help``;
- ``infuse info`` on a small BVH file (a 28 KB Bandai clip);
- ``infuse batch`` rerun with nothing to do (2 characters x 2 motions, all done by a first run);
- ``infuse --help`` without the plugin index (a fresh installation: every command plugin is imported
  once).

Each row runs ``--runs`` times after one run that is not counted; the table gives the median and the
range of the wall clock and of the CPU seconds (user + system) the operating system charged the
process. The targets are for the wall clock on an idle machine; on a busy one the CPU seconds are
the closer figure.

    .venv/bin/python benchmarks/startup.py [--runs 9] [--update-docs]

``--update-docs`` rewrites the section "Start-up" of docs/performance.md.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
SECTION = "## Start-up"
PYTHON = sys.executable
SCRIPT = Path(PYTHON).with_name("infuse")  # the console script beside the interpreter, as a user runs it
INFUSE = [str(SCRIPT)] if SCRIPT.is_file() else [PYTHON, "-c", "from infuse.cli import run; run()"]
SMALL_BVH = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
BATCH_CHARACTERS = ["runxaway-models/Xbot.glb", "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"]
BATCH_MOTIONS = [SMALL_BVH, "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"]


def timed_run(command: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of one run of ``command``; its output is discarded, a failure raises."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    error = proc.stderr.read().decode(errors="replace")
    proc.stderr.close()
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(command)} exited with {proc.returncode}:\n{error}")
    return wall, usage.ru_utime + usage.ru_stime


def measure(command: list[str], runs: int, env: dict[str, str], before=None) -> tuple[list[float], list[float]]:
    """Wall and CPU seconds of ``runs`` runs after one uncounted run; ``before()`` runs before each."""
    walls, cpus = [], []
    for i in range(runs + 1):
        if before is not None:
            before()
        wall, cpu = timed_run(command, env)
        if i:
            walls.append(wall)
            cpus.append(cpu)
    return walls, cpus


def spread(values: list[float]) -> str:
    return f"{statistics.median(values):.3f} ({min(values):.3f} to {max(values):.3f})"


def machine() -> str:
    model = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores ({model}), Python {platform.python_version()}, {platform.system()} {platform.release()}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=9, help="counted runs per row")
    parser.add_argument("--update-docs", action="store_true", help="rewrite the section in docs/performance.md")
    args = parser.parse_args(argv)
    missing = [p for p in [SMALL_BVH, *BATCH_CHARACTERS, *BATCH_MOTIONS] if not (CORPUS / p).is_file()]
    if missing:
        print(f"corpus files missing under {CORPUS} (set INFUSE_CORPUS): {', '.join(missing)}", file=sys.stderr)
        return 2
    env = dict(os.environ)
    env.pop("INFUSE_DEBUG", None)
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "batch"
        batch = [*INFUSE, "batch", *(str(CORPUS / c) for c in BATCH_CHARACTERS),
                 *(a for m in BATCH_MOTIONS for a in ("--motions", str(CORPUS / m))), "-o", str(out), "--workers", "0"]
        timed_run(batch, env)  # the first run does the work; the counted ones find it done
        cold_cache = Path(tmp) / "cache"
        cold_env = dict(env, XDG_CACHE_HOME=str(cold_cache))

        def forget_commands() -> None:
            for index in (cold_cache / "infuse").glob("plugins-*.json"):
                index.unlink()

        rows = [
            ("`python -c pass`", [PYTHON, "-c", "pass"], None, env, None),
            ("`infuse --version`", [*INFUSE, "--version"], 0.3, env, None),
            ("`infuse --help`", [*INFUSE, "--help"], 0.3, env, None),
            ("`infuse info` on a 28 KB BVH", [*INFUSE, "info", str(CORPUS / SMALL_BVH)], 0.6, env, None),
            ("`infuse batch` rerun, nothing to do", batch, 1.0, env, None),
            ("`infuse --help`, command list not cached", [*INFUSE, "--help"], None, cold_env, forget_commands),
        ]
        results = []
        for label, command, target, row_env, before in rows:
            walls, cpus = measure(command, args.runs, row_env, before)
            results.append((label, target, walls, cpus))
            print(f"{label:45s} wall {spread(walls)} s   cpu {spread(cpus)} s", flush=True)
    load_after = os.getloadavg()[0]
    header = (f"Machine: {machine()}. Load average {load_before:.2f} before and {load_after:.2f} after. "
              f"Median of {args.runs} runs (range in brackets), one uncounted run first.")
    lines = ["| command | wall s | CPU s | target (idle machine) | met |", "|---|---:|---:|---:|---|"]
    for label, target, walls, cpus in results:
        met = "" if target is None else ("yes" if statistics.median(walls) < target else
                                         "CPU only" if statistics.median(cpus) < target else "no")
        lines.append(f"| {label} | {spread(walls)} | {spread(cpus)} | {'' if target is None else f'< {target:g}'} | {met} |")
    table = "\n".join(lines)
    print(header)
    print(table)
    if args.update_docs:
        update_docs(header, table)
    return 0


def update_docs(header: str, table: str) -> None:
    path = REPO / "docs" / "performance.md"
    text = path.read_text(encoding="utf-8") if path.exists() else "# Performance\n"
    body = (f"{SECTION}\n\nMeasured with `benchmarks/startup.py`: each command is a whole process started from outside "
            f"and timed to its exit, CPU seconds as the operating system charged it. {header}\n\n{table}\n\n"
            "- *met*: the median wall clock is under the target; *CPU only*: on this busy machine the wall clock "
            "was not, but the CPU seconds were. These commands run on one core and read files the system has "
            "cached, so on an idle machine their wall clock comes close to their CPU seconds.\n"
            "- `infuse` imports neither numpy, scipy nor any plugin to list its commands: their names and help lines "
            "come from an index of what every entry point offers, kept in the cache folder (see "
            "[Writing plugins](plugins.md#loaded-when-needed)). A command imports its own plugin only, and a file is "
            "read importing only the readers that claim its extension.\n"
            "- scipy is imported by the functions that use it (rotation vectors, Euler angles, Delaunay "
            "tessellation, FBX rotations), not by `infuse.quaternions` or a plugin at import.\n"
            "- The last row runs without the index (a fresh installation): every command plugin is imported once "
            "to learn its commands. After a plugin is installed or edited, only that plugin is.\n")
    if SECTION in text:
        start = text.index(SECTION)
        end = text.find("\n## ", start + len(SECTION))
        text = text[:start] + body + ("" if end < 0 else text[end:])
    else:
        text = text.rstrip("\n") + "\n\n" + body
    path.write_text(text, encoding="utf-8")
    print(f"updated {path.relative_to(REPO)}")


if __name__ == "__main__":
    sys.exit(main())
