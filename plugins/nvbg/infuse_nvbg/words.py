"""An utterance's words: where each starts and ends in the text, its sentence and phrase, whether it is
accented (a new content word, the words a speaker stresses with pitch accents and beats), and whether it
is the auxiliary of a question tag ("isn't it?", "don't you?"), which asks rather than denies."""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

_WORD = re.compile(r"[^\W_](?:[\w'’-]*[^\W_])?")
_SENTENCE_END = re.compile(r"[.!?]")
_PHRASE_END = re.compile(r"[,;:—–]")


@dataclass(frozen=True)
class Word:
    """One word: ``text`` lower-case (curly apostrophes straightened), ``start``/``end`` character offsets in
    the utterance, its ``sentence`` index, ``question`` (its sentence ends in "?"), ``sentence_end`` and
    ``phrase_end`` (punctuation follows it), ``accented``, ``tag`` (a contracted negative auxiliary one word
    before the end of a question)."""

    text: str
    start: int
    end: int
    sentence: int
    question: bool = False
    sentence_end: bool = False
    phrase_end: bool = False
    accented: bool = False
    tag: bool = False


def words_of(text: str, function_words: frozenset, said: tuple[str, ...] = ()) -> list[Word]:
    """The words of ``text``; a content word (not in ``function_words``, three letters or more) is accented
    the first time the utterance says it, unless one of the texts ``said`` before it has it (it is given)."""
    found = [(word, m.start(), m.end()) for word, m in _words(text)]
    out: list[Word] = []
    sentence, first = 0, 0
    seen = {word for earlier in said for word, _ in _words(earlier)}
    for k, (word, start, end) in enumerate(found):
        gap = text[end:found[k + 1][1]] if k + 1 < len(found) else text[end:]
        ends_sentence = bool(_SENTENCE_END.search(gap)) or k + 1 == len(found)
        content = word not in function_words and len(word) >= 3
        out.append(Word(word, start, end, sentence, sentence_end=ends_sentence,
                        phrase_end=not ends_sentence and bool(_PHRASE_END.search(gap)),
                        accented=content and word not in seen))
        seen.add(word)
        if ends_sentence:
            if "?" in gap:
                out[first:] = [replace(w, question=True) for w in out[first:]]
                if len(out) - first >= 3 and out[-2].text.endswith("n't"):
                    out[-2] = replace(out[-2], tag=True)
            first, sentence = len(out), sentence + 1
    return out


def _words(text: str):
    """(lower-case word, match) of each word of ``text``."""
    return [(m.group(0).lower().replace("’", "'"), m) for m in _WORD.finditer(text)]
