"""``<gesture>``, SmartBody's ``<animation>`` and ``<blend>``: clips from behaviour packs when
their timing is known, otherwise typical gesture phase durations.

A ``<gesture lexeme>`` (or ``name``) the character has no clip of that name for is looked up in the
installed ``gestures`` pack (:mod:`.gesture_lexicon`; then its ``type``) and timed by that gesture's phases; ``amplitude`` (1: as
authored), ``speed`` (1: as authored) and ``repeats`` (strokes) shape it. A lexeme naming a posture of the
``postures`` pack holds it over the gesture's span, and so does one naming a position the hands rest in
(Greta's ``rest=Lap``, ``allright_Pos_B``): the pack's posture of that name, else the neutral rest. A
lexeme the pack does not know warns here, naming it."""
from __future__ import annotations

import re

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from . import gesture_lexicon, posture_lexicon
from .common import Notes, clip_model, number, with_sbm, word
from .posture import held_posture

# Typical phase timing (seconds from start) of a beat and of larger gestures (deictic, iconic, metaphoric).
BEAT_POINTS = {"start": 0.0, "ready": 0.25, "strokeStart": 0.3, "stroke": 0.4, "strokeEnd": 0.55, "relax": 0.7, "end": 1.1}
GESTURE_POINTS = {"start": 0.0, "ready": 0.45, "strokeStart": 0.5, "stroke": 0.65, "strokeEnd": 0.85, "relax": 1.3, "end": 1.8}
ANIMATION_DEFAULT_S = 2.0
MODES = ("LEFT_HAND", "RIGHT_HAND", "BOTH_HANDS")
#: Words of a lexeme that, with a target, make a gesture point at it.
DEICTIC_WORDS = frozenset({"deictic", "point", "pointing"})
GESTURE_ATTRIBUTES = {"lexeme", "mode", "type", "name", "emotion", "target", "poststroke_hold", "amount", "amplitude",
                      "speed", "repeats"} | with_sbm(
    "joint-range", "frequency", "scale", "additive", "priority")
ANIMATION_ATTRIBUTES = {"name", "speed"} | with_sbm("speed", "additive", "joint-range", "priority")
#: Greta's lexemes of a position the hands rest in, not a stroke: ``rest=NAME`` and ``NAME_Pos_VARIANT``.
REST_POSITION = re.compile(r"^rest=(?P<rest>.+)$|^(?P<position>.+)_Pos_[A-Za-z0-9]+$", re.IGNORECASE)
BLEND_ATTRIBUTES = {"name", "x", "y", "z"} | with_sbm("wrap-mode", "schedule-mode", "blend-mode", "partial-joint")


def _mode(behaviour, notes: Notes) -> str | None:
    mode = (word(behaviour, "mode") or "").upper() or None
    if mode and mode not in MODES:
        notes.append(f"mode {mode!r} is not one of {', '.join(MODES)}; the default hand is used")
        return None
    return mode


def plan_gesture(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    lexeme = word(behaviour, "lexeme")
    clip = word(behaviour, "name") or lexeme
    if clip is None:
        raise BehaviourError("it has neither a lexeme nor a name")
    mode = _mode(behaviour, notes)
    hold = number(behaviour, "poststroke_hold", 0.0, notes, minimum=0.0)
    target = word(behaviour, "target")
    if target and lexeme and DEICTIC_WORDS & set(gesture_lexicon.words(lexeme)):
        return _deictic(behaviour, lexeme, target, mode, hold, notes)
    if not context.clip_timing(clip) and gesture_lexicon.known():
        # SmartBody's gesture maps name a variant in ``type`` (DEICTIC YOU, DEICTIC ME): tried when the lexeme fails.
        # A SmartBody animation name the character has no clip of is read like a lexeme (…_BeatMidRt01 is a beat).
        kind = word(behaviour, "type")
        found = gesture_lexicon.lookup(lexeme or clip, mode) or (gesture_lexicon.lookup(kind, mode) if kind else None)
        if found is not None:
            return _pack_gesture(behaviour, lexeme or clip, found, hold, notes, target,
                                 mode is None and gesture_lexicon.named_hand(lexeme or clip) is None)
        posture = (posture_lexicon.lookup(lexeme, words=False) or _rest_position(lexeme, notes)) if lexeme else None
        if posture is not None:  # a posture given as a gesture (Greta's ArmsCrossed): held over the gesture's span
            return held_posture(posture, GESTURE_POINTS, notes)
        if lexeme:
            notes.append(f"lexeme {lexeme!r} names no gesture of the gestures pack (its gestures: "
                         f"{', '.join(gesture_lexicon.gestures())})")
    default = BEAT_POINTS if "beat" in (lexeme or clip).lower() else GESTURE_POINTS
    timing, source = clip_model(context, clip, default)
    if hold:
        points = dict(zip(timing.sync_ids, timing.offsets_s))
        cut = points["strokeEnd"] if "strokeEnd" in points else points["end"]
        timing = TimingModel.from_points({s: t + (hold if t > cut else 0.0) for s, t in points.items()})
    parameters = {"lexeme": lexeme, "clip": clip, "timing_source": source, "mode": mode,
                  "type": word(behaviour, "type"), "emotion": word(behaviour, "emotion"),
                  "target": word(behaviour, "target"), "poststroke_hold_s": hold, "noise": _noise(behaviour, notes)}
    return BehaviourPlan(timing, "gesture", parameters, notes=tuple(notes))


def _rest_position(lexeme: str, notes: Notes) -> str | None:
    """The posture a rest-position lexeme (:data:`REST_POSITION`) holds: the pack's posture its name names, else
    the neutral rest (noted); None for any other lexeme."""
    match = REST_POSITION.match(lexeme.strip())
    if match is None:
        return None
    name = match["rest"] or match["position"]
    found = posture_lexicon.lookup(name, words=False)
    if found is None:
        found = posture_lexicon.plain("STANDING")
        notes.append(f"rest position {lexeme!r}: {name!r} names no posture of the postures pack; the hands rest in {found}")
    return found


def _deictic(behaviour, lexeme: str, target: str, mode: str | None, hold: float, notes: Notes) -> BehaviourPlan:
    """A deictic gesture at a target (``<gesture lexeme="DEICTIC" target=…>``): pointing at it, with a
    gesture's typical phases divided by ``speed``; the hand of ``mode``, else the one on the target's side."""
    speed = number(behaviour, "speed", 1.0, notes, minimum=0.05, maximum=20.0)
    points = {p: t / speed + (hold if p in ("relax", "end") else 0.0) for p, t in GESTURE_POINTS.items()}
    hand = gesture_lexicon.MODE_HANDS.get(mode or "") or gesture_lexicon.named_hand(lexeme) or "auto"
    parameters = {"lexeme": lexeme, "deictic": True, "target": target, "hand": hand, "pack": gesture_lexicon.PACK,
                  "timing_source": "typical", "speed": speed, "poststroke_hold_s": hold,
                  "noise": _noise(behaviour, notes)}
    return BehaviourPlan(TimingModel.from_points(points), "gesture", parameters, notes=tuple(notes))


def _pack_gesture(behaviour, lexeme: str, found, hold: float, notes: Notes, target: str | None = None,
                  free_hand: bool = False) -> BehaviourPlan:
    """The plan of a gesture of the gestures pack: its phases, divided by ``speed``, the stroke phase
    repeated ``repeats`` times, ``poststroke_hold`` seconds held after the stroke's end; aimed at
    ``target`` when given, by the hand on its side when the hand is ``free_hand`` (``hand_clips``)."""
    gesture, clip, phases, note = found
    if note:
        notes.append(note)
    speed = number(behaviour, "speed", 1.0, notes, minimum=0.05, maximum=20.0)
    amplitude = number(behaviour, "amplitude", 1.0, notes, minimum=0.05, maximum=3.0)
    repeats = int(round(number(behaviour, "repeats", 1.0, notes, minimum=1.0, maximum=20.0)))
    extra = 2.0 * (phases["stroke"] - phases["strokeStart"]) * (repeats - 1)
    points = {p: t + (extra if t > phases["stroke"] else 0.0) for p, t in phases.items()}
    points = {p: t / speed + (hold if p in ("relax", "end") else 0.0) for p, t in points.items()}
    parameters = {"lexeme": lexeme, "gesture": gesture, "clip": clip, "pack": gesture_lexicon.PACK,
                  "timing_source": "pack", "amplitude": amplitude, "speed": speed, "repeats": repeats,
                  "poststroke_hold_s": hold, "noise": _noise(behaviour, notes), "target": target}
    if target and free_hand:
        parameters["hand_clips"] = gesture_lexicon.hand_clips(gesture)
    return BehaviourPlan(TimingModel.from_points(points), "gesture", parameters, notes=tuple(notes))


def _noise(behaviour, notes: Notes) -> dict | None:
    """SmartBody's noise over a gesture: the joints of ``sbm:joint-range`` and its ``sbm:frequency`` and
    ``sbm:scale``; None when it asks for none."""
    noise = {k: number(behaviour, with_sbm(k), 0.0, notes) for k in ("frequency", "scale")
             if word(behaviour, with_sbm(k))}
    return {"joints": (word(behaviour, with_sbm("joint-range")) or "").split(), **noise} if noise else None


def plan_animation(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    name = word(behaviour, "name")
    if name is None:
        raise BehaviourError("it names no animation")
    speed = number(behaviour, ("speed", "sbm:speed"), 1.0, notes, minimum=1e-3)
    timing, source = clip_model(context, name, {"start": 0.0, "end": ANIMATION_DEFAULT_S}, speed)
    return BehaviourPlan(timing, "animation", {"clip": name, "speed": speed, "timing_source": source},
                         notes=tuple(notes))


def plan_blend(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    name = word(behaviour, "name")
    if name is None:
        raise BehaviourError("it names no blend")
    wrap = (word(behaviour, with_sbm("wrap-mode")) or "Loop").lower()
    timing, source = clip_model(context, name, {"start": 0.0, "end": ANIMATION_DEFAULT_S})
    parameters = {"blend": name, "wrap_mode": wrap, "timing_source": source,
                  "schedule_mode": word(behaviour, with_sbm("schedule-mode")),
                  "parameters": [number(behaviour, axis, 0.0, notes) for axis in ("x", "y", "z")
                                 if word(behaviour, axis) is not None]}
    return BehaviourPlan(timing, "blend", parameters, persistent=wrap == "loop", notes=tuple(notes))
