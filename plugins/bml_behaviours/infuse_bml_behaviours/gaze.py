"""``<gaze>``, ``<gazeShift>`` and ``<headDirectionShift>``: look at a target with eyes, head and spine."""
from __future__ import annotations

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, floats, number, optional_number, with_sbm, word

INFLUENCES = ("EYES", "HEAD", "SHOULDER", "WAIST", "WHOLE")
# Spellings other realizers use for the same reach of the gaze chain.
_INFLUENCE_ALIASES = {"NECK": "HEAD", "TORSO": "SHOULDER", "CHEST": "SHOULDER", "BACK": "WAIST", "BODY": "WHOLE"}
DIRECTIONS = ("RIGHT", "LEFT", "UP", "DOWN", "UPRIGHT", "UPLEFT", "DOWNLEFT", "DOWNRIGHT", "POLAR")
#: Natural timing of a temporary gaze (seconds): turn, hold, return.
GAZE_POINTS = {"start": 0.0, "ready": 0.5, "relax": 2.5, "end": 3.0}
SHIFT_DURATION_S = 0.5

ATTRIBUTES = {"target", "influence", "offsetAngle", "offsetDirection", "bmlt:dynamic", "dynamic"} | with_sbm(
    "joint-range", "priority-joint", "joint-speed", "joint-smooth", "fade-in", "fade-out", "handle", "target-pos",
    "direction", "time-hint", "head-speed", "eyes-speed", "neck-speed", "torso-speed")
# Gaze joint groups SmartBody names in sbm:joint-range, from the bottom of the chain up.
_RANGE_ORDER = ("BACK", "CHEST", "NECK", "HEAD", "EYES")


def _parameters(behaviour, notes: Notes) -> dict:
    target = word(behaviour, "target")
    target_pos = word(behaviour, with_sbm("target-pos"))
    position = floats(target_pos, 3) if target_pos else None
    if target_pos and position is None:
        notes.append(f"target-pos={target_pos!r} is not three numbers and is ignored")
    has_offset = word(behaviour, ("offsetAngle", "offsetDirection")) is not None
    if target is None and position is None and not has_offset:
        raise BehaviourError("it has neither a target nor an offset")
    influence_text = (word(behaviour, "influence") or "").upper()
    influence = _INFLUENCE_ALIASES.get(influence_text, influence_text) or None
    if influence and influence not in INFLUENCES:
        notes.append(f"influence {influence_text!r} is not one of {', '.join(INFLUENCES)}; the default chain is used")
        influence = None
    direction = (word(behaviour, "offsetDirection") or "").upper() or None
    if direction and direction not in DIRECTIONS:
        notes.append(f"offsetDirection {direction!r} is unknown and is ignored")
        direction = None
    joint_range = [j.upper() for j in (word(behaviour, with_sbm("joint-range")) or "").split()]
    character, _, joint = (target or "").partition(":")
    return {
        # No target with an offset: the offset is taken from straight ahead.
        "target": target, "target_character": character if joint else None, "target_joint": joint or None,
        "target_position": position, "influence": influence,
        "offset_angle_deg": number(behaviour, "offsetAngle", 0.0, notes),
        "offset_direction": direction,
        "joint_range": sorted(joint_range, key=lambda j: _RANGE_ORDER.index(j) if j in _RANGE_ORDER else -1) or None,
        "priority_joint": word(behaviour, with_sbm("priority-joint")),
        "joint_speed_deg_s": optional_number(behaviour, with_sbm("joint-speed"), notes, minimum=0.0),
        "smooth": optional_number(behaviour, with_sbm("joint-smooth"), notes, 0.0, 1.0),
        "fade_in_s": optional_number(behaviour, with_sbm("fade-in"), notes, minimum=0.0),
        "fade_out_s": optional_number(behaviour, with_sbm("fade-out"), notes, minimum=0.0),
        "handle": word(behaviour, with_sbm("handle")),
        "dynamic": (word(behaviour, ("bmlt:dynamic", "dynamic")) or "").lower() == "true",
    }


def plan_gaze(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    parameters = _parameters(behaviour, notes)
    parameters["mode"] = "gaze"
    # SmartBody's gaze holds until another gaze replaces it; BML 1.0 gaze returns at its end.
    persistent = context.dialect == "smartbody" and not ({"relax", "end"} & set(behaviour.sync_refs))
    return BehaviourPlan(TimingModel.from_points(GAZE_POINTS), "gaze", parameters, persistent, tuple(notes))


def plan_gaze_shift(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    parameters = _parameters(behaviour, notes)
    parameters["mode"] = "shift"
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "end": SHIFT_DURATION_S}), "gaze", parameters, True,
                         tuple(notes))


def plan_head_direction_shift(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    parameters = _parameters(behaviour, notes)
    parameters.update(mode="shift", influence="HEAD")
    return BehaviourPlan(TimingModel.from_points({"start": 0.0, "end": SHIFT_DURATION_S}), "gaze", parameters, True,
                         tuple(notes))
