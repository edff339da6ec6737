"""SmartBody's ``<sbm:reach>`` (touch, pick-up, put-down, point-at), ``<sbm:grab>``, ``<touch>`` and ``<sbm:constraint>``."""
from __future__ import annotations

import math

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, flag, floats, number, with_sbm, word

ACTIONS = ("touch", "pick-up", "put-down", "point-at")
REACH_DURATION_S = 1.0
#: How long the hand stays at a touched or pointed-at target before it returns, seconds.
TOUCH_HOLD_S = 0.5
#: Closing the hand on an object, seconds.
GRASP_S = 0.3
WALK_SPEED_M_S = 1.2
REACH_ATTRIBUTES = {"target"} | with_sbm("action", "reach-type", "reach-duration", "reach-finish", "use-locomotion",
                                          "target-pos", "handle", "apex-duration", "fade-in", "fade-out", "foot-ik")
GRAB_ATTRIBUTES = {"target"} | with_sbm("handle", "grab-type", "grab-state", "wrist", "source-joint", "grab-velocity",
                                         "reach-type")
TOUCH_ATTRIBUTES = {"target", "mode"} | with_sbm("reach-type", "reach-duration")
CONSTRAINT_ATTRIBUTES = {"effector", "target"} | with_sbm("effector-root", "handle", "fade-in", "fade-out",
                                                           "constraint-type", "offset")


def _target(behaviour, notes: Notes):
    target = word(behaviour, "target")
    text = word(behaviour, with_sbm("target-pos"))
    position = floats(text, 3) if text else None
    if text and position is None:
        notes.append(f"target-pos={text!r} is not three numbers and is ignored")
    return target, position


def _walk_s(context, target) -> float:
    """Time to walk up to ``target`` first, when both it and the character can be located."""
    if not target or not context.character:
        return 0.0
    here, there = context.locate(context.character), context.locate(target)
    if here is None or there is None:
        return 0.0
    return math.dist((here[0], here[2]), (there[0], there[2])) / WALK_SPEED_M_S


def plan_reach(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    action = (word(behaviour, with_sbm("action")) or "touch").lower()
    finish = flag(behaviour, with_sbm("reach-finish"))
    target, position = _target(behaviour, notes)
    hand = (word(behaviour, with_sbm("reach-type")) or "").lower() or None
    if hand not in (None, "left", "right"):
        notes.append(f"reach-type {hand!r} is neither left nor right; the nearer hand is used")
        hand = None
    duration = number(behaviour, with_sbm("reach-duration"), REACH_DURATION_S, notes, minimum=0.0)
    if target is None and position is None:
        if not finish:
            raise BehaviourError("it has no target")
        action = "finish"  # SmartBody: end the current reach and return the hand
    elif action not in ACTIONS:
        raise BehaviourError(f"action {action!r} is not one of {', '.join(ACTIONS)}")
    walk = _walk_s(context, target) if flag(behaviour, with_sbm("use-locomotion")) else 0.0
    arrive = walk + duration
    if action == "finish":
        points, persistent = {"start": 0.0, "end": duration}, False
    elif action == "pick-up":
        points, persistent = {"start": 0.0, "ready": arrive, "stroke": arrive, "relax": arrive + GRASP_S,
                              "end": arrive + GRASP_S}, True
    elif action == "put-down":
        points, persistent = {"start": 0.0, "ready": arrive, "stroke": arrive, "relax": arrive + GRASP_S,
                              "end": arrive + GRASP_S + duration}, False
    else:
        persistent = not finish
        relax = arrive + TOUCH_HOLD_S
        points = {"start": 0.0, "ready": arrive, "stroke": arrive, "relax": relax,
                  "end": relax + (duration if finish else 0.0)}
    parameters = {"action": action, "target": target, "target_position": position, "hand": hand,
                  "reach_duration_s": duration, "finish": finish, "use_locomotion": walk > 0 or flag(behaviour, with_sbm("use-locomotion")),
                  "handle": word(behaviour, with_sbm("handle"))}
    return BehaviourPlan(TimingModel.from_points(points), "reach", parameters, persistent, tuple(notes))


def plan_touch(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    target, _ = _target(behaviour, notes)
    if target is None:
        raise BehaviourError("it has no target")
    duration = number(behaviour, with_sbm("reach-duration"), REACH_DURATION_S, notes, minimum=0.0)
    points = {"start": 0.0, "ready": duration, "stroke": duration, "relax": duration + TOUCH_HOLD_S,
              "end": 2 * duration + TOUCH_HOLD_S}
    hand = (word(behaviour, with_sbm("reach-type")) or "").lower() or None
    return BehaviourPlan(TimingModel.from_points(points), "reach",
                         {"action": "touch", "target": target, "target_position": None, "hand": hand,
                          "reach_duration_s": duration, "finish": True, "use_locomotion": False, "handle": None},
                         notes=tuple(notes))


def plan_grab(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    target = word(behaviour, "target")
    state = (word(behaviour, with_sbm("grab-state")) or "start").lower()
    if target is None and state == "start":
        raise BehaviourError("it has no target")
    points = {"start": 0.0, "ready": GRASP_S, "stroke": GRASP_S, "end": GRASP_S}
    parameters = {"target": target, "state": state, "handle": word(behaviour, with_sbm("handle")),
                  "hand": (word(behaviour, with_sbm("reach-type")) or "").lower() or None,
                  "wrist": word(behaviour, with_sbm("wrist"))}
    return BehaviourPlan(TimingModel.from_points(points), "grab", parameters, state != "finish", tuple(notes))


def plan_constraint(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    effector, target = word(behaviour, "effector"), word(behaviour, "target")
    if effector is None or target is None:
        raise BehaviourError("it needs an effector and a target")
    fade_in = number(behaviour, with_sbm("fade-in"), 0.0, notes, minimum=0.0)
    parameters = {"effector": effector, "effector_root": word(behaviour, with_sbm("effector-root")), "target": target,
                  "handle": word(behaviour, with_sbm("handle")), "fade_in_s": fade_in,
                  "fade_out_s": number(behaviour, with_sbm("fade-out"), 0.0, notes, minimum=0.0)}
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "ready": fade_in, "end": fade_in}), "ik_constraint",
                         parameters, True, tuple(notes))
