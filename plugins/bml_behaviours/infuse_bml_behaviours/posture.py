"""``<posture>``, ``<postureShift>``, SmartBody's ``<body posture=...>`` and Greta's ``<torso>``.

A stance and its pose lexemes (BML 1.0 ``<stance type="STANDING"/><pose part="ARMS"
lexeme="ARMS_CROSSED"/>``, ``<stance type="SITTING"/><pose part="ARMS" lexeme="HANDS_ON_LAP"/>``), a
SmartBody posture name or a torso lexeme name a posture of the installed ``postures`` pack
(:mod:`.posture_lexicon`; with a stance, one of that stance); the plan then carries it as ``posture``
(and ``pack``) for the posture controller. A stance alone is its plain posture (``STANDING``: neutral,
``SITTING``: sitting upright). A SmartBody posture the character has a clip of keeps that clip. A name the
pack does not know, or a stance the pack has no posture of, warns here, naming what the pack knows. ``<posture>`` is temporary (into it by ``ready``, back out from ``relax``);
``<postureShift>`` and ``<body>`` last until the next one.
"""
from __future__ import annotations

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from . import posture_lexicon
from .common import Notes, number, with_sbm, word

#: A temporary posture (seconds): into it, held, back.
POSTURE_POINTS = {"start": 0.0, "ready": 1.0, "relax": 3.0, "end": 4.0}
SHIFT_DURATION_S = 1.0
#: SmartBody blends into a new idle posture over this long and keeps it.
BODY_TRANSITION_S = 0.5
#: BML 1.0's stances.
STANCES = ("SITTING", "CROUCHING", "STANDING", "LYING")
POSTURE_ATTRIBUTES = {"priority", "convanim:amount"}
BODY_ATTRIBUTES = {"posture"} | with_sbm("posture", "blend", "duration")
TORSO_ATTRIBUTES = {"lexeme"}


def _unknown(what: str, stance: str | None = None) -> str:
    return f"{what} names no{' ' + stance.lower() if stance else ''} posture of the postures pack " \
           f"(its postures: {posture_lexicon.described(stance)})"


def _stance_and_poses(behaviour, notes: Notes) -> dict:
    """The stance and poses of the behaviour, and the pack's posture they name (``posture``, ``pack``) when
    one does."""
    stance = next((c.attributes.get("type") for c in behaviour.children if c.name == "stance"), None)
    if stance and stance.upper() not in STANCES:
        notes.append(f"stance {stance!r} is not one of {', '.join(STANCES)}")
    poses = [{"part": c.attributes.get("part"), "lexeme": c.attributes.get("lexeme")}
             for c in behaviour.children if c.name == "pose"]
    if stance is None and not poses:
        raise BehaviourError("it has neither a <stance> nor a <pose>")
    parameters = {"stance": stance.upper() if stance else None, "poses": poses}
    if not posture_lexicon.known():
        return parameters
    stance = parameters["stance"]
    if stance not in (None, *posture_lexicon.STANCES):
        notes.append(f"stance {stance} is not realized: the postures pack has {' and '.join(posture_lexicon.STANCES)} "
                     f"postures only")
        return parameters
    found = None
    for pose in poses:
        found = posture_lexicon.lookup(pose["lexeme"], stance=stance)
        if found is not None:
            break
        notes.append(_unknown(f"pose {pose['part']}={pose['lexeme']}", stance))
    if found is None and stance is not None:
        found = posture_lexicon.plain(stance)  # the stance, its pose unnamed or unknown: its plain posture
    if found is not None:
        parameters.update(posture=found, pack=posture_lexicon.PACK)
    return parameters


def held_posture(posture: str, points: dict, notes: Notes) -> BehaviourPlan:
    """A temporary posture of the pack timed by ``points`` (sync point -> seconds): in by ``ready``, out
    from ``relax``."""
    return BehaviourPlan(TimingModel.from_points(points), "posture",
                         {"stance": None, "poses": [], "posture": posture, "pack": posture_lexicon.PACK}, notes=tuple(notes))


def plan_posture(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    parameters = _stance_and_poses(behaviour, notes)
    return BehaviourPlan(TimingModel.from_points(POSTURE_POINTS), "posture", parameters, notes=tuple(notes))


def plan_posture_shift(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    parameters = _stance_and_poses(behaviour, notes)
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "end": SHIFT_DURATION_S}), "posture", parameters,
                         True, tuple(notes))


def plan_body(behaviour, context) -> BehaviourPlan:
    """SmartBody ``<body posture=...>``: a lasting idle posture. SmartBody reads a plain number in ``ready`` as the
    time to blend into the posture from its start (``relax`` has no meaning for a lasting posture). A clip of
    the character of that name plays; else the pack's posture the name says."""
    notes = Notes()
    posture = word(behaviour, ("posture", "sbm:posture"))
    if posture is None:
        raise BehaviourError("it names no posture")
    transition = number(behaviour, with_sbm("duration"), BODY_TRANSITION_S, notes, minimum=0.0)
    own = frozenset()
    if context.dialect == "smartbody":
        own = frozenset(s for s in ("ready", "relax") if s in behaviour.sync_refs and behaviour.sync_refs[s].is_absolute)
        if "ready" in own:
            transition = max(behaviour.sync_refs["ready"].time, 0.0)
    points = {"start": 0.0, "ready": transition, "relax": transition, "end": transition}
    parameters = {"clip": posture, "stance": None, "poses": [], "transition_s": transition}
    if not context.clip_timing(posture) and posture_lexicon.known():
        found = posture_lexicon.lookup(posture)
        if found is None:
            notes.append(_unknown(f"posture {posture!r}"))
        else:
            parameters.update(clip=None, posture=found, pack=posture_lexicon.PACK, lexeme=posture)
    return BehaviourPlan(TimingModel.from_points(points), "posture", parameters, True, tuple(notes), own)


def plan_torso(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    lexeme = word(behaviour, "lexeme")
    if lexeme is None:
        raise BehaviourError("it has no lexeme")
    parameters = {"stance": None, "poses": [{"part": "TORSO", "lexeme": lexeme}]}
    if posture_lexicon.known():
        found = posture_lexicon.lookup(lexeme)
        if found is None:
            notes.append(_unknown(f"torso lexeme {lexeme!r}"))
        else:
            parameters.update(posture=found, pack=posture_lexicon.PACK)
    return BehaviourPlan(TimingModel.from_points(POSTURE_POINTS), "posture", parameters, notes=tuple(notes))
