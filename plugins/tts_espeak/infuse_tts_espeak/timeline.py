"""libespeak-ng events -> phoneme intervals, word intervals and mark times (seconds).

A phoneme event marks where a phoneme starts; it lasts until the next phoneme event (the last one
until the end of the audio). Times come from the events' sample index, so they are exact to one
sample of the audio the events came with.

libespeak-ng emits word and mark events somewhat before the word's first phoneme (up to about
50 ms, inside the previous phoneme), so a word or a mark is timed at the phoneme event that
follows it: a mark is reached when the sound after it begins.
"""
from __future__ import annotations

import html
from dataclasses import dataclass, field

import numpy as np

from infuse.speech import SILENCE, contiguous_phonemes, to_common

from .library import Event

_VOWEL_LETTERS = set("aeiouyAEIOUVY@0236")


@dataclass
class Timeline:
    phonemes: list[tuple[float, float, str]]
    source_phonemes: list[str]
    words: list[tuple[float, float, str]]
    marks: dict[str, float]
    unknown_phonemes: list[str] = field(default_factory=list)


def common_name(name: str) -> tuple[str, bool]:
    """The common phoneme for an espeak-ng mnemonic and whether it was known.

    An unknown mnemonic (a voice with phonemes the table lacks) becomes a neutral vowel or "hh",
    so it takes its shape from its neighbours; the caller reports it.
    """
    common = to_common(name, "espeak")
    if common is not None:
        return common, True
    return ("ah" if name[:1] in _VOWEL_LETTERS else "hh"), False


def build_timeline(events: list[Event], total_samples: int, sample_rate: int, text: str) -> Timeline:
    """Phonemes (common set, contiguous over the audio), words and marks from ``events``.

    ``text`` is the exact string given to espeak-ng (plain or SSML), for the word spellings.
    """
    duration = total_samples / sample_rate
    ph_events = [e for e in events if e.kind == "phoneme"]
    starts = np.array([e.sample for e in ph_events], float) / sample_rate
    ends = np.append(starts[1:], duration) if len(starts) else starts
    intervals: list[tuple[float, float, str]] = []
    sources: list[str] = []
    unknown: list[str] = []
    for e, s, t in zip(ph_events, starts, ends):
        common, known = common_name(e.name)
        if not known and e.name not in unknown:
            unknown.append(e.name)
        intervals.append((float(s), float(min(t, duration)), common))
        sources.append(e.name)
    phonemes, source_phonemes = contiguous_phonemes(intervals, duration, sources)
    onsets = _next_phoneme_samples(events, total_samples)
    marks = {e.name: onsets[i] / sample_rate for i, e in enumerate(events) if e.kind == "mark"}
    return Timeline(phonemes, source_phonemes, _words(events, onsets, phonemes, sample_rate, text), marks, unknown)


def _next_phoneme_samples(events: list[Event], total_samples: int) -> list[int]:
    """For each event, the sample of the first phoneme event at or after it in the list (or the end)."""
    out = [total_samples] * len(events)
    upcoming = total_samples
    for i in range(len(events) - 1, -1, -1):
        if events[i].kind == "phoneme":
            upcoming = events[i].sample
        out[i] = max(upcoming, events[i].sample)
    return out


def _words(events: list[Event], onsets: list[int], phonemes: list[tuple[float, float, str]], sample_rate: int, text: str):
    """Word intervals: from the word's first phoneme to the end of its last spoken phoneme before the next word."""
    chosen = [i for i, e in enumerate(events) if e.kind == "word" and e.length > 0]
    if not chosen or not phonemes:
        return []
    p_start = np.array([p[0] for p in phonemes])
    p_end = np.array([p[1] for p in phonemes])
    spoken = np.array([p[2] != SILENCE for p in phonemes])
    w_start = np.array([onsets[i] for i in chosen], float) / sample_rate
    w_next = np.append(w_start[1:], np.inf)
    words = []
    for i, s, nxt in zip(chosen, w_start, w_next):
        e = events[i]
        inside = spoken & (p_start >= s - 1e-9) & (p_start < nxt)
        end = float(p_end[inside].max()) if inside.any() else float(s)
        spelling = html.unescape(text[e.text_position - 1:e.text_position - 1 + e.length])
        words.append((float(s), end, spelling))
    return words
