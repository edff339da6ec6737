"""``<gesture>``, ``<pointing>``, SmartBody's ``<animation>`` and ``<blend>``: clips from behaviour packs when
their timing is known, otherwise typical gesture phase durations."""
from __future__ import annotations

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, clip_model, number, with_sbm, word

# Typical phase timing (seconds from start) of a beat and of larger gestures (deictic, iconic, metaphoric).
BEAT_POINTS = {"start": 0.0, "ready": 0.25, "strokeStart": 0.3, "stroke": 0.4, "strokeEnd": 0.55, "relax": 0.7, "end": 1.1}
GESTURE_POINTS = {"start": 0.0, "ready": 0.45, "strokeStart": 0.5, "stroke": 0.65, "strokeEnd": 0.85, "relax": 1.3, "end": 1.8}
POINTING_POINTS = {"start": 0.0, "ready": 0.6, "strokeStart": 0.6, "stroke": 0.8, "strokeEnd": 1.6, "relax": 2.0, "end": 2.6}
ANIMATION_DEFAULT_S = 2.0
MODES = ("LEFT_HAND", "RIGHT_HAND", "BOTH_HANDS")
GESTURE_ATTRIBUTES = {"lexeme", "mode", "type", "name", "emotion", "target", "poststroke_hold", "amount"} | with_sbm(
    "joint-range", "frequency", "scale", "additive", "priority")
POINTING_ATTRIBUTES = {"target", "mode"}
ANIMATION_ATTRIBUTES = {"name", "speed"} | with_sbm("speed", "additive", "joint-range", "priority")
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
    default = BEAT_POINTS if "beat" in (lexeme or clip).lower() else GESTURE_POINTS
    timing, source = clip_model(context, clip, default)
    hold = number(behaviour, "poststroke_hold", 0.0, notes, minimum=0.0)
    if hold:
        points = dict(zip(timing.sync_ids, timing.offsets_s))
        cut = points["strokeEnd"] if "strokeEnd" in points else points["end"]
        timing = TimingModel.from_points({s: t + (hold if t > cut else 0.0) for s, t in points.items()})
    noise = {k: number(behaviour, with_sbm(k), 0.0, notes) for k in ("frequency", "scale")
             if word(behaviour, with_sbm(k))}
    parameters = {"lexeme": lexeme, "clip": clip, "timing_source": source, "mode": _mode(behaviour, notes),
                  "type": word(behaviour, "type"), "emotion": word(behaviour, "emotion"),
                  "target": word(behaviour, "target"), "poststroke_hold_s": hold,
                  "noise": ({"joints": (word(behaviour, with_sbm("joint-range")) or "").split(), **noise}
                            if noise else None)}
    return BehaviourPlan(timing, "gesture", parameters, notes=tuple(notes))


def plan_pointing(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    target = word(behaviour, "target")
    if target is None:
        raise BehaviourError("it has no target")
    return BehaviourPlan(TimingModel.from_points(POINTING_POINTS), "pointing",
                         {"target": target, "mode": _mode(behaviour, notes)}, notes=tuple(notes))


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
