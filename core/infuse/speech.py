"""Speech: what a text-to-speech engine returns (:class:`Utterance`) and the common phoneme set.

Times are in seconds from the start of the audio. Phonemes are in the common set (ARPAbet in lower
case without stress digits, plus ``"sil"``); engines convert their own names with :func:`to_common`.
Speech text may carry sync marks, ``<mark name="x"/>`` (SSML) or ``<sync id="x"/>`` (BML), whose
times an engine reports in :attr:`Utterance.marks` (see :func:`parse_speech_markup`).

TTS engines are plugins (hook ``infuse_tts_engines``); :func:`tts_engine` builds one by name.
"""
from __future__ import annotations

import re
import tomllib
import unicodedata
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError, UsageError

SILENCE = "sil"
ALPHABETS = ("espeak", "ipa", "arpabet")


@lru_cache(maxsize=1)
def _tables() -> dict:
    text = resources.files("infuse").joinpath("data/phonemes.toml").read_text(encoding="utf-8")
    return tomllib.loads(text)


@lru_cache(maxsize=1)
def common_phonemes() -> tuple[str, ...]:
    """The common phoneme set: 39 ARPAbet phonemes (lower case) and ``"sil"``."""
    return tuple(_tables()["common"])


@lru_cache(maxsize=1)
def vowels() -> frozenset[str]:
    return frozenset(_tables()["vowels"])


@lru_cache(maxsize=None)
def to_common(name: str, alphabet: str) -> str | None:
    """The common phoneme for ``name`` written in ``alphabet`` ("espeak", "ipa" or "arpabet").

    Silence and pause names give ``"sil"``; an unknown name gives ``None`` (the caller reports it).
    """
    if alphabet not in ALPHABETS:
        raise UsageError(f"unknown phoneme alphabet {alphabet!r}; known: {', '.join(ALPHABETS)}")
    table = _tables()[alphabet]
    common = set(common_phonemes())
    if name.strip() in table["silence"]:
        return SILENCE
    if alphabet == "arpabet":
        key = re.sub(r"[0-9]", "", name.strip()).lower()
        if key in table["silence"]:
            return SILENCE
        return table["names"].get(key) or (key if key in common else None)
    names = table["names"]
    if name in names:
        return names[name]
    if alphabet == "ipa":
        key = unicodedata.normalize("NFC", name.strip())
        for mark in table["strip"]:
            key = key.replace(mark, "")
        key = unicodedata.normalize("NFC", key)
        return names.get(key) or names.get(unicodedata.normalize("NFD", key)[:1])
    # espeak: drop length, stress and variant marks ("a#", "e:", "I2", "l/") and try again
    key = re.sub(r"[:#;/'\",\-0-9]+$", "", name)
    if key in names:
        return names[key]
    return None


def detect_alphabet(labels: list[str]) -> str:
    """"arpabet" when every non-silence label is ARPAbet (any case, stress digits allowed), else "ipa"."""
    arpabet = set(common_phonemes()) | set(_tables()["arpabet"]["names"])
    silence = set(_tables()["arpabet"]["silence"]) | set(_tables()["ipa"]["silence"])
    spoken = [s for s in (label.strip() for label in labels) if s.lower() not in silence]
    if spoken and all(re.sub(r"[0-9]", "", s).lower() in arpabet for s in spoken):
        return "arpabet"
    return "ipa"


@dataclass
class Utterance:
    """One synthesized or recorded utterance and its timing.

    - ``phonemes``: ``(start_s, end_s, phoneme)`` in the common set, contiguous from 0 to
      ``duration_s`` (pauses are ``"sil"``); ``source_phonemes`` holds the engine's own names.
    - ``words``: ``(start_s, end_s, word)``; ``marks``: sync mark name -> time in seconds.
    - The audio: ``wav_path`` (a WAV file) and/or ``samples`` (mono int16, ``sample_rate`` Hz).
    - ``meta``: engine facts (voice, rate, how the audio was checked against the timings...).
    """

    text: str
    duration_s: float
    phonemes: list[tuple[float, float, str]]
    words: list[tuple[float, float, str]] = field(default_factory=list)
    marks: dict[str, float] = field(default_factory=dict)
    wav_path: Path | None = None
    samples: np.ndarray | None = None
    sample_rate: int | None = None
    source_phonemes: list[str] = field(default_factory=list)
    engine: str = ""
    meta: dict[str, Any] = field(default_factory=dict)

    def phoneme_arrays(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """``(starts (P,), ends (P,), names)`` of :attr:`phonemes`, seconds."""
        if not self.phonemes:
            return np.zeros(0), np.zeros(0), []
        starts, ends, names = zip(*self.phonemes)
        return np.asarray(starts, float), np.asarray(ends, float), list(names)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able summary (no audio samples): text, duration, phonemes, words, marks, engine, meta."""
        r = lambda t: round(float(t), 6)  # noqa: E731 - microsecond precision is plenty
        phonemes = []
        for i, (s, e, p) in enumerate(self.phonemes):
            entry = {"start": r(s), "end": r(e), "phoneme": p}
            if i < len(self.source_phonemes):
                entry["source"] = self.source_phonemes[i]
            phonemes.append(entry)
        return {
            "text": self.text,
            "duration_s": r(self.duration_s),
            "engine": self.engine,
            "sample_rate": self.sample_rate,
            "wav": str(self.wav_path) if self.wav_path else None,
            "phonemes": phonemes,
            "words": [{"start": r(s), "end": r(e), "word": w} for s, e, w in self.words],
            "marks": {k: r(v) for k, v in self.marks.items()},
            "meta": {k: v for k, v in self.meta.items() if isinstance(v, (str, int, float, bool, type(None)))},
        }


def contiguous_phonemes(intervals: list[tuple[float, float, str]], duration_s: float,
                        sources: list[str] | None = None) -> tuple[list[tuple[float, float, str]], list[str]]:
    """Sorted, non-overlapping ``intervals`` made contiguous over ``[0, duration_s]``.

    Gaps become ``"sil"``, neighbouring silences merge, zero-length intervals are dropped and the
    last interval is cut at ``duration_s``. Returns the intervals and their source names.
    """
    sources = list(sources) if sources is not None else [p for _, _, p in intervals]
    out: list[tuple[float, float, str]] = []
    out_src: list[str] = []

    def push(s: float, e: float, p: str, src: str) -> None:
        if e <= s:
            return
        if out and p == SILENCE and out[-1][2] == SILENCE:
            out[-1] = (out[-1][0], e, SILENCE)
            return
        out.append((s, e, p))
        out_src.append(src)

    t = 0.0
    for (s, e, p), src in zip(intervals, sources):
        s, e = max(s, t), min(e, duration_s)
        if s > t:
            push(t, s, SILENCE, "")
        push(s, e, p, src)
        t = max(t, e)
    if t < duration_s:
        push(t, duration_s, SILENCE, "")
    return out, out_src


# -- speech text ----------------------------------------------------------------------------------

_MARKUP = re.compile(r"<\s*(mark|sync|tm)\b", re.IGNORECASE)
_MARK_ELEMENTS = {"mark": "name", "sync": "id", "tm": "id"}


@dataclass(frozen=True)
class SpeechText:
    """Speech text split for an engine: ``plain`` (marks removed), ``ssml`` (marks as SSML ``<mark>``,
    ``None`` when there are none), the mark names in order and where each sits in ``plain``
    (character offsets)."""

    plain: str
    ssml: str | None
    marks: tuple[str, ...]
    mark_offsets: tuple[int, ...] = ()


def parse_speech_markup(text: str) -> SpeechText:
    """Split speech text with ``<mark name="x"/>``, ``<sync id="x"/>`` or ``<tm id="x"/>`` elements.

    Text without such elements is taken literally (``<`` and ``&`` are then ordinary characters).
    Other elements, duplicate or missing names raise :class:`InputError`.
    """
    if not _MARKUP.search(text):
        return SpeechText(text, None, (), ())
    from lxml import etree
    from xml.sax.saxutils import escape, quoteattr

    parser = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=False, load_dtd=False)
    try:
        root = etree.fromstring(f"<speech>{text}</speech>".encode("utf-8"), parser)
    except etree.XMLSyntaxError as exc:
        raise InputError(None, "speech text", f"marks present but the text is not well-formed markup: {exc}") from None
    plain = [root.text or ""]
    ssml = [escape(root.text or "")]
    marks: list[str] = []
    offsets: list[int] = []
    for child in root:
        tag = child.tag if isinstance(child.tag, str) else ""
        if tag.lower() not in _MARK_ELEMENTS:
            raise InputError(None, "speech text", f"unsupported element <{tag or child}> in speech text; "
                             'allowed: <mark name="..."/>, <sync id="..."/>')
        name = child.get(_MARK_ELEMENTS[tag.lower()]) or child.get("name") or child.get("id")
        if not name:
            raise InputError(None, "speech text", f"<{tag}> needs a {_MARK_ELEMENTS[tag.lower()]!r} attribute")
        if name in marks:
            raise InputError(None, "speech text", f"mark {name!r} appears twice")
        if len(child) or (child.text or "").strip():
            raise InputError(None, "speech text", f"<{tag} {name!r}> must be empty")
        marks.append(name)
        offsets.append(sum(len(p) for p in plain))
        ssml.append(f"<mark name={quoteattr(name)}/>" + escape(child.tail or ""))
        plain.append(child.tail or "")
    return SpeechText("".join(plain), "".join(ssml), tuple(marks), tuple(offsets))


_ALLOWED_CONTROLS = {"\t", "\n", "\r"}


def check_speech_text(text: str) -> str:
    """``text`` checked for speaking: NFC-normalized; raises :class:`InputError` when it is empty or holds
    characters no voice can pronounce (control, private-use, unassigned or unpaired surrogate code
    points), naming the first such character and its position."""
    if not isinstance(text, str):
        raise InputError(None, "speech text", f"expected a string, got {type(text).__name__}")
    if not text.strip():
        raise InputError(None, "speech text", "empty text: nothing to say")
    for i, ch in enumerate(text):
        cat = unicodedata.category(ch)
        if (cat == "Cc" and ch not in _ALLOWED_CONTROLS) or cat in ("Co", "Cn", "Cs"):
            kind = {"Cc": "control", "Co": "private-use", "Cn": "unassigned", "Cs": "unpaired surrogate"}[cat]
            raise InputError(None, f"speech text, character {i + 1}",
                             f"unsupported character U+{ord(ch):04X} ({kind}); remove it or replace it with words")
    return unicodedata.normalize("NFC", text)


# -- engines -----------------------------------------------------------------------------------------

def tts_engines() -> dict[str, Any]:
    """Installed TTS engines: name -> :class:`~infuse.plugin_types.TTSEngine`."""
    from . import registry

    return registry.table("tts")


def tts_engine(name: str | None = None, **settings) -> Any:
    """Build the TTS engine ``name`` (default: the ``tts`` default of :func:`infuse.registry.default_name`,
    ``"espeak"`` unless configured) with ``settings``.

    An engine has ``synthesize(text, wav_path=None) -> Utterance``. Raises :class:`UsageError`
    when no engine of that name is installed.
    """
    from . import registry

    return registry.get("tts", name).factory(**settings)
