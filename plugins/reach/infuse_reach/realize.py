"""BML ``<sbm:reach>`` realized in a scene through its :class:`~infuse.stage.Stage`: touch, pick up (the object
then follows the hand) or put down (the object the character holds, whoever's grab took it, at the
target, with the hand that holds it), with the character's reaching pack; ``finish`` ends its reaches.
What each hand holds is the stage's record (:class:`~infuse.stage.Held`).
"""
from __future__ import annotations

import math

from infuse.bml.model import CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from infuse.stage import Held, until_s

from .controller import Reach

#: BML reach actions -> the reach controller's.
REACH_ACTIONS = {"touch": "touch", "pick-up": "grab", "put-down": "put"}


class PutDowns:
    """The starts of a scene's put-downs (global seconds). A block of frames begins at each, so that the
    object is in the hand (a grab takes hold once the block its closing falls in is evaluated) when the
    put-down first reads where the hand holds it."""

    def __init__(self, stage):
        self.stage = stage
        self.starts: list[float] = []

    def frames_ahead(self, most: int) -> int:
        frame, fps = self.stage.runtime.frame, self.stage.fps
        later = [f - frame for f in (math.ceil(t * fps - 1e-6) for t in self.starts) if frame < f < frame + most]
        return min(later, default=most)


def warm_up(stage, character: str) -> Reach | None:
    """A reach in front of the character with its reaching pack (None without one), to prepare its binding."""
    space = stage.blend_space(character, "reach")
    return None if space is None else Reach(target=(0.25, 1.2, 0.35), hand="auto", pack=space)


def realize_reach(activation, stage):
    """Reach with the character's reaching pack; returns the activity, or None (warned, or a finish)."""
    p = activation.parameters
    name = activation.character
    action = p.get("action")
    space = stage.blend_space(name, "reach")
    if space is None:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: no reaching pack infused: "
                                                       "the character does not reach")
        return None
    if action == "finish":
        for activity in stage.activities(name):
            if isinstance(activity.controller, Reach) and (activity.end_s is None or activity.end_s > activation.start):
                stage.runtime.stop(activity, activation.start)
        return None
    if action not in REACH_ACTIONS:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> action {action!r} is not realized "
                                                       f"(realized: {', '.join(REACH_ACTIONS)})")
        return None
    if p.get("target_position") is not None:
        target = tuple(float(v) for v in p["target_position"])
    else:
        target = stage.resolve(p.get("target"))
        if stage.what(target) not in ("object", "target") and ":" not in target:
            stage.warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: no object named {target!r}")
            return None
    obj = None
    hand = p.get("hand") or "auto"
    if action == "pick-up":
        if not isinstance(target, str) or stage.what(target) != "object":
            stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: only a scene object can be picked up")
            return None
        obj = target
        if hand == "auto":  # the hand that will hold it is known now, for the stage's record
            hand = stage.runtime.rig(name).side_of(stage.runtime.target(target).positions([activation.start], None)[0])
        busy = [h.obj for h in stage.held(name) if h.hand == hand]
        if busy:
            stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot pick up {target!r}: the "
                                                           f"{hand} hand holds {busy[-1]!r} (put it down first)")
            return None
    elif action == "put-down":
        holding = [h for h in stage.held(name) if hand == "auto" or h.hand == hand]
        if not holding:
            stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: the character holds nothing to put "
                       "down" + ("" if hand == "auto" else f" in its {hand} hand"))
            return None
        obj, hand = holding[-1].obj, holding[-1].hand
    reach = Reach(target=target, hand=hand, pack=space, action=REACH_ACTIONS[action], obj=obj)
    span = until_s(activation) - activation.start
    if span > reach.stroke_s + reach.blend_out_s:  # hold at the target until the behaviour's relax
        reach.hold_s = span - reach.stroke_s - reach.blend_out_s
    activity = stage.activate(activation, reach, activation.start + reach.stroke_s + reach.hold_s + reach.blend_out_s)
    stroke = activation.start + reach.stroke_s
    if obj is not None:  # it follows the hand, or stays where it is put, from the stroke on
        stage.note_object_move(obj, stroke)
    if action == "pick-up":
        stage.hold(Held(name, hand, obj, stroke, reach.release))
    elif action == "put-down":
        stage.let_go(name, stroke, obj=obj)
        stage.stagehand("reach", PutDowns).starts.append(activation.start)
    return activity
