"""How long speech lasts and when its marks fall: estimated from the text, or asked of a TTS engine.

A TTS plugin offers real timings by giving its engine a ``time_speech(text, marks, voice=None,
language=None) -> SpeechTiming`` method (see :class:`SpeechTimer`); without one the scheduler
uses :class:`EstimatedSpeechTimer`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Protocol, Sequence, runtime_checkable


@dataclass(frozen=True)
class SpeechTiming:
    """``duration_s``: length of the utterance; ``mark_times_s``: mark id -> seconds from its start;
    ``source``: ``"estimate"`` or the engine's name; ``details``: plain data an engine adds (phonemes, audio path)."""

    duration_s: float
    mark_times_s: dict
    source: str = "estimate"
    details: dict = field(default_factory=dict)


@runtime_checkable
class SpeechTimer(Protocol):
    def time_speech(self, text: str, marks: Sequence[tuple[str, int]], voice: str | None = None,
                    language: str | None = None) -> SpeechTiming:
        """Timing of ``text``; ``marks`` are (mark id, character offset in ``text``)."""


@dataclass(frozen=True)
class EstimatedSpeechTimer:
    """Speech timing from the text alone: a fixed time per character plus pauses at punctuation.

    The defaults (0.068 s per character, about 175 words per minute) match ordinary conversational rate.
    """

    seconds_per_char: float = 0.068
    comma_pause_s: float = 0.15
    sentence_pause_s: float = 0.35

    def char_times(self, text: str) -> list[float]:
        """Seconds from the start of ``text`` at which each character offset 0..len(text) is reached."""
        times = [0.0]
        for ch in text:
            cost = self.seconds_per_char if not ch.isspace() else self.seconds_per_char * 0.5
            if ch in ",;:":
                cost += self.comma_pause_s
            elif ch in ".!?":
                cost += self.sentence_pause_s
            times.append(times[-1] + cost)
        return times

    def time_speech(self, text, marks, voice=None, language=None) -> SpeechTiming:
        times = self.char_times(text)
        # Pauses after the last word are not speech.
        end = self.char_times(text.rstrip(" .!?,;:"))[-1] if text.strip() else 0.0
        marks_s = {mark: min(times[min(offset, len(text))], end) for mark, offset in marks}
        return SpeechTiming(end, marks_s, "estimate")


@dataclass(frozen=True)
class EngineSpeechTimer:
    """Real timings from a TTS engine (``engine.synthesize(text) -> infuse.speech.Utterance``, marks written as
    ``<mark name="..."/>``). Only timing is kept here; the realizer asks the engine again for the audio.

    A mark the engine does not report (espeak-ng drops one that stands between two sentences) is timed at
    the start of the word after it, from the utterance's words when the engine timed every word of the
    text, else in proportion to its place in the text."""

    engine: object

    def time_speech(self, text, marks, voice=None, language=None) -> SpeechTiming:
        from xml.sax.saxutils import escape, quoteattr

        if not text.strip():
            return SpeechTiming(0.0, {m: 0.0 for m, _ in marks}, getattr(self.engine, "name", "tts"))
        if marks:
            pieces, last = [], 0
            for mark, offset in sorted(marks, key=lambda m: m[1]):
                pieces.append(escape(text[last:offset]) + f"<mark name={quoteattr(mark)}/>")
                last = offset
            markup = "".join(pieces) + escape(text[last:])
        else:
            markup = text
        utterance = self.engine.synthesize(markup)
        details = {"phonemes": [list(p) for p in utterance.phonemes], "words": [list(w) for w in utterance.words]}
        return SpeechTiming(float(utterance.duration_s), mark_times(text, marks, utterance),
                            getattr(self.engine, "name", "tts"), details)


_WORD = re.compile(r"[^\W_](?:[\w'’-]*[^\W_])?")


def mark_times(text: str, marks, utterance) -> dict:
    """Mark id -> seconds in ``utterance`` (an :class:`infuse.speech.Utterance` of ``text``) for each (mark id,
    character offset in ``text``) of ``marks``: the engine's time, else the start of the word after the
    mark (see :class:`EngineSpeechTimer`)."""
    return {m: float(utterance.marks[m]) if m in utterance.marks else _word_time(text, offset, utterance)
            for m, offset in marks}


def _word_time(text: str, offset: int, utterance) -> float:
    """Seconds at which the word at or after character ``offset`` of ``text`` starts in ``utterance``."""
    starts = [m.start() for m in _WORD.finditer(text)]
    index = sum(start < offset for start in starts)
    if len(starts) == len(utterance.words) and starts:
        return float(utterance.words[index][0]) if index < len(starts) else float(utterance.duration_s)
    return float(utterance.duration_s) * min(offset / max(len(text), 1), 1.0)
