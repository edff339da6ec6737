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


def words(lexeme: str) -> list[str]:
    """The lexeme's words, lower case (see the module doc)."""
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
    gesture = tags.get(lexeme.lower()) or next((tags[w] for w in words(lexeme) if w in tags), None)
    if gesture is None:
        return None
    hand = MODE_HANDS.get(mode or "") or named_hand(lexeme) or "right"
    hands = clips[gesture]
    note = None
    if hand not in hands:
        chosen = "right" if "right" in hands else next(iter(hands))
        note = f"gesture {gesture!r} is not made for {hand} hands; the {chosen} hand plays it"
        hand = chosen
    name, phases = hands[hand]
    return gesture, name, dict(phases), note


def named_hand(lexeme: str) -> str | None:
    """The hand ("left", "right", "both") a lexeme's last word names, or None."""
    found = words(lexeme)
    return HAND_WORDS.get(found[-1]) if len(found) > 1 else None


def hand_clips(gesture: str) -> dict[str, str]:
    """Clip name of ``gesture`` per single hand ("left", "right") the pack has it for."""
    lexicon = _lexicon()
    clips = lexicon[1].get(gesture, {}) if lexicon else {}
    return {hand: clips[hand][0] for hand in ("left", "right") if hand in clips}


def gestures() -> list[str]:
    """The installed pack's gestures (their lexemes are listed in its manifest and docs/bml.md)."""
    lexicon = _lexicon()
    return sorted(lexicon[1]) if lexicon else []
