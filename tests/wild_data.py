"""Where the rigs of unseen families are, and their labels. One setting: env ``INFUSE_WILD`` (default
``../shared/wild`` relative to the repository root), read like ``INFUSE_CORPUS`` (see :mod:`corpus_data`):
tests may skip when it is absent, except under ``CI=true``, where that is a failure."""
from __future__ import annotations

import json
import os
from functools import lru_cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
WILD = Path(os.environ.get("INFUSE_WILD", REPO.parent / "shared" / "wild")).resolve()
UNDER_CI = os.environ.get("CI", "").lower() == "true"


def wild_available() -> bool:
    return (WILD / "labels").is_dir()


def require_wild() -> Path:
    """The wild root; fails under CI and skips elsewhere when it is missing."""
    if not wild_available():
        message = f"wild rigs not found at {WILD} (set INFUSE_WILD)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return WILD


@lru_cache(maxsize=1)
def wild_labels() -> tuple[dict, ...]:
    """Every label document of the wild rigs, sorted by file; empty when the folder is missing."""
    if not wild_available():
        return ()
    return tuple(json.loads(p.read_text()) for p in sorted((WILD / "labels").glob("*.json")))


def wild_file(relative: str) -> Path:
    """A wild rig by its path relative to the wild root (skips/fails when absent)."""
    path = require_wild() / relative
    if not path.exists():
        pytest.fail(f"wild rig missing: {relative}")
    return path
