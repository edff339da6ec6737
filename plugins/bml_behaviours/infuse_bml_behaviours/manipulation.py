"""``<pointing>``, SmartBody's ``<sbm:reach>`` (touch, pick-up, put-down, point-at), ``<sbm:grab>``, ``<touch>`` and
``<sbm:constraint>``.

``<pointing>`` and ``sbm:reach action="point-at"`` plan a ``pointing`` behaviour: the hand rises until
``ready``, reaches out furthest at ``stroke``, holds until ``relax`` and returns by ``end``. ``sbm:grab``
plans a ``grab``: the hand at the object at ``ready``, closed on it at ``stroke``, held from then on
(persistent) until a ``sbm:grab-state="release"`` (or ``"finish"``) lets it go.
"""
from __future__ import annotations

import math

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, flag, floats, number, with_sbm, word

#: Natural phase times of a pointing (seconds from its start).
POINTING_POINTS = {"start": 0.0, "ready": 0.6, "strokeStart": 0.6, "stroke": 0.8, "strokeEnd": 1.6, "relax": 2.0,
                   "end": 2.6}
#: BML 1.0 ``mode`` -> the pointing hand.
POINTING_MODES = {"LEFT_HAND": "left", "RIGHT_HAND": "right", "BOTH_HANDS": "both"}
POINTING_ATTRIBUTES = {"target", "mode"} | with_sbm("target-pos")
#: A pointing reach (``point-at``) holds its stroke this long before it relaxes, seconds.
POINT_HOLD_S = 1.0
#: The pointing arm's return, seconds.
POINT_RETURN_S = 0.6
GRAB_STATES = ("start", "reach", "release", "finish")
#: A constraint's fade in and out when the BML gives none, seconds.
CONSTRAINT_FADE_S = 0.3
#: Natural span of a constraint given an end, after its fade-in, seconds (the end given stretches it).
CONSTRAINT_HOLD_S = 1.0
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
                                         "reach-type", "reach-duration")
TOUCH_ATTRIBUTES = {"target", "mode"} | with_sbm("reach-type", "reach-duration")
CONSTRAINT_ATTRIBUTES = {"effector", "target"} | with_sbm("effector-root", "handle", "fade-in", "fade-out",
                                                           "constraint-type", "offset", "target-pos")


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
    if action == "point-at":
        if walk:
            notes.append("a pointing reach does not walk first; use-locomotion is ignored")
        points = {"start": 0.0, "ready": duration, "stroke": duration, "relax": duration + POINT_HOLD_S,
                  "end": duration + POINT_HOLD_S + POINT_RETURN_S}
        return BehaviourPlan(TimingModel.from_points(points), "pointing",
                             {"target": target, "target_position": position, "hand": hand}, notes=tuple(notes))
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
    if state not in GRAB_STATES:
        raise BehaviourError(f"grab-state {state!r} is not one of {', '.join(GRAB_STATES)}")
    hand = (word(behaviour, with_sbm("reach-type")) or "").lower() or None
    if hand not in (None, "left", "right"):
        notes.append(f"reach-type {hand!r} is neither left nor right; the nearer hand is used")
        hand = None
    parameters = {"target": target, "state": state, "handle": word(behaviour, with_sbm("handle")), "hand": hand,
                  "wrist": word(behaviour, with_sbm("wrist"))}
    for name, instead in (("grab-type", "the hand closes as a grip"), ("grab-velocity", f"the hand closes in {GRASP_S:g} s"),
                          ("source-joint", "the wrist holds the object")):
        if word(behaviour, with_sbm(name)) is not None:
            notes.append(f"{name} is not used: {instead}")
    if state in ("release", "finish"):
        return BehaviourPlan(TimingModel.from_points({"start": 0.0, "ready": GRASP_S, "stroke": GRASP_S, "end": GRASP_S}),
                             "grab", parameters, notes=tuple(notes))
    if target is None:
        raise BehaviourError("it has no target")
    reach = number(behaviour, with_sbm("reach-duration"), REACH_DURATION_S, notes, minimum=0.0)
    points = {"start": 0.0, "ready": reach, "stroke": reach + GRASP_S, "end": reach + GRASP_S}
    return BehaviourPlan(TimingModel.from_points(points), "grab", parameters, True, tuple(notes))


def plan_constraint(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    effector = word(behaviour, "effector")
    target, position = _target(behaviour, notes)
    if effector is None or (target is None and position is None):
        raise BehaviourError("it needs an effector and a target")
    fade_in = number(behaviour, with_sbm("fade-in"), CONSTRAINT_FADE_S, notes, minimum=0.0)
    text = word(behaviour, with_sbm("offset"))
    offset = floats(text, 3) if text else None
    if text and offset is None:
        notes.append(f"offset={text!r} is not three numbers (metres) and is ignored")
    kind = (word(behaviour, with_sbm("constraint-type")) or "").lower()
    if kind and kind not in ("pos", "position", "point"):
        notes.append(f"constraint-type {kind!r}: only the effector's position is held")
    parameters = {"effector": effector, "effector_root": word(behaviour, with_sbm("effector-root")), "target": target,
                  "target_position": position, "offset": offset, "handle": word(behaviour, with_sbm("handle")),
                  "fade_in_s": fade_in,
                  "fade_out_s": number(behaviour, with_sbm("fade-out"), CONSTRAINT_FADE_S, notes, minimum=0.0)}
    # SmartBody's constraint stays until replaced; one given an end lasts until then, faded out by it.
    lasting = "end" not in behaviour.sync_refs
    end = fade_in if lasting else fade_in + CONSTRAINT_HOLD_S
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "ready": fade_in, "end": end}), "ik_constraint",
                         parameters, lasting, tuple(notes))


def plan_pointing(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    target, position = _target(behaviour, notes)
    if target is None and position is None:
        raise BehaviourError("it has no target")
    mode = (word(behaviour, "mode") or "").upper() or None
    if mode is not None and mode not in POINTING_MODES:
        notes.append(f"mode {mode!r} is not one of {', '.join(POINTING_MODES)}; the hand on the target's side points")
    return BehaviourPlan(TimingModel.from_points(POINTING_POINTS), "pointing",
                         {"target": target, "target_position": position, "hand": POINTING_MODES.get(mode)},
                         notes=tuple(notes))
