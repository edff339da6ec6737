"""BML posture names -> a posture of the installed ``postures`` pack, read from the pack's manifest.

Each posture clip of the pack lists, as tags (lower case), its name and the lexemes it realizes (BML
1.0 pose lexemes such as ``ARMS_CROSSED``, SmartBody's and other realizers' words). A name matches a
posture when the whole name is one of its tags (also with ``_``, ``-`` and spaces removed:
``ArmsCrossed``), else when two neighbouring words of it are (``ChrBrad@Idle01_ArmsCrossed`` ->
``arms_crossed``), else when one word is (``ChrMarine@Idle01`` -> ``idle``: neutral). Words are split at
``_``, ``-``, ``@``, ``.``, spaces and lower-to-upper case changes, trailing digits dropped. A more
specific posture wins over the neutral one.

A posture tagged ``seated`` is a ``SITTING`` one, the others ``STANDING``; the first of each stance is
its plain posture (the stance named alone). With a stance, only postures of that stance match.
"""
from __future__ import annotations

import re
from functools import lru_cache

PACK = "postures"
NEUTRAL = "neutral"
#: The stances the pack's postures have, and the tag that makes a posture seated.
STANCES = ("STANDING", "SITTING")
SEATED_TAG = "seated"


@lru_cache(maxsize=1)
def _lexicon() -> tuple[dict, dict, dict] | None:
    """(tag -> postures, posture -> its BML lexemes in manifest order, posture -> its stance) of the installed
    pack, or None."""
    from infuse import registry
    from infuse.errors import InfuseError
    from infuse.packs import load_pack

    if PACK not in registry.table("behaviour-pack"):
        return None
    try:
        doc = load_pack(PACK).require_built()
    except InfuseError:
        return None
    tags, lexemes, stances = {}, {}, {}
    for c in doc["clips"]:
        if c.get("role") != "posture":
            continue
        lexemes[c["name"]] = [t.upper() for t in c["tags"]] or [c["name"].upper()]
        stances[c["name"]] = "SITTING" if SEATED_TAG in c["tags"] else "STANDING"
        for tag in (c["name"], *c["tags"]):
            for key in (tag, _squashed(tag)):
                if c["name"] not in tags.setdefault(key, []):
                    tags[key].append(c["name"])
    return tags, lexemes, stances


def _squashed(name: str) -> str:
    return re.sub(r"[\s_\-.@]+", "", name).lower()


def _words(name: str) -> list[str]:
    spaced = re.sub(r"([a-z])([A-Z])", r"\1 \2", name)
    return [w.rstrip("0123456789").lower() for w in re.split(r"[_\-@.\s]+", spaced) if w.rstrip("0123456789")]


def known() -> bool:
    """Whether a postures pack is installed."""
    return _lexicon() is not None


def lookup(name: str | None, words: bool = True, stance: str | None = None) -> str | None:
    """The posture of the pack that ``name`` (a lexeme, a SmartBody posture, a Greta torso lexeme) names, or None;
    ``words=False``: only the whole name (a gesture lexeme naming a posture); ``stance``: only a posture of it."""
    lexicon = _lexicon()
    if lexicon is None or not name or not name.strip():
        return None
    tags, _, stances = lexicon

    def first(key: str) -> str | None:
        return next((p for p in tags.get(key, ()) if stance is None or stances[p] == stance), None)

    whole = first(name.strip().lower()) or first(_squashed(name))
    if whole is not None or not words:
        return whole
    parts = _words(name)
    pairs = [f"{a}_{b}" for a, b in zip(parts, parts[1:])]
    found = [p for p in (first(k) for k in pairs + parts) if p is not None]
    return next((p for p in found if p != NEUTRAL), found[0] if found else None)


def plain(stance: str) -> str | None:
    """The posture a stance named alone takes: the pack's first of that stance (``STANDING``: neutral)."""
    lexicon = _lexicon()
    if lexicon is None:
        return None
    if stance == "STANDING" and NEUTRAL in lexicon[2]:
        return NEUTRAL
    return next((p for p, s in lexicon[2].items() if s == stance), None)


def postures() -> list[str]:
    """The installed pack's postures."""
    lexicon = _lexicon()
    return list(lexicon[1]) if lexicon else []


def described(stance: str | None = None) -> str:
    """The pack's postures (of ``stance`` when given) with the first lexemes each realizes, for warnings:
    ``arms_crossed (ARMS_CROSSED, ...)``."""
    lexicon = _lexicon()
    if lexicon is None:
        return "no postures pack is installed"
    return "; ".join(f"{p} ({', '.join(lex[:3])})" for p, lex in lexicon[1].items()
                     if stance is None or lexicon[2][p] == stance)
