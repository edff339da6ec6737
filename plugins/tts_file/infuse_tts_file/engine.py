"""The ``file`` TTS engine: a recorded voice (WAV) and its phoneme timing file -> :class:`Utterance`.

Everything is validated against the audio: times must be finite, non-negative, ordered, not
overlapping and inside the recording (up to ``tolerance_s`` past its end, then cut); labels must be
phonemes of the file's alphabet (ARPAbet, IPA or espeak-ng, detected unless given). Sync marks come
from the timing file (a ``marks`` point tier or JSON ``marks``) or from ``<sync id>``/``<mark name>``
elements in the text, placed at the start of the word that follows them (which needs a words tier).
"""
from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np

from infuse.atomic import atomic_path
from infuse.errors import InputError, UsageError
from infuse.speech import ALPHABETS, SILENCE, Utterance, contiguous_phonemes, detect_alphabet, parse_speech_markup, to_common

from .audio import read_wav
from .timing import Entry, read_timing

_WORD = re.compile(r"\w+(?:['’]\w+)*")
_SILENT_WORDS = {"", "<eps>", "sil", "sp", "spn", "<sil>", "silence", "#"}


class FileEngine:
    """Recorded speech.

    - ``audio``: the WAV file; ``timing``: the phoneme timing file (see :mod:`.timing`).
    - ``alphabet``: "arpabet", "ipa" or "espeak"; detected from the labels when not given.
    - ``tolerance_s``: how far past the end of the audio an interval may reach before it is an error.
    """

    name = "file"

    def __init__(self, audio: str | Path | None = None, timing: str | Path | None = None, alphabet: str | None = None,
                 tolerance_s: float = 0.02):
        if alphabet is not None and alphabet not in ALPHABETS:
            raise UsageError(f"alphabet must be one of {', '.join(ALPHABETS)}, not {alphabet!r}")
        self.audio = Path(audio) if audio else None
        self.timing = Path(timing) if timing else None
        self.alphabet = alphabet
        self.tolerance_s = float(tolerance_s)

    def synthesize(self, text: str | None = None, wav_path: str | Path | None = None) -> Utterance:
        """The utterance of the recording; ``text`` (optional) may carry sync marks. With ``wav_path`` the
        recording is copied there."""
        if self.audio is None or self.timing is None:
            raise UsageError("the file TTS engine needs audio= (a WAV) and timing= (a phoneme timing file)")
        for path in (self.audio, self.timing):
            if not path.is_file():
                raise InputError(path, None, "file not found")
        samples, rate = read_wav(self.audio)
        duration = len(samples) / rate
        if duration <= 0:
            raise InputError(self.audio, None, "the recording is empty")
        doc = read_timing(self.timing)
        alphabet = self.alphabet or doc.get("alphabet") or detect_alphabet([e[2] for e in doc["phones"]])
        if alphabet not in ALPHABETS:
            raise InputError(self.timing, "alphabet", f"unknown phoneme alphabet {alphabet!r}; known: {', '.join(ALPHABETS)}")
        phones = self._checked(doc["phones"], duration, "phone")
        intervals, sources = [], []
        for s, e, label, place in phones:
            common = to_common(label, alphabet)
            if common is None:
                raise InputError(self.timing, place, f"unknown {alphabet} phoneme {label!r}")
            intervals.append((s, e, common))
            sources.append(label)
        phonemes, source_phonemes = contiguous_phonemes(intervals, duration, sources)
        if not any(p != SILENCE for _, _, p in phonemes):
            raise InputError(self.timing, "phones", "no spoken phoneme in the timing file")
        words = [(s, e, w) for s, e, w, _ in self._checked(doc["words"], duration, "word") if w.strip().lower() not in _SILENT_WORDS]
        marks = {}
        for t, name, place in doc["marks"]:
            if not 0.0 <= t <= duration + self.tolerance_s:
                raise InputError(self.timing, place, f"mark {name!r} at {t:g} s is outside the recording (0..{duration:g} s)")
            marks[name] = min(t, duration)
        text = text if text is not None else " ".join(w for _, _, w in words)
        if text.strip():
            marks.update(self._text_marks(text, words))
        utterance = Utterance(
            text=text, duration_s=duration, phonemes=phonemes,
            words=words, marks=marks, samples=samples, sample_rate=rate, source_phonemes=source_phonemes,
            engine=self.name, meta={"audio": str(self.audio), "timing": str(self.timing), "alphabet": alphabet},
        )
        if wav_path is not None:
            with atomic_path(wav_path) as tmp:
                shutil.copyfile(self.audio, tmp)
            utterance.wav_path = Path(wav_path)
        return utterance

    def _checked(self, entries: list[Entry], duration: float, what: str) -> list[Entry]:
        """Entries in time order, validated; zero-length ones dropped, the last cut at the end of the audio."""
        out: list[Entry] = []
        previous_end = 0.0
        for s, e, label, place in entries:
            if s < 0:
                raise InputError(self.timing, place, f"{what} {label!r} starts before 0 s ({s:g} s)")
            if e < s:
                raise InputError(self.timing, place, f"{what} {label!r} ends ({e:g} s) before it starts ({s:g} s)")
            if s < previous_end - 1e-6:
                raise InputError(self.timing, place, f"{what} {label!r} at {s:g} s overlaps the previous one (ends at {previous_end:g} s)")
            if e > duration + self.tolerance_s:
                raise InputError(self.timing, place, f"{what} {label!r} ends at {e:g} s, after the end of the audio ({duration:g} s)")
            previous_end = max(previous_end, e)
            if e - s > 0 and s < duration:
                out.append((s, min(e, duration), label, place))
        return out

    def _text_marks(self, text: str, words: list[tuple[float, float, str]]) -> dict[str, float]:
        """Marks written in the text, at the start of the word after each (the end of the last word if none)."""
        speech = parse_speech_markup(text)
        if not speech.marks:
            return {}
        if not words:
            raise InputError(self.timing, "words", "sync marks in the text need a words tier in the timing file to be placed")
        starts = np.array([s for s, _, _ in words])
        out = {}
        for name, offset in zip(speech.marks, speech.mark_offsets):
            k = len(_WORD.findall(speech.plain[:offset]))
            out[name] = float(starts[k]) if k < len(words) else float(words[-1][1])
        return out
