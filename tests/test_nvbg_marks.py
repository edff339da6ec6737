"""Word marks the TTS engine does not report (espeak-ng drops a mark between two sentences, where the
generator often puts one) are timed at the start of the word after them, never at 0 s."""
from __future__ import annotations

import pytest

from infuse import registry
from infuse.bml import EngineSpeechTimer
from infuse.bml.speech import mark_times
from infuse.speech import Utterance

from espeak_support import require_espeak

TEXT = "Hello there. First you go."


def test_a_mark_between_sentences_is_timed_at_its_word_with_espeak():
    require_espeak()
    engine = registry.get("tts", "espeak").factory()
    timing = EngineSpeechTimer(engine).time_speech(TEXT, [("first", 13), ("you", 19)])
    words = timing.details["words"]  # the words of that very synthesis (espeak's timing varies between calls)
    assert words[3][2] == "you"  # (espeak cuts the word after a dropped mark: "irst")
    assert timing.mark_times_s["first"] == pytest.approx(words[2][0], abs=1e-3) and words[2][0] > 0.5
    assert timing.mark_times_s["you"] == pytest.approx(words[3][0], abs=1e-3)


def test_without_the_engines_words_a_missing_mark_is_placed_by_its_place_in_the_text():
    timed = Utterance(TEXT, 2.0, [], words=[(0.0, 0.3, "Hello"), (0.3, 0.7, "there"), (0.9, 1.2, "First"),
                                        (1.2, 1.4, "you"), (1.4, 1.8, "go")], marks={"you": 1.21})
    assert mark_times(TEXT, [("first", 13), ("you", 19), ("end", len(TEXT))], timed) == \
        {"first": 0.9, "you": 1.21, "end": 2.0}
    untimed = Utterance(TEXT, 2.0, [], words=[], marks={})
    assert mark_times(TEXT, [("first", 13)], untimed)["first"] == pytest.approx(2.0 * 13 / len(TEXT))
