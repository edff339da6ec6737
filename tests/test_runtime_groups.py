"""The runtime evaluates activities of one class and layer but different priorities in one call when the
class touches only its own characters' poses and each character's activities keep their order; never
across a class that may read other characters, nor past another activity of the same character."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.runtime import Controller, Layer, Mode, Runtime

from runtime_characters import synthetic_character

CALLS: list[tuple[str, tuple[str, ...]]] = []  # (class, characters) of each evaluate call


class _Recorded(Controller):
    """Test controller: sets one joint to a turn about +Y (degrees), recording each evaluate call."""

    layer = Layer.BASE
    mode = Mode.OVERRIDE
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, degrees: float, joint: str = "spine1"):
        self.turn, self.joint = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.radians(degrees)), joint

    def bind(self, rig, report):
        return rig.joint(self.joint)

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        CALLS.append((cls.__name__, tuple(job.rig.name for job in jobs)))
        for job in jobs:
            job.controller.evaluate_one(job, block)

    def evaluate_one(self, job, block):
        job.pose.set_rotations([job.binding], np.broadcast_to(self.turn, (len(block), 1, 4)), job.weight, job.mode)


class Lean(_Recorded):
    own_characters_only = True
    call_ms = 2.0  # costlier than a sway: its calls are the ones joined where there is a choice


class Sway(_Recorded):
    own_characters_only = True


class Peek(_Recorded):
    """As if it read other characters' poses (a look at another's face): a barrier."""


def runtime_of(plays: list[tuple[type, str, int, float]]) -> Runtime:
    rt = Runtime(fps=30.0)
    for name in sorted({name for _, name, _, _ in plays}):
        rt.add_character(synthetic_character(name), name)
    for cls, name, priority, degrees in plays:
        rt.activate(name, cls(degrees), 0.0, priority=priority)
    return rt


def evaluated(plays, merging: bool, monkeypatch) -> tuple[list, dict[str, np.ndarray]]:
    monkeypatch.setattr(Lean, "own_characters_only", merging)
    monkeypatch.setattr(Sway, "own_characters_only", merging)
    CALLS.clear()
    rt = runtime_of(plays)
    rt.step(3)
    calls = list(CALLS)
    return calls, {name: rt.motion(name).local_rotations for name in rt.characters}


@pytest.mark.parametrize("plays, calls", [
    # two characters' leans of priorities 2 and 4: one call
    ([(Lean, "a", 2, 10.0), (Lean, "b", 4, 20.0)], [("Lean", ("a", "b"))]),
    # a's sway after its lean stays after it; b's lean joins a's
    ([(Lean, "a", 2, 10.0), (Sway, "a", 3, 30.0), (Lean, "b", 4, 20.0)], [("Lean", ("a", "b")), ("Sway", ("a",))]),
    # b's sway comes before b's lean of priority 4: the sway first, then both leans
    ([(Lean, "a", 2, 10.0), (Sway, "b", 3, 30.0), (Lean, "b", 4, 20.0)], [("Sway", ("b",)), ("Lean", ("a", "b"))]),
    # a walk over its own idle, with another's walk under its idle: the clips apart, the walks in one call
    ([(Lean, "a", 2, 10.0), (Sway, "a", 3, 30.0), (Sway, "b", 3, 40.0), (Lean, "b", 4, 20.0)],
     [("Sway", ("b",)), ("Lean", ("a", "b")), ("Sway", ("a",))]),
    # a class that may read any character's pose in between: nothing moves past it
    ([(Lean, "a", 2, 10.0), (Peek, "c", 3, 30.0), (Lean, "b", 4, 20.0)],
     [("Lean", ("a",)), ("Peek", ("c",)), ("Lean", ("b",))]),
    # the same character's leans of two priorities: one after the other, not in one call
    ([(Lean, "a", 2, 10.0), (Lean, "a", 4, 20.0)], [("Lean", ("a",)), ("Lean", ("a",))]),
])
def test_groups_join_only_where_each_characters_order_holds(plays, calls, monkeypatch):
    merged_calls, merged = evaluated(plays, True, monkeypatch)
    apart_calls, apart = evaluated(plays, False, monkeypatch)
    assert merged_calls == calls  # one block of three frames
    assert len(apart_calls) == len({(cls, priority) for cls, _, priority, _ in plays})  # a call per class and priority
    for name in apart:
        assert np.array_equal(merged[name], apart[name])
    last = {name: degrees for _, name, _, degrees in sorted(plays, key=lambda p: p[2])}  # the highest priority's turn shows
    for name, degrees in last.items():
        spine = runtime_of(plays).rig(name).joint("spine1")
        assert np.allclose(merged[name][:, spine], quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.radians(degrees)), atol=1e-12)
