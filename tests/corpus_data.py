"""Where the test corpus is, and its labels. One setting: env ``INFUSE_CORPUS`` (default ``../shared/corpus``
relative to the repository root). Tests may skip when it is absent, except under ``CI=true``."""
from __future__ import annotations

import json
import os
from functools import lru_cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
UNDER_CI = os.environ.get("CI", "").lower() == "true"


def corpus_available() -> bool:
    return (CORPUS / "labels").is_dir()


def require_corpus() -> Path:
    """The corpus root; fails under CI and skips elsewhere when it is missing."""
    if not corpus_available():
        message = f"corpus not found at {CORPUS} (set INFUSE_CORPUS)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return CORPUS


@lru_cache(maxsize=1)
def labels() -> tuple[dict, ...]:
    """Every label document, sorted by file; empty when the corpus is missing."""
    if not corpus_available():
        return ()
    docs = [json.loads(p.read_text()) for p in sorted((CORPUS / "labels").glob("*.json"))]
    return tuple(docs)


def corpus_file(relative: str) -> Path:
    """A corpus file by its path relative to the corpus root (skips/fails when absent)."""
    path = require_corpus() / relative
    if not path.exists():
        pytest.fail(f"corpus file missing: {relative}")
    return path
