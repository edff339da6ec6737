"""The nonverbal generator's rate and timing against published figures (docs/nonverbal.md cites them):

- Shattuck-Hufnagel & Ren (2018, Front. Psychol. 9:1514): 1,334 gestures in 20 minutes of academic-lecture
  speech, 67 a minute, a gesture-rich style; their strokes fall on pitch-accented syllables, as Loehr (2004)
  found in conversation. The generator stays below that rate (at least a third of it is our own aim for an
  explaining speaker) and puts every hand stroke on the onset of a new content word or of a word its rules name.
- Kendon (1967, as summarized by Rutter et al., 1978): over 70 % of long utterances begin with the speaker looking
  away and over 70 % end with the speaker looking at the listener.
"""
from __future__ import annotations

import numpy as np
import pytest

from infuse.bml import Scheduler
from infuse_nvbg.rules import load_rules
from infuse_nvbg.words import words_of

#: An explaining speaker's turns: instructions, a description, questions, agreement and disagreement.
UTTERANCES = (
    "Let me explain how the machine works.",
    "First, the water comes in through the pipe at the top, and it fills the small tank.",
    "Then the pump pushes it through the filter, which takes out the sand and the dirt.",
    "The clean water goes into the big tank over there, and the whole process starts again.",
    "Is that clear so far?",
    "No, the filter is not the problem; the pump is.",
    "Yes, exactly, you have to open the valve before you switch it on.",
    "I checked it myself yesterday, and I really think we should replace it.",
    "It is a huge job, but it only takes a couple of hours if two people help.",
    "Maybe we can do it next week, when the weather is better.",
    "On the one hand it costs money, but on the other hand the old one keeps breaking.",
    "Do you want me to call the company, or will you do it?",
    "Hello, my name is Anna, and I look after the garden and the greenhouse.",
    "Every morning I water the plants, check the temperature and open the windows.",
    "The tomatoes grow very fast in summer, so we pick them twice a week.",
    "Here is the cup I told you about; it belonged to my grandmother.",
    "Never leave the door open at night, because the cats come in and knock everything over.",
    "Okay, so that is the plan for tomorrow: we meet at nine, we load the van and we drive to the coast.",
)
CAST = {"ann": "character", "bob": "character", "cup": "object"}
LECTURE_GESTURES_PER_MINUTE = 1334 / 20.0
HAND = ("gesture", "pointing")


def scheduled(text: str, block_id: str, seed: int):
    scheduler = Scheduler(names=lambda: CAST, seed=seed)
    records = scheduler.submit(f'<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:infuse="urn:infuse:bml" '
                               f'id="{block_id}" characterId="ann" infuse:nonverbal="true">'
                               f'<speech id="s1"><text>{text}</text></speech></bml>')
    return records[0]


def rate(seed: int) -> tuple[float, float]:
    """(hand gestures per minute of speech, per word) over the utterances."""
    gestures = words = 0
    seconds = 0.0
    for k, text in enumerate(UTTERANCES):
        record = scheduled(text, f"u{k}", seed)
        speech = record.activation("s1")
        seconds += speech.end - speech.start
        words += len(text.split())
        gestures += sum(a.controller in HAND for a in record.activations)
    return gestures / seconds * 60.0, gestures / words


def test_the_gesture_rate_stays_below_gesture_rich_lecture_speech():
    rates = np.array([rate(seed) for seed in range(5)])
    per_minute = rates[:, 0]
    assert np.all(per_minute <= LECTURE_GESTURES_PER_MINUTE)
    assert np.all(per_minute >= LECTURE_GESTURES_PER_MINUTE / 3)
    assert 0.12 <= rates[:, 1].mean() <= 0.3  # hand gestures per spoken word (about one every five words)


def test_every_hand_stroke_is_on_an_accented_or_named_word():
    rules = load_rules()
    named = {w for r in rules.rules if r.channel == "hands" and r.on in rules.words for w in rules.words[r.on]}
    named |= rules.words["demonstrative"] | {"cup", "cups"}
    strokes = 0
    for k, text in enumerate(UTTERANCES):
        record = scheduled(text, f"u{k}", seed=1)
        words = {w.start: w for w in words_of(text, rules.words["function"])}
        speech = next(b for b in record.block.behaviours if b.id == "s1")
        offsets = dict(speech.marks)
        for b in record.block.behaviours:
            if b.element in HAND:
                word = words[offsets[b.sync_refs["stroke"].sync]]
                assert word.accented or word.text in named, (text, word)
                strokes += 1
    assert strokes >= len(UTTERANCES)


@pytest.mark.parametrize("what", ["aversion", "look back"])
def test_gaze_at_turn_start_and_end_as_kendon_measured(what):
    text = "Well, the thing about this old machine is that nobody really remembers how it was built."
    hits = 0
    n = 400
    for seed in range(n):
        record = scheduled(text, "turn", seed)
        elements = {a.element for a in record.activations if a.behaviour.startswith("nv")}
        hits += ("gaze" if what == "aversion" else "gazeShift") in elements
    assert 0.70 <= hits / n <= 0.80  # the rules draw 0.75; Kendon: over 70 %
