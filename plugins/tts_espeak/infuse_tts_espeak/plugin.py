"""Registers the ``espeak`` TTS engine (entry point group ``infuse.tts``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import TTSEngine

from .engine import EspeakEngine


@hookimpl
def infuse_tts_engines():
    return [TTSEngine("espeak", EspeakEngine, "espeak-ng speech: pyttsx3 writes the WAV, libespeak-ng phoneme events time it",
                      ("voice", "rate", "volume", "library", "wav_writer"))]
