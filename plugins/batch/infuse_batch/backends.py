"""Where units run: in this process, on a local process pool, or on a Dask cluster, with a bounded
window of units in flight so that a job of any size holds only a few units' results at a time.

Every backend runs :func:`.work.run_unit` and hands back its :class:`~.work.UnitResult`; no
scheduling of our own happens here beyond keeping the window full.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
from typing import Iterable, Iterator

from infuse.errors import MissingFeatureError, UnusableInputError

from . import work

#: Units in flight per worker slot: one running, one waiting, so no worker idles between units.
WINDOW_PER_SLOT = 2
#: Seconds to wait for a first worker on a Dask scheduler that has none.
WORKER_WAIT = 60.0


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class InProcess:
    """Runs each unit when it is submitted, in this process (no parallelism; for debugging and tests)."""

    slots = 1

    def submit(self, unit) -> cf.Future:
        future: cf.Future = cf.Future()
        future.set_result(work.run_unit(unit))
        return future

    def wait(self, handles):
        return cf.wait(handles, return_when=cf.FIRST_COMPLETED)

    def result(self, handle):
        return handle.result()

    def close(self) -> None:
        pass


class Pool:
    """A local process pool (``workers`` processes, started by a fork server that has infuse
    imported, each loading the plugins once), or any ``concurrent.futures`` executor given."""

    def __init__(self, workers: int | None = None, executor: cf.Executor | None = None):
        self.workers = workers or (getattr(executor, "_max_workers", None) if executor else None) or cores()
        self.slots = WINDOW_PER_SLOT * self.workers
        self._own = executor is None
        self.executor = executor or self._start()

    def _start(self) -> cf.ProcessPoolExecutor:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["infuse_batch.work"])
        return cf.ProcessPoolExecutor(self.workers, mp_context=context, initializer=work.warm)

    def submit(self, unit) -> cf.Future:
        try:
            return self.executor.submit(work.run_unit, unit)
        except cf.process.BrokenProcessPool:
            if not self._own:
                raise
            # A worker died (its units are reported as failed); the rest of the job gets a new pool.
            self.executor.shutdown(wait=False, cancel_futures=True)
            self.executor = self._start()
            return self.executor.submit(work.run_unit, unit)

    def wait(self, handles):
        return cf.wait(handles, return_when=cf.FIRST_COMPLETED)

    def result(self, handle):
        return handle.result()

    def close(self) -> None:
        if self._own:
            self.executor.shutdown(wait=True)


class Dask:
    """An existing ``dask.distributed`` scheduler at ``address`` (``tcp://HOST:PORT``), or a
    ``distributed.Client`` given; one task per unit, as many in flight as twice its worker threads."""

    def __init__(self, address: str | None = None, client=None):
        try:
            import distributed
        except ImportError:
            raise MissingFeatureError(None, "--cluster needs dask.distributed: pip install 'infuse-anim-batch[dask]'") from None
        self._own = client is None
        if client is None:
            try:
                client = distributed.Client(address, timeout="20s", set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise UnusableInputError(address, f"cannot reach a Dask scheduler there: {exc}") from None
        self.client = client
        threads = sum(client.nthreads().values())
        if threads == 0:
            try:
                client.wait_for_workers(1, timeout=WORKER_WAIT)
            except TimeoutError:
                if self._own:
                    client.close()
                raise UnusableInputError(address, f"no Dask worker joined the scheduler in {WORKER_WAIT:g} s") from None
            threads = sum(client.nthreads().values())
        self.slots = WINDOW_PER_SLOT * max(threads, 1)
        self._finished = distributed.as_completed(loop=client.loop, raise_errors=False)

    def submit(self, unit):
        future = self.client.submit(work.run_unit, unit, pure=False)
        self._finished.add(future)
        return future

    def wait(self, handles):
        done = next(self._finished)
        return {done}, [h for h in handles if h is not done]

    def result(self, handle):
        try:
            return handle.result()
        finally:
            handle.release()

    def close(self) -> None:
        if self._own:
            self.client.close()


def stream(backend, units: Iterable) -> Iterator[tuple[object, object]]:
    """Run ``units`` on ``backend``, at most ``backend.slots`` at a time; yield ``(unit, result)``
    as each finishes, ``result`` being a :class:`~.work.UnitResult` or the exception that lost it
    (a worker that died, a cluster that went away)."""
    pending = iter(units)
    inflight: dict = {}

    def fill() -> None:
        while len(inflight) < backend.slots:
            unit = next(pending, None)
            if unit is None:
                return
            inflight[backend.submit(unit)] = unit

    fill()
    while inflight:
        done, _ = backend.wait(list(inflight))
        for handle in done:
            unit = inflight.pop(handle)
            try:
                result = backend.result(handle)
            except Exception as exc:
                result = exc
            yield unit, result
        fill()
