"""Speech in a scene: one TTS synthesis per utterance, shared by the scheduler (timing, marks) and the
realizer (lip sync, audio); and a character's utterances mixed into one WAV that plays with its clip.

:class:`SpeechCache` is the scheduler's speech timer. It synthesizes each distinct text once (marks as
SSML ``<mark>``), keeps the :class:`~infuse.speech.Utterance` and passes its key with the timing
(``details["utterance"]``), so the activation the realizer gets leads back to the very audio that was
timed. When no TTS engine can run (espeak-ng missing), it times speech from the text instead and says so
once (:attr:`SpeechCache.unavailable`).
"""
from __future__ import annotations

import time
import wave
from pathlib import Path
from typing import Callable
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..atomic import atomic_path
from ..bml import EstimatedSpeechTimer, SpeechTiming
from ..bml.speech import mark_times
from ..errors import InputError, MissingFeatureError, UsageError
from ..speech import Utterance, tts_engine


def speech_markup(text: str, marks) -> str:
    """``text`` with each (mark id, character offset) of ``marks`` written as ``<mark name="..."/>`` (escaped);
    the text itself when there are no marks."""
    if not marks:
        return text
    pieces, last = [], 0
    for mark, offset in sorted(marks, key=lambda m: m[1]):
        pieces.append(escape(text[last:offset]) + f"<mark name={quoteattr(mark)}/>")
        last = offset
    return "".join(pieces) + escape(text[last:])


class SpeechCache:
    """Times speech by synthesizing it, once per (text, marks, voice); see the module doc.

    ``engine``: a TTS engine name (``"espeak"``, default) or an engine object (``synthesize(text)``);
    ``settings``: the engine's settings; ``voice_of``: ``() -> voice`` of the character being scheduled
    (None: the engine's default); ``warn``: called once with a message when speech falls back to estimates.
    """

    def __init__(self, engine="espeak", settings: dict | None = None, voice_of: Callable[[], str | None] | None = None,
                 warn: Callable[[str], None] | None = None):
        self._engine_spec = engine
        self._settings = dict(settings or {})
        self._engines: dict = {}
        self._voice_of = voice_of or (lambda: None)
        self._warn = warn or (lambda message: None)
        self._keys: dict[tuple, int] = {}
        self.utterances: list[Utterance] = []
        self.unavailable: str | None = None if engine is not None else "no TTS engine was given"
        self.estimate = EstimatedSpeechTimer()
        self.synthesis_s = 0.0  # CPU seconds this process spent synthesizing

    def engine(self, voice: str | None):
        """The engine for ``voice`` (built once per voice)."""
        if not isinstance(self._engine_spec, str):
            return self._engine_spec
        if voice not in self._engines:
            settings = dict(self._settings)
            if voice:
                settings["voice"] = voice
            self._engines[voice] = tts_engine(self._engine_spec, **settings)
        return self._engines[voice]

    def time_speech(self, text, marks, voice=None, language=None) -> SpeechTiming:
        if not text.strip() or self.unavailable:
            return self.estimate.time_speech(text, marks, voice, language)
        voice = voice or self._voice_of()
        key = (text, tuple(marks), voice)
        if key not in self._keys:
            markup = speech_markup(text, marks)
            started = time.process_time()
            try:
                try:
                    utterance = self.engine(voice).synthesize(markup)
                except InputError as exc:
                    default = self._voice_of()
                    if exc.place != "voice" or voice == default:
                        raise
                    # another realizer's voice name (SmartBody's, MaryTTS'): the character's own voice speaks
                    self._warn(f"voice {voice!r} is unknown to the TTS engine; the {'default' if default is None else repr(default)} voice speaks")
                    utterance = self.engine(default).synthesize(markup)
            except MissingFeatureError as exc:  # espeak-ng (or the engine's extra) is not installed
                self.unavailable = str(exc)
                self._warn(f"speech is timed from its text, without audio or lip sync: {exc}")
                return self.estimate.time_speech(text, marks, voice, language)
            finally:
                self.synthesis_s += time.process_time() - started
            self._keys[key] = len(self.utterances)
            self.utterances.append(utterance)
        index = self._keys[key]
        utterance = self.utterances[index]
        details = {"phonemes": [list(p) for p in utterance.phonemes], "words": [list(w) for w in utterance.words],
                   "utterance": index}
        return SpeechTiming(float(utterance.duration_s), mark_times(text, marks, utterance),
                            getattr(utterance, "engine", "") or "tts", details)

    def release(self, indices) -> None:
        """Let the utterances at ``indices`` go (a scene that runs for hours): their entries become None and
        their texts are synthesized anew if they are spoken again."""
        released = {int(i) for i in indices if 0 <= int(i) < len(self.utterances)}
        for i in released:
            self.utterances[i] = None
        self._keys = {key: i for key, i in self._keys.items() if i not in released}

    def utterance(self, parameters: dict) -> Utterance | None:
        """The utterance a ``<speech>`` activation's ``parameters`` were timed with, or None (estimated)."""
        index = (parameters.get("tts") or {}).get("utterance")
        return self.utterances[index] if isinstance(index, int) and 0 <= index < len(self.utterances) else None


def utterance_samples(utterance: Utterance) -> tuple[np.ndarray, int]:
    """Mono int16 samples and the sample rate of an utterance (its samples, else its WAV file)."""
    if utterance.samples is not None and utterance.sample_rate:
        return np.asarray(utterance.samples, dtype=np.int16).reshape(-1), int(utterance.sample_rate)
    if utterance.wav_path is not None:
        return read_wav(utterance.wav_path)
    raise UsageError(f"the utterance {utterance.text[:40]!r} carries no audio")


def read_wav(path: str | Path) -> tuple[np.ndarray, int]:
    """Mono int16 samples (the first channel) and the rate of a 16-bit PCM WAV file."""
    with wave.open(str(path), "rb") as f:
        if f.getsampwidth() != 2:
            raise UsageError(f"{path}: only 16-bit PCM WAV files are mixed")
        data = np.frombuffer(f.readframes(f.getnframes()), dtype="<i2")
        return data.reshape(-1, f.getnchannels())[:, 0].astype(np.int16), f.getframerate()


def mix(pieces, duration_s: float, fade_s: float = 0.01) -> tuple[np.ndarray, int]:
    """One int16 track of ``duration_s`` seconds holding ``pieces``: (start_s, stop_s or None, samples, rate).

    The track takes the first piece's rate (others are resampled linearly); a piece cut by ``stop_s``
    (an interrupted utterance) fades out over ``fade_s``; overlaps add, clipped to the int16 range.
    """
    rate = int(pieces[0][3]) if pieces else 22050
    track = np.zeros(max(int(round(duration_s * rate)), 0), dtype=np.float64)
    for start_s, stop_s, samples, piece_rate in pieces:
        x = np.asarray(samples, dtype=np.float64)
        if piece_rate != rate:
            positions = np.arange(int(len(x) * rate / piece_rate)) * (piece_rate / rate)
            x = np.interp(positions, np.arange(len(x)), x)
        if stop_s is not None:
            keep = max(int(round((stop_s - start_s) * rate)), 0)
            if keep < len(x):
                x = x[:keep].copy()
                n = min(int(fade_s * rate), len(x))
                x[len(x) - n:] *= np.linspace(1.0, 0.0, n)
        first = int(round(start_s * rate))
        if first < 0:  # started before the scene's time 0: only its tail is heard
            x, first = x[-first:], 0
        x = x[:max(len(track) - first, 0)]
        track[first:first + len(x)] += x
    np.rint(track, out=track)
    np.clip(track, -32768, 32767, out=track)
    return track.astype(np.int16), rate


def write_wav(path: str | Path, samples: np.ndarray, rate: int) -> Path:
    """Write mono int16 ``samples`` at ``rate`` Hz as a WAV file, atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        with wave.open(str(tmp), "wb") as f:
            f.setnchannels(1)
            f.setsampwidth(2)
            f.setframerate(int(rate))
            f.writeframes(np.asarray(samples, dtype="<i2").tobytes())
    return path
