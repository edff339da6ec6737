"""espeak-ng for the tests that synthesize real speech: required under CI, a skip elsewhere when missing."""
from __future__ import annotations

import pytest

from corpus_data import UNDER_CI


def require_espeak() -> None:
    """Fail (under ``CI=true``) or skip the calling test when the espeak-ng library cannot be loaded."""
    try:
        from infuse_tts_espeak.library import espeak
        espeak()
    except Exception as exc:  # espeak-ng itself missing on this machine
        if UNDER_CI:
            pytest.fail(f"espeak-ng is required under CI: {exc}")
        pytest.skip(f"espeak-ng not available: {exc}")
