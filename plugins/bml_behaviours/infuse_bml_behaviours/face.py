"""``<faceLexeme>``, ``<faceFacs>``, ``<faceShift>`` and the older ``<face>`` (SmartBody ``type="facs"``, draft
``<lexeme>`` child).

A lexeme is checked at scheduling against the installed controller that realizes face behaviours: one
it does not know (its constructor refuses it with a :class:`~infuse.errors.UsageError`, naming the
lexemes it knows) warns here and the behaviour is not shown.
"""
from __future__ import annotations

import re

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, number, word

#: Natural timing (seconds): onset to the attack peak, hold, offset.
FACE_POINTS = {"start": 0.0, "attackPeak": 0.3, "relax": 1.3, "end": 1.6}
# BML 1.0 gives face behaviours start, attackPeak, relax, end; other spellings of the same moments.
_ALIASES = {"ready": "attackPeak", "strokeStart": "attackPeak", "stroke": "attackPeak", "strokeEnd": "relax"}
#: A face shift's natural timing (seconds): the change of expression, which then lasts.
SHIFT_POINTS = {"start": 0.0, "end": 0.5}
SIDES = ("LEFT", "RIGHT", "BOTH")
LEXEME_ATTRIBUTES = {"lexeme", "amount", "overshoot"}
FACS_ATTRIBUTES = {"au", "side", "amount", "overshoot"}
FACE_ATTRIBUTES = {"type", "au", "side", "amount", "lexeme", "sbm:duration"}


def _timing() -> TimingModel:
    return TimingModel.from_points(FACE_POINTS, aliases=_ALIASES)


def _persistent(behaviour, context) -> bool:
    # SmartBody holds a facial expression it was given without an end until it is changed.
    return context.dialect == "smartbody" and not ({"relax", "end"} & set(behaviour.sync_refs))


def _check(lexeme: str) -> None:
    """Raise :class:`BehaviourError` when the installed face controller does not know ``lexeme``."""
    from infuse import registry
    from infuse.errors import UsageError

    descriptor = registry.realizer("face")
    if descriptor is None:
        return  # nothing realizes faces: the scene says so when it plays the block
    try:
        descriptor.factory(lexeme=lexeme)
    except UsageError as exc:
        raise BehaviourError(str(exc)) from None


def plan_lexeme(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    lexeme = word(behaviour, "lexeme")
    if lexeme is None:
        raise BehaviourError("it has no lexeme")
    _check(lexeme)
    parameters = {"kind": "lexeme", "lexeme": lexeme, "amount": number(behaviour, "amount", 0.5, notes, -1.0, 1.0)}
    return BehaviourPlan(_timing(), "face", parameters, _persistent(behaviour, context), tuple(notes))


def plan_shift(behaviour, context) -> BehaviourPlan:
    """BML 1.0 ``<faceShift lexeme>``: the expression comes in from start to end and stays until the next
    face shift (``shift``: the realizer ends the one before)."""
    notes = Notes()
    lexeme = word(behaviour, "lexeme")
    if lexeme is None:
        raise BehaviourError("it has no lexeme")
    _check(lexeme)
    parameters = {"kind": "lexeme", "lexeme": lexeme, "amount": number(behaviour, "amount", 0.5, notes, -1.0, 1.0),
                  "shift": True}
    timing = TimingModel.from_points(SHIFT_POINTS, aliases={"attackPeak": "end", "ready": "end", "stroke": "end"})
    return BehaviourPlan(timing, "face", parameters, True, tuple(notes))


def _action_unit(text: str, side: str | None, notes: Notes) -> tuple[int, str]:
    """``"12"``, ``"1_left"`` -> (12, "BOTH"), (1, "LEFT")."""
    m = re.fullmatch(r"\s*(\d+)\s*(?:_(left|right|both))?\s*", text, re.I)
    if not m:
        raise BehaviourError(f"au={text!r} is not an action unit number")
    side_text = (m.group(2) or side or "BOTH").upper()
    if side_text not in SIDES:
        notes.append(f"side {side_text!r} is not one of {', '.join(SIDES)}; BOTH is used")
        side_text = "BOTH"
    return int(m.group(1)), side_text


def plan_facs(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    au_text = word(behaviour, "au")
    if au_text is None:
        raise BehaviourError("it has no au")
    au, side = _action_unit(au_text, word(behaviour, "side"), notes)
    parameters = {"kind": "facs", "au": au, "side": side, "amount": number(behaviour, "amount", 0.5, notes, -1.0, 1.0)}
    return BehaviourPlan(_timing(), "face", parameters, _persistent(behaviour, context), tuple(notes))


def plan_face(behaviour, context) -> BehaviourPlan:
    """SmartBody ``<face type="facs" au=...>`` or the draft's ``<face><lexeme lexeme=.../></face>``."""
    if word(behaviour, "au") is not None or (word(behaviour, "type") or "").lower() == "facs":
        return plan_facs(behaviour, context)
    lexeme = word(behaviour, "lexeme") or next((c.attributes.get("lexeme") for c in behaviour.children
                                                if c.name == "lexeme" and c.attributes.get("lexeme")), None)
    if lexeme is None:
        raise BehaviourError("it has neither an au nor a lexeme")
    _check(lexeme)
    notes = Notes()
    parameters = {"kind": "lexeme", "lexeme": lexeme, "amount": number(behaviour, "amount", 0.5, notes, -1.0, 1.0)}
    return BehaviourPlan(_timing(), "face", parameters, _persistent(behaviour, context), tuple(notes))
