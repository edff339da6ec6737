"""``<head>``: nod, shake, toss, tilt and SmartBody's other head movements, timed by the oscillation model.

angle(t) = -m sin(2 pi r t / d), d = r / v (seconds), so the extremes fall every 0.5 / v seconds. Sync points:
ready 0.2/v; strokes at each extreme from 0.75/v; relax at the last extreme before the end; end r/v.
"""
from __future__ import annotations

import math

from infuse.bml import BehaviourPlan, TimingModel

from .common import Notes, number, word

#: Peak angle per unit amount, degrees.
AMPLITUDE_DEG = {"NOD": 30.0, "SHAKE": 45.0, "TOSS": 30.0, "TILT": 30.0, "WIGGLE": 30.0, "WAGGLE": 30.0,
                 "ORIENT": 30.0, "SPIN": 45.0}
#: Words of head lexemes that name a direction to turn the head to (Greta: ``Down_Aside_Right``).
DIRECTION_WORDS = {"UP", "DOWN", "LEFT", "RIGHT", "ASIDE", "FORWARD", "BACK"}
ATTRIBUTES = {"lexeme", "type", "repetition", "repeats", "amount", "velocity", "sbm:velocity", "sbm:repeats",
              "sbm:amount"}


#: Most oscillations one head movement makes (each one is a sync point).
MAX_REPEATS = 100.0


def nod_timing(repeats: float, velocity_hz: float) -> TimingModel:
    """The head movement's sync points for ``repeats`` oscillations at ``velocity_hz`` (see the module doc)."""
    r, v = max(repeats, 0.25), velocity_hz
    n_strokes = math.floor((r - 0.25) / 0.5)
    relax = (n_strokes * 0.5 + 0.25) / v
    points = {"start": 0.0, "ready": 0.2 / v, "strokeStart": 0.2 / v}
    strokes = [(0.25 + 0.5 * k) / v for k in range(1, n_strokes + 1)] or [relax]
    for k, t in enumerate(strokes, start=1):
        points["stroke" if k == 1 else f"stroke:{k}"] = t
    points.update(strokeEnd=strokes[-1], relax=relax, end=r / v)
    return TimingModel.from_points(points)


def plan(behaviour, context) -> BehaviourPlan:
    notes = Notes()
    kind = (word(behaviour, ("lexeme", "type")) or "NOD").upper()
    words = kind.replace("-", "_").split("_")
    direction = None
    if kind not in AMPLITUDE_DEG and set(words) <= DIRECTION_WORDS:
        kind, direction = "ORIENT", [w for w in words if w != "ASIDE"]
    elif kind not in AMPLITUDE_DEG and words[0] in AMPLITUDE_DEG:
        kind = words[0]  # a variant such as NOD_BIG or SHAKE_MIDDLE
    if kind not in AMPLITUDE_DEG:
        notes.append(f"head movement {kind!r} is unknown; it is realized as a NOD")
        kind = "NOD"
    repeats = number(behaviour, ("repetition", "repeats", "sbm:repeats"), 1.0, notes, minimum=0.25, maximum=MAX_REPEATS)
    velocity = number(behaviour, ("velocity", "sbm:velocity"), 1.0, notes, minimum=1e-3)
    amount = number(behaviour, ("amount", "sbm:amount"), 0.5, notes, -1.0, 1.0)
    parameters = {"lexeme": kind, "amount": amount, "repeats": repeats, "velocity_hz": velocity,
                  "peak_angle_deg": amount * AMPLITUDE_DEG[kind], "direction": direction}
    return BehaviourPlan(nod_timing(repeats, velocity), "head", parameters, notes=tuple(notes))
