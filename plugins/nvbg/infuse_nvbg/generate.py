"""Nonverbal behaviour from speech: the rules of :mod:`infuse_nvbg.rules` applied to each ``<speech>`` of a block.

For each utterance the generator marks the words it uses (``<sync id="nvw3"/>`` before word 3, ``nve3``
after it, so the TTS engine times them), then adds, rule by rule, hand gestures, head movements and
facial expressions whose sync point falls on a word's onset, gaze aversion at the start of a long
utterance and the look back at the listener, and a block of backchannel nods for the listener, its
strokes on the speaker's phrase ends. A channel (hands, head, face, gaze) the author already uses in
the block is left to the author. Spacing between strokes is judged on the estimated speech timing
(the real timing, a TTS engine's, comes later and moves every stroke with its word).
"""
from __future__ import annotations

import math
import random
import re
from dataclasses import dataclass, replace
from xml.sax.saxutils import escape, quoteattr

from infuse.bml import EstimatedSpeechTimer, GenerationError, Generation, parse_bml

from .rules import Rules, load_rules
from .words import Word, words_of

BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"
#: Elements of each channel: an author's element of a channel keeps the generator off that channel.
CHANNEL_ELEMENTS = {
    "hands": frozenset({"gesture", "pointing", "sbm:reach", "reach", "sbm:grab", "grab", "touch", "animation", "sbm:animation"}),
    "head": frozenset({"head"}),
    "face": frozenset({"faceLexeme", "faceFacs", "face"}),
    "gaze": frozenset({"gaze", "gazeShift", "headDirectionShift"}),
}
_PLACEHOLDER = re.compile(r"\{(\w+)\}")
_TAG = re.compile(r"^\s*<([\w:.-]+)")


@dataclass
class _Placed:
    """A generated element: when its sync point falls (estimated seconds from the speech start) and its XML."""

    time_s: float
    xml: str


def generate(block, context, rules: Rules | None = None) -> Generation:
    """``block`` with nonverbal behaviour for its speech, and the listener's backchannel block (see the module doc).

    ``context`` is the :class:`infuse.bml.GeneratorContext`; its settings ``listener`` (a character's name)
    and ``seed`` (an integer) override the listener found in the scene and the block's seed;
    ``expressiveness`` (0 to 3, default 1) multiplies the probability of every hand, head and face rule."""
    rules = rules or load_rules()
    settings = context.settings
    try:
        seed = int(settings["seed"]) if "seed" in settings else context.seed
    except ValueError:
        raise GenerationError(f"infuse:seed={settings['seed']!r} is not an integer") from None
    scale = _expressiveness(settings.get("expressiveness"))
    rng = random.Random(seed)
    listener, notes = _listener(context)
    objects = {name.lower(): name for name in context.objects}
    taken = {channel for b in block.behaviours for channel, elements in CHANNEL_ELEMENTS.items() if b.element in elements}
    ids = _Ids({b.id for b in block.behaviours})
    speaker_xml, listener_xml, speeches = [], [], {}
    listener_ids = _Ids(set())
    said = list(context.said[-rules.remembered_utterances:] if rules.remembered_utterances else ())
    for speech in (b for b in block.behaviours if b.element == "speech" and b.text):
        words = words_of(speech.text, rules.words["function"], tuple(said))
        said.append(speech.text)
        if not words:
            continue
        marks = _Marks(speech)
        onset = EstimatedSpeechTimer().char_times(speech.text)
        pinned = _pinned_start(speech, context.dialect)
        placed = _word_rules(rules, words, onset, speech.id, marks, ids, rng, listener, objects, taken, pinned, scale)
        if "gaze" not in taken and listener is not None:
            placed += _gaze(rules, words, onset, speech.id, marks, ids, rng, listener)
        speaker_xml += [p.xml for p in sorted(placed, key=lambda p: p.time_s)]
        if listener is not None:
            listener_xml += _backchannel(rules, words, onset, f"{block.id}:{speech.id}", marks, listener_ids, rng)
        speeches[speech.id] = _speech_xml(speech, marks)
    if not speaker_xml and not listener_xml:
        return Generation(block, notes=tuple(notes))
    character = f" characterId={quoteattr(context.character)}" if context.character else ""
    speaker_doc = (f'<bml xmlns="{BML_NS}" id={quoteattr(block.id)}{character}>'
                   + "".join(speeches.values()) + "".join(speaker_xml) + "</bml>")
    (parsed,) = parse_bml(speaker_doc).blocks
    marked = {b.id: b for b in parsed.behaviours if b.element == "speech"}
    behaviours = tuple(replace(b, marks=marked[b.id].marks) if b.id in marked else b for b in block.behaviours)
    added = tuple(b for b in parsed.behaviours if b.element != "speech")
    out = replace(block, behaviours=behaviours + added)
    if not listener_xml or listener is None:  # backchannels are made only for a listener
        return Generation(out, (), speaker_doc, tuple(notes))
    listener_id = f"{block.id}_{listener}_nv"
    listener_doc = (f'<bml xmlns="{BML_NS}" id={quoteattr(listener_id)} characterId={quoteattr(listener)}>'
                    + "".join(listener_xml) + "</bml>")
    (listening,) = parse_bml(listener_doc).blocks
    document = f"<act>{speaker_doc}{listener_doc}</act>"
    return Generation(out, (listening,), document, tuple(notes))


def _listener(context) -> tuple[str | None, list[str]]:
    """The character spoken to: the ``listener`` setting, else the nearest other character of the scene."""
    others = [c for c in context.characters if c != context.character]
    named = context.settings.get("listener")
    if named is not None and named.lower() == (context.character or "").lower():
        return None, [f"infuse:listener={named!r} is the speaker; no listener behaviour"]
    if named is not None:
        if context.characters and named not in context.characters:
            match = next((c for c in context.characters if c.lower() == named.lower()), None)
            if match is None:
                return None, [f"infuse:listener={named!r} names no character of the scene "
                              f"({', '.join(context.characters)}); no listener behaviour"]
            named = match
        return named, []
    if not others:
        return None, []
    here = context.locate(context.character) if context.character else None
    if here is None:
        return others[0], []
    return min(others, key=lambda c: _distance(here, context.locate(c))), []


def _distance(a, b) -> float:
    return math.inf if b is None else math.dist(a, b)


class _Ids:
    """Fresh behaviour ids (``nv1``, ``nv2``...) that no behaviour of the block uses."""

    def __init__(self, taken: set):
        self.taken = set(taken)
        self.count = 0

    def next(self) -> str:
        while True:
            self.count += 1
            name = f"nv{self.count}"
            if name not in self.taken:
                self.taken.add(name)
                return name


class _Marks:
    """The speech marks the generator adds: ``nvwK`` before word K, ``nveK`` after it (prefixed further when
    the author's marks already use the names)."""

    def __init__(self, speech):
        self.speech = speech
        existing = {m for m, _ in speech.marks}
        self.prefix = "nv"
        while any(m.startswith(self.prefix) for m in existing):
            self.prefix += "_"
        self.added: dict[str, int] = {}

    def onset(self, index: int, word: Word) -> str:
        return self._mark(f"{self.prefix}w{index}", word.start)

    def after(self, index: int, word: Word) -> str:
        return self._mark(f"{self.prefix}e{index}", word.end)

    def _mark(self, name: str, offset: int) -> str:
        self.added[name] = offset
        return name


def _speech_xml(speech, marks: _Marks) -> str:
    """The speech as BML 1.0 with its own marks and the added ones inline (its other attributes are kept on
    the block's own speech; this copy shows where the marks fall)."""
    at = sorted([(offset, name) for name, offset in marks.added.items()] + [(o, m) for m, o in speech.marks])
    pieces, last = [], 0
    for offset, name in at:
        pieces.append(escape(speech.text[last:offset]) + f"<sync id={quoteattr(name)}/>")
        last = offset
    pieces.append(escape(speech.text[last:]))
    return f"<speech id={quoteattr(speech.id)}><text>{''.join(pieces)}</text></speech>"


def _element(template: str, values: dict, behaviour_id: str, syncs: dict) -> str:
    """``template`` with its placeholders filled, an id and sync attributes."""
    text = _PLACEHOLDER.sub(lambda m: escape(str(values[m.group(1)]), {'"': "&quot;"}), template)
    attributes = f" id={quoteattr(behaviour_id)}" + "".join(f" {k}={quoteattr(v)}" for k, v in syncs.items())
    return _TAG.sub(lambda m: m.group(0) + attributes, text, count=1)


def _expressiveness(text: str | None) -> float:
    if text is None:
        return 1.0
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.0 <= value <= 3.0:
        raise GenerationError(f"infuse:expressiveness={text!r} is not a number from 0 to 3")
    return value


def _pinned_start(speech, dialect: str) -> float | None:
    """Seconds from its block's start at which a BML 1.0 speech is pinned (``start="0.2"``), else None."""
    ref = speech.sync_refs.get("start")
    return ref.time if dialect == "bml1.0" and ref is not None and ref.is_absolute else None


def _word_rules(rules: Rules, words: list[Word], onset, speech_id: str, marks: _Marks, ids: _Ids, rng, listener,
                objects: dict, taken: set, pinned: float | None, scale: float) -> list[_Placed]:
    """Every rule over every word, in order: an element where the rule matches, its draw (against its
    probability times ``scale``) passes, its
    placeholders name something, its channel has room and, when the speech is pinned at ``pinned`` seconds
    after its block's start, it need not start before the block."""
    placed: dict[str, list[float]] = {channel: [] for channel in rules.gap_s}
    pointed: set[tuple] = set()  # (sentence, who or what): one deictic at a target per sentence
    out = []
    questions = _question_words(words, rules.words["function"])
    for rule in rules.rules:
        if rule.channel in taken:
            continue
        for index, word in enumerate(words):
            if not _matches(rule.on, index, word, rules, objects, questions):
                continue
            if rng.random() >= min(rule.probability * scale, 1.0):
                continue
            anchor = _anchor(index, words, rules) if rule.on == "object" else index
            values = _values(rule.bml, index, words, rules, rng, listener, objects)
            if values is None:
                continue
            time_s = onset[words[anchor].start]
            if any(abs(time_s - t) < rules.gap_s[rule.channel] for t in placed[rule.channel]):
                continue
            if pinned is not None and pinned + time_s < rules.lead_s[rule.channel]:
                continue
            targets = {(word.sentence, values[k]) for k in ("object", "listener") if k in values}
            if targets & pointed:
                continue
            pointed |= targets
            placed[rule.channel].append(time_s)
            sync = {rule.sync: f"{speech_id}:{marks.onset(anchor, words[anchor])}"}
            out.append(_Placed(time_s, _element(rule.bml, values, ids.next(), sync)))
    return out


def _matches(on: str, index: int, word: Word, rules: Rules, objects: dict, questions: set) -> bool:
    if on == "accented":
        return word.accented
    if on == "object":
        return _object_of(word, objects) is not None
    if on == "question":
        return index in questions
    if on == "negation" and word.tag:
        return False
    return word.text in rules.words[on]


def _question_words(words: list[Word], function_words) -> set[int]:
    """Index of the last content word of each question."""
    last: dict[int, int] = {}
    for index, word in enumerate(words):
        if word.question and word.text not in function_words:
            last[word.sentence] = index
    return set(last.values())


def _object_of(word: Word, objects: dict) -> str | None:
    """The scene object a word names (its name, or its plural)."""
    return objects.get(word.text) or (objects.get(word.text[:-1]) if word.text.endswith("s") else None)


def _anchor(index: int, words: list[Word], rules: Rules) -> int:
    """Where an object's pointing strokes: a demonstrative up to ``object_lookahead_words`` before its name, else the name."""
    first = max(index - rules.object_lookahead_words, 0)
    for k in range(index - 1, first - 1, -1):
        if words[k].sentence != words[index].sentence:
            break
        if words[k].text in rules.words["demonstrative"]:
            return k
    return index


def _values(template: str, index: int, words: list[Word], rules: Rules, rng, listener, objects: dict) -> dict | None:
    """What the template's placeholders name, or None when one names nothing."""
    values = {}
    for name in set(_PLACEHOLDER.findall(template)):
        if name == "hand":
            modes, weights = zip(*rules.hands)
            values[name] = rng.choices(modes, weights)[0]
        elif name == "amplitude":
            values[name] = f"{rng.uniform(*rules.amplitude):.2f}"
        elif name == "listener":
            values[name] = listener
        elif name == "object":
            values[name] = _object_near(index, words, objects)
        elif name == "direction":
            values[name] = rng.choice(rules.gaze.directions)
        if values[name] is None:
            return None
    return values


def _object_near(index: int, words: list[Word], objects: dict) -> str | None:
    """The object word ``index`` names, else the object named nearest to it in its sentence."""
    named = [(abs(k - index), _object_of(w, objects)) for k, w in enumerate(words)
             if w.sentence == words[index].sentence and _object_of(w, objects) is not None]
    return min(named)[1] if named else None


def _gaze(rules: Rules, words: list[Word], onset, speech_id: str, marks: _Marks, ids: _Ids, rng, listener) -> list[_Placed]:
    """Aversion from the start of a long utterance; the look back at the listener on the word ``look_back_at``
    through it (an aversion without a look back lasts to the end)."""
    g = rules.gaze
    if len(words) < g.long_utterance_words:
        return []
    avert = rng.random() < g.aversion_probability
    look = rng.random() < g.look_back_probability
    back = min(max(int(round(g.look_back_at * len(words))), 1), len(words) - 1)
    back_sync = f"{speech_id}:{marks.onset(back, words[back])}"
    out = []
    if avert:
        values = {"listener": listener, "direction": rng.choice(g.directions)}
        end = back_sync if look else f"{speech_id}:end"
        out.append(_Placed(0.0, _element(g.aversion, values, ids.next(), {"start": f"{speech_id}:start", "end": end})))
    if look:
        out.append(_Placed(onset[words[back].start], _element(g.look_back, {"listener": listener}, ids.next(),
                                                              {"start": back_sync})))
    return out


def _backchannel(rules: Rules, words: list[Word], onset, speech_ref: str, marks: _Marks, ids: _Ids, rng) -> list[str]:
    """The listener's nods: on sentence or phrase ends after ``min_words`` words since the last one."""
    li = rules.listener
    out, since, last_s = [], 0, -math.inf
    for index, word in enumerate(words):
        since += 1
        ends = ("sentence_end" in li.on and word.sentence_end) or ("phrase_end" in li.on and word.phrase_end)
        if not ends or since < li.min_words:
            continue
        if rng.random() >= li.probability or onset[word.end] - last_s < li.gap_s:
            continue
        last_s, since = onset[word.end], 0
        sync = {li.sync: f"{speech_ref}:{marks.after(index, word)}"}
        out.append(_element(li.bml, {}, ids.next(), sync))
    return out
