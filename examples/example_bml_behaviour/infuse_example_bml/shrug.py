"""``<shrug>`` in the ``urn:infuse:example`` namespace: both shoulders rise, hold and fall.

::

    <bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:ex="urn:infuse:example" id="b1">
      <ex:shrug id="sh1" amount="0.8" duration="1.2" start="s1:end"/>
    </bml>

Attributes: ``amount`` (0..1, default 1) and ``duration`` (seconds, default 1). Sync points (natural
timing, fractions of the duration): start, ready 0.25 (shoulders up), stroke 0.45, relax 0.65 (they
start to fall), end. Like any behaviour it stretches between the sync points others constrain.
It is realized by the installed controller of kind ``shrug`` (the example controller package).
"""
from __future__ import annotations

import math

from infuse.bml import BehaviourError, BehaviourPlan, TimingModel

NAMESPACE = "urn:infuse:example"
ELEMENT = "{" + NAMESPACE + "}shrug"
ATTRIBUTES = frozenset({"amount", "duration"})
#: Sync points as fractions of the duration.
SYNC_FRACTIONS = {"start": 0.0, "ready": 0.25, "stroke": 0.45, "relax": 0.65, "end": 1.0}


def _number(behaviour, name: str, default: float, low: float, high: float) -> float:
    text = behaviour.attributes.get(name)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        raise BehaviourError(f"{name}={text!r} is not a number") from None
    if not (math.isfinite(value) and low <= value <= high):
        raise BehaviourError(f"{name}={text!r} must lie in [{low:g}, {high:g}]")
    return value


def plan_shrug(behaviour, context) -> BehaviourPlan:
    """The timing and the ``shrug`` controller's parameters of one ``<shrug>`` element."""
    amount = _number(behaviour, "amount", 1.0, 0.0, 1.0)
    duration = _number(behaviour, "duration", 1.0, 0.2, 10.0)
    timing = TimingModel.from_points({sync: f * duration for sync, f in SYNC_FRACTIONS.items()})
    return BehaviourPlan(timing, "shrug", {"amount": amount, "duration_s": duration})
