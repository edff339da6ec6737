"""``run_batch``: the job's driver. It lists the work, leaves out what the output tree already holds,
streams units through a backend, records each finished unit in the manifest and sums up.

The driver never reads a motion or character file itself (workers do), so its memory does not
grow with the size of the files, only with their number (their paths and names).
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

from infuse.errors import UsageError
from infuse.progress import Progress

from . import backends, jobs
from .manifest import Manifest
from .work import Failure, UnitResult


@dataclass
class BatchResult:
    """What a batch did.

    - ``items``: (character, input) pairs in the job, an input being a motion file or the packs;
      ``skipped``: those already in the output tree from an earlier run.
    - ``written``: output files written; ``clips`` and ``frames``: clips retargeted and their
      source frames (clip-frames), counted once per character.
    - ``failures``: what was not produced, each with the file at fault and the reason.
    - ``empty``: motion files that hold no clip (nothing to retarget; not failures).
    - ``seconds``: wall time; ``cpu_seconds``: CPU time summed over the units, wherever they ran;
      ``worker_cpu``: the same per worker (host:process id).
    """

    out: Path
    items: int = 0
    skipped: int = 0
    units: int = 0
    written: int = 0
    clips: int = 0
    frames: int = 0
    failures: list[Failure] = field(default_factory=list)
    empty: list[str] = field(default_factory=list)
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    worker_cpu: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.failures

    @property
    def exit_code(self) -> int:
        """0 when everything was produced; else 2 when some input was malformed, 3 when the
        failed inputs were well formed but unusable (e.g. not a humanoid), 1 when only bugs failed."""
        codes = {f.exit_code for f in self.failures}
        for code in (2, 3):
            if code in codes:
                return code
        return 1 if codes else 0


def _as_list(value) -> list[str]:
    if value is None:
        return []
    if isinstance(value, (str, Path)):
        return [str(value)]
    return [str(v) for v in value]


def _packs(packs) -> tuple[tuple[str, ...], dict]:
    """Pack names as the workers will find them (folders made absolute) and each pack's version
    and analysis fingerprint."""
    from infuse.packs import load_pack

    names = [n.strip() for item in _as_list(packs) for n in item.split(",") if n.strip()]
    resolved = tuple(str(Path(n).resolve()) if Path(n).exists() else n for n in names)
    fingerprints = {}
    for name in resolved:
        pack = load_pack(name)
        fingerprints[pack.name] = f"{pack.version}:{pack.require_built()['fingerprint']}"
    return resolved, fingerprints


def _backend(workers, cluster, executor):
    if cluster is not None and executor is not None:
        raise UsageError("give a cluster or an executor, not both")
    if cluster is not None:
        return backends.Dask(client=cluster) if not isinstance(cluster, str) else backends.Dask(cluster)
    if executor is not None:
        return backends.Pool(executor=executor)
    if workers is not None and workers < 0:
        raise UsageError(f"workers must be 0 (this process) or more, got {workers}")
    if workers == 0:
        return backends.InProcess()
    return backends.Pool(workers)


def _lost(unit, exc: BaseException) -> UnitResult:
    """A unit whose worker never reported: every input it held failed."""
    reason = f"the worker running it failed: {type(exc).__name__}: {exc}"
    result = UnitResult(unit.pairs)
    if isinstance(unit, jobs.PackUnit):
        result.failures.append(Failure(unit.character.path, reason, 1))
    else:
        files = sorted({unit.motions[m].path for _, m in unit.todo})
        result.failures += [Failure(f, reason, 1) for f in files]
    return result


def run_batch(characters: str | Iterable[str], *, out: str | Path, motions: str | Iterable[str] | None = None,
              packs: str | Iterable[str] | None = None, workers: int | None = None, cluster=None, executor=None,
              format: str | None = None, mapper: str | None = None, retargeter: str | None = None,
              resume: bool = True, progress: bool = True) -> BatchResult:
    """Retarget every motion file onto every character, and/or infuse every character with packs.

    - ``characters``, ``motions``: files, folders (searched recursively) or globs.
    - ``packs``: pack names, folders or manifests ("a,b" or a list); one infusion cache per
      character (``OUT/CHARACTER/infusion.npz`` and ``.json``).
    - ``out``: the output tree, ``OUT/CHARACTER/MOTION.glb|bvh`` (a file of several clips gives
      a folder, one file per clip); ``format``: "glb" (the character with the clip, mesh and
      all) or "bvh"; by default glb for glTF characters and bvh for the others.
    - ``workers``: local process pool size (default: the cores); 0 runs in this process.
      ``cluster``: a Dask scheduler address ``tcp://HOST:PORT`` or a ``distributed.Client``.
      ``executor``: a ``concurrent.futures`` executor to run on instead.
    - ``resume``: skip what the output tree already holds (see :mod:`.manifest`).
    - ``progress``: a progress bar on stderr.

    Inputs that fail are listed in :attr:`BatchResult.failures`; the others complete.
    """
    start = time.perf_counter()
    out = Path(out).expanduser().resolve()
    if format is not None and format not in jobs.FORMATS:
        raise UsageError(f"format must be one of {', '.join(jobs.FORMATS)}, got {format!r}")
    motion_specs = _as_list(motions)
    if not motion_specs and not packs:
        raise UsageError("give motions to retarget, packs to infuse, or both")
    chars = jobs.character_sources(_as_list(characters))
    pack_names, fingerprints = _packs(packs) if packs else ((), {})
    settings = jobs.Settings(format, mapper, retargeter, pack_names)
    manifest = Manifest(out, resume=resume)
    result = BatchResult(out)
    units: list = []
    if motion_specs:
        files = jobs.motion_sources(motion_specs, out)
        result.items += len(chars) * len(files)
        units += jobs.motion_units(chars, files, lambda c, m: manifest.done(c, m, settings), settings, out)
    if pack_names:
        result.items += len(chars)
        units += jobs.pack_units(chars, lambda c, m: manifest.done(c, None, settings, fingerprints), settings, out,
                                 fingerprints)
    todo = sum(u.pairs for u in units)
    result.skipped = result.items - todo
    result.units = len(units)
    bar = Progress(todo, "batch", enabled=progress, unit="items", also=("clip-frames",))
    seen: set = set()
    backend = _backend(workers, cluster, executor) if units else None
    try:
        for unit, done in backends.stream(backend, units) if backend else ():
            if isinstance(done, BaseException):
                done = _lost(unit, done)
            manifest.record(done.done)
            for f in done.failures:
                if (f.file, f.reason, f.clip) not in seen:
                    seen.add((f.file, f.reason, f.clip))
                    result.failures.append(f)
            result.empty += done.empty
            result.written += done.written
            result.clips += done.clips
            result.frames += done.frames
            result.cpu_seconds += done.cpu
            result.worker_cpu[done.worker] = result.worker_cpu.get(done.worker, 0.0) + done.cpu
            bar.advance(unit.pairs, done.frames)
    finally:
        bar.close()
        if backend is not None:
            backend.close()
    result.empty = sorted(set(result.empty))
    result.seconds = time.perf_counter() - start
    return result


def summary(result: BatchResult, stream=None) -> None:
    """Print what a batch did and every failure (file, reason)."""
    stream = stream or sys.stdout
    rate = result.frames / result.seconds if result.seconds > 0 else 0.0
    print(f"{result.out}: wrote {result.written} files ({result.clips} clips, {result.frames:,} clip-frames) "
          f"in {result.seconds:.1f} s, {rate:,.0f} clip-frames/s; {result.skipped} of {result.items} items "
          f"already done", file=stream)
    if result.empty:
        print(f"{len(result.empty)} motion files hold no clip: {', '.join(result.empty)}", file=stream)
    if result.failures:
        print(f"{len(result.failures)} failures:", file=stream)
        for f in result.failures:
            clip = f" (clip {f.clip!r})" if f.clip else ""
            print(f"  {f.file}{clip}: {f.reason}", file=stream)
