"""``<posture>``, ``<postureShift>``, SmartBody's ``<body posture=...>`` and Greta's ``<torso>``."""
from __future__ import annotations

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, number, with_sbm, word

#: A temporary posture (seconds): into it, held, back.
POSTURE_POINTS = {"start": 0.0, "ready": 1.0, "relax": 3.0, "end": 4.0}
SHIFT_DURATION_S = 1.0
#: SmartBody blends into a new idle posture over this long and keeps it.
BODY_TRANSITION_S = 0.5
STANCES = ("SITTING", "CROUCHING", "STANDING", "LYING")
POSTURE_ATTRIBUTES = {"priority", "convanim:amount"}
BODY_ATTRIBUTES = {"posture"} | with_sbm("posture", "blend", "duration")
TORSO_ATTRIBUTES = {"lexeme"}


def _stance_and_poses(behaviour, notes: Notes) -> dict:
    stance = next((c.attributes.get("type") for c in behaviour.children if c.name == "stance"), None)
    if stance and stance.upper() not in STANCES:
        notes.append(f"stance {stance!r} is not one of {', '.join(STANCES)}")
    poses = [{"part": c.attributes.get("part"), "lexeme": c.attributes.get("lexeme")}
             for c in behaviour.children if c.name == "pose"]
    if stance is None and not poses:
        raise BehaviourError("it has neither a <stance> nor a <pose>")
    return {"stance": stance.upper() if stance else None, "poses": poses}


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
    time to blend into the posture from its start (``relax`` has no meaning for a lasting posture)."""
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
    return BehaviourPlan(TimingModel.from_points(points), "posture",
                         {"clip": posture, "stance": None, "poses": [], "transition_s": transition},
                         True, tuple(notes), own)


def plan_torso(behaviour, context) -> BehaviourPlan:
    lexeme = word(behaviour, "lexeme")
    if lexeme is None:
        raise BehaviourError("it has no lexeme")
    return BehaviourPlan(TimingModel.from_points(POSTURE_POINTS), "posture",
                         {"stance": None, "poses": [{"part": "TORSO", "lexeme": lexeme}]})
