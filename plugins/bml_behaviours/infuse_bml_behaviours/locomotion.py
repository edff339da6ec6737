"""``<locomotion>``: walk, jog or run to a target or along a path; its duration follows from distance and speed.

A target is a point ``"x z"`` (metres on the ground plane), several points ``"x1 z1 x2 z2 ..."``, object
names, or a mix of them (SmartBody).
"""
from __future__ import annotations

import math

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

from .common import Notes, number, with_sbm, word

#: Speed of each manner, m/s.
MANNER_SPEEDS = {"walk": 1.2, "jog": 2.5, "run": 3.5}
#: Time to reach the travel speed from standing and to stop again, seconds.
ACCELERATION_S = 0.5
#: Distance assumed for a waypoint whose position is not known yet, metres.
UNKNOWN_LEG_M = 2.0
ATTRIBUTES = {"target", "manner", "speed", "type", "facing", "proximity"} | with_sbm(
    "braking", "accel", "manner", "follow", "steering")


def path_from(text: str, locate) -> list:
    """Waypoints: numbers pair up as [x, z]; a name becomes [x, z] when ``locate`` knows it, else stays a name."""
    path, numbers = [], []
    for token in text.replace(",", " ").split():
        try:
            numbers.append(float(token))
            if len(numbers) == 2:
                path.append(numbers)
                numbers = []
            continue
        except ValueError:
            pass
        if numbers:
            raise BehaviourError(f"target {text!r} has an unpaired coordinate before {token!r}")
        position = locate(token)
        path.append([float(position[0]), float(position[2])] if position is not None else token)
    if numbers:
        raise BehaviourError(f"target {text!r} has an unpaired coordinate")
    return path


def path_length_m(path: list, origin) -> float:
    """Length of the path from ``origin`` ([x, z]), counting legs to or from unknown places as :data:`UNKNOWN_LEG_M`."""
    total, here = 0.0, origin
    for point in path:
        known = not isinstance(point, str)
        total += math.dist(here, point) if known and here is not None else UNKNOWN_LEG_M
        here = point if known else None
    return total


def plan(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    target = word(behaviour, "target")
    if target is None:
        raise BehaviourError("it has no target")
    path = path_from(target, context.locate)
    manner = (word(behaviour, ("manner", "sbm:manner")) or "walk").lower()
    if manner not in MANNER_SPEEDS:
        notes.append(f"manner {manner!r} is not one of {', '.join(MANNER_SPEEDS)}; walk is used")
        manner = "walk"
    speed = number(behaviour, "speed", MANNER_SPEEDS[manner], notes, minimum=0.05)
    here = context.locate(context.character) if context.character else None
    origin = [float(here[0]), float(here[2])] if here is not None else [0.0, 0.0]
    distance = path_length_m(path, origin)
    travel = distance / speed
    ramp = min(ACCELERATION_S, travel / 2)
    points = {"start": 0.0, "ready": ramp, "relax": ramp + max(travel - ramp, 0.0), "end": travel + ramp}
    facing = word(behaviour, "facing")
    parameters = {"path": path, "speed_m_s": speed, "manner": manner, "distance_m": distance,
                  "facing_deg": number(behaviour, "facing", 0.0, notes) if facing is not None else None,
                  "proximity_m": number(behaviour, "proximity", 0.0, notes, minimum=0.0),
                  "braking": number(behaviour, "sbm:braking", 1.0, notes, minimum=0.0),
                  "type": word(behaviour, "type")}
    return BehaviourPlan(TimingModel.from_points(points), "locomotion", parameters, notes=tuple(notes))
