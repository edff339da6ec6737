"""Registers the ``file`` TTS engine (entry point group ``infuse.tts``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import TTSEngine

from .engine import FileEngine


@hookimpl
def infuse_tts_engines():
    return [TTSEngine("file", FileEngine, "recorded speech: a WAV plus a phoneme timing file (TextGrid, MFA JSON, JSON, TSV)",
                      ("audio", "timing", "alphabet"))]
