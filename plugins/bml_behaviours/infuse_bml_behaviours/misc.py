"""``<wait>``, ``<event>``, ``<saccade>``, ``<sbm:noise>`` and ASAP's blink and breathing emitters."""
from __future__ import annotations

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, number, with_sbm, word

SACCADE_MODES = ("talk", "listen", "think")
WAIT_ATTRIBUTES = {"max-wait", "condition"}
EVENT_ATTRIBUTES = {"message"} | with_sbm("message")
SACCADE_ATTRIBUTES = {"mode", "finish", "angle-limit"} | with_sbm("mode", "finish", "angle-limit")
NOISE_ATTRIBUTES = {"joints", "frequency", "scale", "type"} | with_sbm("joints", "frequency", "scale", "joint-range")
EMITTER_ATTRIBUTES = {"range", "avgwaitingtime"}


def _instant(controller: str, parameters: dict, persistent: bool = False, notes=()) -> BehaviourPlan:
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "end": 0.0}), controller, parameters, persistent,
                         tuple(notes))


def plan_wait(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    duration = number(behaviour, "max-wait", 0.0, notes, minimum=0.0)
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "end": duration}), "wait",
                         {"condition": word(behaviour, "condition")}, notes=tuple(notes))


def plan_event(behaviour, context) -> BehaviourPlan:
    message = word(behaviour, ("message", "sbm:message")) or (behaviour.text or "").strip() or None
    if message is None:
        raise BehaviourError("it carries no message")
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "stroke": 0.0, "end": 0.0}), "event",
                         {"message": message})


def plan_saccade(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    mode = (word(behaviour, ("mode", "sbm:mode")) or "talk").lower()
    if mode not in SACCADE_MODES:
        notes.append(f"saccade mode {mode!r} is not one of {', '.join(SACCADE_MODES)}; talk is used")
        mode = "talk"
    finish = (word(behaviour, ("finish", "sbm:finish")) or "").lower() == "true"
    return _instant("saccade", {"mode": mode, "enabled": not finish,
                                "angle_limit_deg": number(behaviour, ("angle-limit", "sbm:angle-limit"), 0.0, notes) or None},
                    persistent=True, notes=notes)


def plan_noise(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    joints = (word(behaviour, ("joints", "sbm:joints", "sbm:joint-range")) or "").split()
    parameters = {"joints": joints, "frequency_hz": number(behaviour, with_sbm("frequency"), 0.05, notes, minimum=0.0),
                  "scale": number(behaviour, with_sbm("scale"), 0.02, notes, minimum=0.0), "type": word(behaviour, "type")}
    return _instant("noise", parameters, persistent=True, notes=notes)


def plan_blink_emitter(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    return _instant("blink", {"mean_interval_s": number(behaviour, "avgwaitingtime", 4.0, notes, minimum=0.0),
                              "interval_range_s": number(behaviour, "range", 0.0, notes, minimum=0.0)}, True, notes)


def plan_breathing_emitter(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    return _instant("breathing", {"mean_interval_s": number(behaviour, "avgwaitingtime", 4.0, notes, minimum=0.0),
                                  "interval_range_s": number(behaviour, "range", 0.0, notes, minimum=0.0)}, True, notes)
