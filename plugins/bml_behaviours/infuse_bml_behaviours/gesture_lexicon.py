"""BML gesture lexemes -> a gesture of the installed ``gestures`` pack, read from the pack's manifest.

Each gesture clip of the pack lists the lexemes it realizes as tags (lower case) and its hand. A
lexeme matches a gesture when the whole lexeme is one of its tags, else when one of its words is
(words split at ``_``, ``-``, spaces and lower-to-upper case changes, trailing digits dropped:
``greta_beat4`` -> ``greta``, ``beat``). A final word ``L``/``R``/``B`` (or ``Lt``, ``Rt``, ``left``,
``right``, ``both``) names the hand when the BML gives no mode.
"""
from __future__ import annotations

import re
from functools import lru_cache

PACK = "gestures"
HAND_WORDS = {"l": "left", "lt": "left", "left": "left", "r": "right", "rt": "right", "right": "right",
              "b": "both", "both": "both"}
MODE_HANDS = {"LEFT_HAND": "left", "RIGHT_HAND": "right", "BOTH_HANDS": "both"}


@lru_cache(maxsize=1)
def _lexicon() -> tuple[dict, dict] | None:
    """(tag -> gesture, gesture -> {hand: (clip name, phases in seconds)}) of the installed pack, or None."""
    from infuse import registry
    from infuse.errors import InfuseError
    from infuse.packs import load_pack

    if PACK not in registry.table("behaviour-pack"):
        return None
    try:
        doc = load_pack(PACK).require_built()
    except InfuseError:
        return None
    tags, clips = {}, {}
    for c in doc["clips"]:
        if "sync" not in c or not c["tags"]:
            continue
        gesture = c["tags"][0]
        clips.setdefault(gesture, {})[c["hand"]] = (c["name"], {"start": 0.0, **c["sync"], "end": float(c["duration"])})
        for tag in c["tags"]:
            tags.setdefault(tag, gesture)
    return tags, clips


def _words(lexeme: str) -> list[str]:
    spaced = re.sub(r"([a-z])([A-Z])", r"\1 \2", lexeme)
    return [w.rstrip("0123456789").lower() for w in re.split(r"[_\-\s]+", spaced) if w.rstrip("0123456789")]


def known() -> bool:
    """Whether a gestures pack is installed."""
    return _lexicon() is not None


def lookup(lexeme: str, mode: str | None) -> tuple[str, str, dict, str | None] | None:
    """(gesture, clip name, phases, note) for ``lexeme`` played in BML ``mode``, or None when no gesture
    of the pack matches. The note says when the hand asked for is not available."""
    lexicon = _lexicon()
    if lexicon is None:
        return None
    tags, clips = lexicon
    words = _words(lexeme)
    gesture = tags.get(lexeme.lower()) or next((tags[w] for w in words if w in tags), None)
    if gesture is None:
        return None
    hand = MODE_HANDS.get(mode or "") or (HAND_WORDS.get(words[-1]) if len(words) > 1 else None) or "right"
    hands = clips[gesture]
    note = None
    if hand not in hands:
        chosen = "right" if "right" in hands else next(iter(hands))
        note = f"gesture {gesture!r} is not made for {hand} hands; the {chosen} hand plays it"
        hand = chosen
    name, phases = hands[hand]
    return gesture, name, dict(phases), note


def gestures() -> list[str]:
    """The installed pack's gestures (their lexemes are listed in its manifest and docs/bml.md)."""
    lexicon = _lexicon()
    return sorted(lexicon[1]) if lexicon else []
