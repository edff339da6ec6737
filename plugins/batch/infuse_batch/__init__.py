"""infuse-anim-batch: many characters × many motion clips or behaviour packs, on local processes or Dask.

::

    from infuse_batch import run_batch
    result = run_batch(["cast/"], motions="mocap/", out="out/", workers=4)   # or cluster="tcp://host:8786"
    for f in result.failures:
        print(f.file, f.reason)

See :func:`run_batch` and ``docs/batch.md``.
"""
from __future__ import annotations

from .run import BatchResult, run_batch, summary
from .work import Failure

__all__ = ["BatchResult", "Failure", "run_batch", "summary"]
