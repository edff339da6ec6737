"""The generator's rules, read from a TOML file (``rules.toml`` beside this module by default) and checked.

A mistake raises :class:`infuse.errors.InputError` naming the file, the key (``rule[3].bml``) and the
problem. See ``rules.toml`` for the meaning of each key.
"""
from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import NoReturn

from infuse.bml import parse_bml
from infuse.errors import InfuseError, InputError

DEFAULT_RULES = Path(__file__).resolve().parent / "rules.toml"
CHANNELS = ("hands", "head", "face")
#: Triggers that are not word classes.
SPECIAL_TRIGGERS = ("accented", "object", "question")
LISTENER_TRIGGERS = ("sentence_end", "phrase_end")
#: Word classes the generator itself reads.
REQUIRED_CLASSES = ("function", "demonstrative")
PLACEHOLDERS = ("hand", "amplitude", "listener", "object", "direction")
_PLACEHOLDER = re.compile(r"\{(\w+)\}")
_BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"


@dataclass(frozen=True)
class Rule:
    """On words matching ``on``, with ``probability``, the element ``bml`` on ``channel``, its ``sync`` on the word."""

    name: str
    on: str
    channel: str
    probability: float
    bml: str
    sync: str


@dataclass(frozen=True)
class GazeRules:
    """Gaze aversion at the start of long utterances and the look back at the listener."""

    long_utterance_words: int
    aversion_probability: float
    look_back_probability: float
    look_back_at: float
    aversion: str
    directions: tuple[str, ...]
    look_back: str


@dataclass(frozen=True)
class ListenerRules:
    """The listener's backchannel: ``bml`` on ``on`` (sentence or phrase ends) after ``min_words`` words."""

    on: tuple[str, ...]
    min_words: int
    probability: float
    gap_s: float
    bml: str
    sync: str


@dataclass(frozen=True)
class Rules:
    """Everything ``rules.toml`` says: word classes (lower-case words), rules in order, gaps and leads
    (seconds, per channel), the amplitude range, how many words before an object's name a demonstrative
    may stand, how many earlier utterances make a word given, hand weights."""

    path: Path
    words: dict
    rules: tuple[Rule, ...]
    gap_s: dict
    lead_s: dict
    amplitude: tuple[float, float]
    object_lookahead_words: int
    remembered_utterances: int
    hands: tuple[tuple[str, float], ...]
    gaze: GazeRules
    listener: ListenerRules


class _Checker:
    def __init__(self, path: Path):
        self.path = path

    def fail(self, place: str, problem: str) -> NoReturn:
        raise InputError(self.path, place, problem)

    def table(self, doc: dict, key: str) -> dict:
        value = doc.get(key)
        if not isinstance(value, dict):
            self.fail(key, "expected a table")
        return value

    def channels(self, doc: dict, key: str) -> dict:
        value = doc.get(key)
        if not isinstance(value, dict) or set(value) != set(CHANNELS):
            self.fail(f"timing.{key}", f"expected a table of {', '.join(CHANNELS)}")
        return value

    def number(self, value, place: str, low: float, high: float) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or not low <= value <= high:
            self.fail(place, f"expected a number in [{low:g}, {high:g}], got {value!r}")
        return float(value)

    def text(self, value, place: str) -> str:
        if not isinstance(value, str) or not value.strip():
            self.fail(place, f"expected text, got {value!r}")
        return value

    def words(self, value, place: str) -> frozenset:
        if not isinstance(value, list) or not all(isinstance(w, str) and w.strip() for w in value):
            self.fail(place, "expected a list of words")
        return frozenset(w.strip().lower() for w in value)

    def element(self, value: object, place: str) -> str:
        """``value`` checked as a template: one BML element, known placeholders, no sync point of its own."""
        template = self.text(value, place)
        unknown = sorted(set(_PLACEHOLDER.findall(template)) - set(PLACEHOLDERS))
        if unknown:
            self.fail(place, f"unknown placeholder {{{unknown[0]}}}; known: {', '.join(PLACEHOLDERS)}")
        sample = _PLACEHOLDER.sub("x", template)
        try:
            document = parse_bml(f'<bml xmlns="{_BML_NS}" id="check">{sample}</bml>', file=str(self.path))
        except InfuseError as exc:
            self.fail(place, f"not one BML element: {exc}")
        behaviours = document.blocks[0].behaviours
        if len(behaviours) != 1:
            self.fail(place, f"expected one BML element, found {len(behaviours)}")
        if behaviours[0].sync_refs:
            self.fail(place, "the element sets its own sync points; the generator places them")
        return template


def load_rules(path: str | Path | None = None) -> Rules:
    """The rules of ``path`` (default: the built-in ``rules.toml``), checked."""
    return _load(Path(path).resolve() if path is not None else DEFAULT_RULES)


@lru_cache(maxsize=8)
def _load(path: Path) -> Rules:
    c = _Checker(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(path, None, f"cannot be read: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InputError(path, None, f"not a TOML rules file: {exc}") from None
    words = {name: c.words(value, f"words.{name}") for name, value in c.table(doc, "words").items()}
    for needed in REQUIRED_CLASSES:
        if needed not in words:
            c.fail(f"words.{needed}", "missing: the generator needs this word class")
    timing = c.table(doc, "timing")
    gap_s, lead_s = ({k: c.number(v, f"timing.{key}.{k}", 0.0, 10.0) for k, v in c.channels(timing, key).items()}
                     for key in ("gap_s", "lead_s"))
    amplitude = timing.get("amplitude")
    if not isinstance(amplitude, list) or len(amplitude) != 2:
        c.fail("timing.amplitude", "expected [lowest, highest]")
    low, high = (c.number(v, "timing.amplitude", 0.05, 3.0) for v in amplitude)
    if low > high:
        c.fail("timing.amplitude", "the lowest is above the highest")
    lookahead = int(c.number(timing.get("object_lookahead_words"), "timing.object_lookahead_words", 0, 20))
    remembered = int(c.number(c.table(doc, "discourse").get("remembered_utterances"),
                              "discourse.remembered_utterances", 0, 1000))
    hands = tuple((mode, c.number(w, f"hands.{mode}", 0.0, 1e6)) for mode, w in c.table(doc, "hands").items())
    if not hands or sum(w for _, w in hands) <= 0:
        c.fail("hands", "expected at least one hand with a positive weight")
    for mode, _ in hands:
        if mode not in ("LEFT_HAND", "RIGHT_HAND", "BOTH_HANDS"):
            c.fail(f"hands.{mode}", "expected LEFT_HAND, RIGHT_HAND or BOTH_HANDS")
    rules = []
    for k, item in enumerate(doc.get("rule", [])):
        place = f"rule[{k + 1}]"
        if not isinstance(item, dict):
            c.fail(place, "expected a table")
        on = c.text(item.get("on"), f"{place}.on")
        if on not in words and on not in SPECIAL_TRIGGERS:
            c.fail(f"{place}.on", f"{on!r} is no word class of [words] nor one of {', '.join(SPECIAL_TRIGGERS)}")
        channel = c.text(item.get("channel"), f"{place}.channel")
        if channel not in CHANNELS:
            c.fail(f"{place}.channel", f"expected one of {', '.join(CHANNELS)}")
        sync = c.text(item.get("sync"), f"{place}.sync")
        rules.append(Rule(c.text(item.get("name"), f"{place}.name"), on, channel,
                          c.number(item.get("probability"), f"{place}.probability", 0.0, 1.0),
                          c.element(item.get("bml"), f"{place}.bml"), sync))
    g = c.table(doc, "gaze")
    directions = g.get("directions")
    if not isinstance(directions, list) or not directions or not all(isinstance(d, str) for d in directions):
        c.fail("gaze.directions", "expected a list of offset directions")
    gaze = GazeRules(int(c.number(g.get("long_utterance_words"), "gaze.long_utterance_words", 1, 1000)),
                     c.number(g.get("aversion_probability"), "gaze.aversion_probability", 0.0, 1.0),
                     c.number(g.get("look_back_probability"), "gaze.look_back_probability", 0.0, 1.0),
                     c.number(g.get("look_back_at"), "gaze.look_back_at", 0.0, 1.0),
                     c.element(g.get("aversion"), "gaze.aversion"), tuple(directions),
                     c.element(g.get("look_back"), "gaze.look_back"))
    li = c.table(doc, "listener")
    triggers = li.get("on")
    if not isinstance(triggers, list) or not triggers or any(t not in LISTENER_TRIGGERS for t in triggers):
        c.fail("listener.on", f"expected a list of {', '.join(LISTENER_TRIGGERS)}")
    listener = ListenerRules(tuple(triggers), int(c.number(li.get("min_words"), "listener.min_words", 1, 1000)),
                             c.number(li.get("probability"), "listener.probability", 0.0, 1.0),
                             c.number(li.get("gap_s"), "listener.gap_s", 0.0, 60.0),
                             c.element(li.get("bml"), "listener.bml"), c.text(li.get("sync"), "listener.sync"))
    return Rules(path, words, tuple(rules), gap_s, lead_s, (low, high), lookahead, remembered, hands, gaze, listener)
