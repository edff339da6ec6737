"""The ``espeak`` TTS engine: text -> WAV + phoneme, word and mark timings that align with it.

Two passes over the same text with the same voice, rate and volume, both at once and each from a
freshly initialised libespeak-ng:

- pyttsx3 (driver ``espeak``) writes the WAV, in a child process (:mod:`.pyttsx3_writer`);
- libespeak-ng through ctypes (:mod:`.library`) synthesizes again with phoneme, word and mark
  events, which give the timings: in this process if it has not synthesized anything yet, else in
  a fresh child process (:mod:`.isolated`).

Both use the same library from the same fresh state, so the audio is the same; the engine checks
that sample for sample and records the outcome in ``Utterance.meta["alignment"]``. A pyttsx3 WAV
that stops short of the timed audio (its driver can drop the last block) is written again; were they
still to differ, the WAV is rewritten from the timing pass's audio, with a warning, so the timings
always belong to the WAV next to them. ``wav_writer="libespeak"`` skips
pyttsx3 and writes that audio directly; without a WAV path the samples and timings come from one
in-process synthesis.
"""
from __future__ import annotations

import warnings
import wave
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from infuse.atomic import atomic_path
from infuse.errors import InputError, MissingFeatureError, UnusableInputError, UsageError
from infuse.speech import SILENCE, Utterance, check_speech_text, parse_speech_markup

from . import isolated, pyttsx3_writer
from . import library as espeak_library
from .timeline import build_timeline

WAV_WRITERS = ("pyttsx3", "libespeak")
#: pyttsx3's espeak driver can drop the last block of audio (when the end-of-message event arrives in the
#: same callback as that block); a WAV that is a strict prefix of the timed audio is asked for again.
PYTTSX3_ATTEMPTS = 3


def write_wav(path: str | Path, samples: np.ndarray, sample_rate: int) -> None:
    """Mono 16-bit PCM WAV."""
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1)
        f.setsampwidth(2)
        f.setframerate(int(sample_rate))
        f.writeframes(np.ascontiguousarray(samples, dtype="<i2").tobytes())


def read_wav_samples(path: str | Path) -> tuple[np.ndarray, int]:
    """Mono 16-bit samples and the sample rate of a WAV written by pyttsx3."""
    with wave.open(str(path), "rb") as f:
        if f.getnchannels() != 1 or f.getsampwidth() != 2:
            raise UnusableInputError(path, f"expected mono 16-bit audio, got {f.getnchannels()} channels of {8 * f.getsampwidth()} bits")
        return np.frombuffer(f.readframes(f.getnframes()), dtype="<i2").astype(np.int16), f.getframerate()


@contextmanager
def _as_infuse_errors():
    """libespeak-ng's own errors as infuse errors (exit codes 2 and 3)."""
    try:
        yield
    except espeak_library.LibraryMissing as exc:
        raise MissingFeatureError(None, str(exc)) from None
    except espeak_library.BadSetting as exc:
        raise InputError(None, exc.place, str(exc)) from None
    except espeak_library.EspeakError as exc:
        raise UnusableInputError(None, str(exc)) from None


class EspeakEngine:
    """espeak-ng speech.

    - ``voice``: an espeak-ng voice name ("en", "en-us", "de"...; ``espeak-ng --voices`` lists them).
    - ``rate``: words per minute, 80..450 (espeak-ng's normal is 175).
    - ``volume``: pyttsx3's scale, 0..2 (1 normal).
    - ``library``: the libespeak-ng file (default: ``$INFUSE_ESPEAK_LIBRARY`` or the system's).
    - ``wav_writer``: "pyttsx3" (default) or "libespeak".
    - ``timeout_s``: how long to wait for each synthesis process (default grows with the text).
    """

    name = "espeak"

    def __init__(self, voice: str = "en", rate: int = 175, volume: float = 1.0, library: str | None = None,
                 wav_writer: str = "pyttsx3", timeout_s: float | None = None):
        if wav_writer not in WAV_WRITERS:
            raise UsageError(f"wav_writer must be one of {', '.join(WAV_WRITERS)}, not {wav_writer!r}")
        if not 0.0 <= float(volume) <= 2.0:
            raise InputError(None, "volume", f"volume {volume} is outside 0..2")
        if not _rate_ok(rate):
            raise InputError(None, "rate", f"speech rate {rate} words/min is outside {espeak_library.RATE_MINIMUM}..{espeak_library.RATE_MAXIMUM}")
        self.voice = str(voice)
        self.rate = int(rate)
        self.volume = float(volume)
        self.library = library
        self.wav_writer = wav_writer
        self.timeout_s = timeout_s

    def synthesize(self, text: str, wav_path: str | Path | None = None) -> Utterance:
        """Speak ``text`` (sync marks allowed, see :func:`infuse.speech.parse_speech_markup`).

        With ``wav_path`` the WAV is written there (atomically) and the utterance refers to it; without,
        the utterance carries the samples only. Raises :class:`InputError` for empty text, characters
        no voice can pronounce or an unknown voice, :class:`MissingFeatureError` when espeak-ng or
        pyttsx3 is missing.
        """
        text = check_speech_text(text)
        speech = parse_speech_markup(text)
        if not speech.plain.strip():
            raise InputError(None, "speech text", "empty text: only marks, nothing to say")
        ssml = speech.ssml is not None
        espeak_text = speech.ssml if speech.ssml is not None else speech.plain
        volume = int(round(self.volume * 100))
        with _as_infuse_errors():
            espeak = espeak_library.espeak(self.library)  # also tells early, here, when espeak-ng is missing
            if wav_path is None or self.wav_writer == "libespeak":
                synthesis = espeak.synthesize(espeak_text, self.voice, self.rate, volume, ssml=ssml)
        if wav_path is None:
            samples = np.frombuffer(synthesis.samples, dtype=np.int16).copy()
            utterance = self._utterance(text, espeak_text, samples, synthesis.sample_rate, synthesis.events)
            utterance.samples = samples
            utterance.meta["alignment"] = "timings and samples from one synthesis"
            return utterance
        wav_path = Path(wav_path)
        with atomic_path(wav_path) as tmp:
            if self.wav_writer == "libespeak":
                samples = np.frombuffer(synthesis.samples, dtype=np.int16).copy()
                utterance = self._utterance(text, espeak_text, samples, synthesis.sample_rate, synthesis.events)
                write_wav(tmp, samples, synthesis.sample_rate)
                utterance.meta.update(wav_writer="libespeak", alignment="timings and WAV from one synthesis")
            else:
                timeout = self.timeout_s or pyttsx3_writer.default_timeout_s(speech.plain)
                writer = pyttsx3_writer.start(speech.plain, tmp, self.voice, self.rate, self.volume, timeout)
                try:
                    if espeak.claim_fresh():  # this process has not synthesized yet: time it here
                        with _as_infuse_errors():
                            synthesis = espeak.synthesize(espeak_text, self.voice, self.rate, volume, ssml=ssml)
                        samples, rate, events = np.frombuffer(synthesis.samples, dtype=np.int16).copy(), synthesis.sample_rate, synthesis.events
                    else:
                        timing = isolated.start(espeak_text, self.voice, self.rate, volume, ssml, self.library)
                        samples, rate, events = isolated.finish(timing, timeout)
                    utterance = self._utterance(text, espeak_text, samples, rate, events)
                except BaseException:
                    writer.kill()
                    writer.communicate()
                    raise
                self._check_pyttsx3_wav(writer, tmp, samples, rate, timeout, utterance, speech.plain)
        utterance.wav_path = wav_path
        return utterance

    def _check_pyttsx3_wav(self, writer, tmp: Path, samples: np.ndarray, rate: int, timeout: float,
                           utterance: Utterance, text: str) -> None:
        for attempt in range(PYTTSX3_ATTEMPTS):
            if attempt:  # pyttsx3 dropped the end of the audio: ask it again
                writer = pyttsx3_writer.start(text, tmp, self.voice, self.rate, self.volume, timeout)
            code, err = pyttsx3_writer.finish(writer, timeout)
            if code == pyttsx3_writer.EXIT_MISSING:
                raise MissingFeatureError(None, f"{err}; {espeak_library.INSTALL_HINT}, and pip install pyttsx3")
            if code != 0:
                raise UnusableInputError(None, f"pyttsx3 could not write the WAV: {err or f'exit code {code}'}")
            wav, wav_rate = read_wav_samples(tmp)
            if wav_rate == rate and np.array_equal(wav, samples):
                utterance.meta.update(wav_writer="pyttsx3", alignment="WAV identical to the timed synthesis",
                                      pyttsx3_attempts=attempt + 1)
                return
            truncated = wav_rate == rate and len(wav) < len(samples) and np.array_equal(wav, samples[:len(wav)])
            if not truncated:
                break
        problem = (f"pyttsx3's WAV ({len(wav)} samples at {wav_rate} Hz) differs from the timed synthesis "
                   f"({len(samples)} samples at {rate} Hz)")
        warnings.warn(f"{problem}; writing the timed synthesis instead so the timings match the WAV", RuntimeWarning, stacklevel=3)
        write_wav(tmp, samples, rate)
        utterance.meta.update(wav_writer="libespeak", alignment=f"rewritten: {problem}")

    def _utterance(self, text: str, espeak_text: str, samples: np.ndarray, sample_rate: int, events) -> Utterance:
        timeline = build_timeline(events, len(samples), sample_rate, espeak_text)
        if not any(p != SILENCE for _, _, p in timeline.phonemes):
            raise InputError(None, "speech text", f"nothing to pronounce in {text[:60]!r} with voice {self.voice!r}")
        meta = {"voice": self.voice, "rate_wpm": self.rate, "volume": self.volume, "library": espeak_library.library_path(self.library)}
        if timeline.unknown_phonemes:
            meta["unknown_phonemes"] = " ".join(timeline.unknown_phonemes)
        return Utterance(
            text=text, duration_s=len(samples) / sample_rate, phonemes=timeline.phonemes, words=timeline.words,
            marks=timeline.marks, sample_rate=sample_rate, source_phonemes=timeline.source_phonemes,
            engine=self.name, meta=meta,
        )


def _rate_ok(rate) -> bool:
    try:
        return espeak_library.RATE_MINIMUM <= int(rate) <= espeak_library.RATE_MAXIMUM
    except (TypeError, ValueError):
        return False
