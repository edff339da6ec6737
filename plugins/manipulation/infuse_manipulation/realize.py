"""BML ``<pointing>``, ``sbm:grab`` and ``sbm:constraint`` activations realized by this plugin's controllers.

Each kind has a ``realize(activation, stage)`` for scenes (names resolved and checked by the
:class:`~infuse.stage.Stage`, warnings naming the reason) and a ``from_bml(parameters, runtime,
character, activation)`` for a bare :class:`~infuse.runtime.Runtime`. The parameters are those the
built-in BML handlers plan: ``target`` (a name, ``"character:joint"``) or ``target_position`` (x, y, z
metres); pointing ``hand``; grab ``state`` (``start``/``reach``: take, ``release``/``finish``: let go),
``hand``, ``wrist``, ``pack``; constraint ``effector``, ``effector_root``, ``offset`` (x, y, z metres),
``fade_in_s``, ``fade_out_s``.
"""
from __future__ import annotations

from infuse.bml.model import BEHAVIOR_DEGRADED, CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from infuse.errors import InfuseError, UsageError
from infuse.stage import Held, end_s

from .constraint import IKConstraint
from .grab import GRASP_S, Grab, HeldObject, approach
from .pointing import Pointing
from .targets import check_point, resolve_target

#: How long a grabbing arm holds still at the object before it returns carrying it, seconds.
GRAB_HOLD_S = 0.2
#: The return of the arm after a grab, seconds.
GRAB_RETURN_S = 0.6
#: Shortest reach asked of the arm, seconds (a grab whose ready comes sooner arrives late).
MIN_REACH_S = 0.2
RELEASING = ("release", "finish")


# -- pointing ---------------------------------------------------------------------------------------------
def pointing(parameters: dict, activation) -> Pointing:
    """The :class:`Pointing` of an activation: its target and hand, its phases on the sync points."""
    target = _target(parameters)
    start = activation.start
    ready = _time(activation, "ready", start + 0.6)
    stroke = _time(activation, "stroke", ready)
    end = activation.end
    relax = _time(activation, "relax", max(stroke, end - 0.6))
    return Pointing(target, hand=parameters.get("hand") or "auto", ready_s=ready - start, stroke_s=stroke - start,
                    relax_s=relax - start, duration_s=end - start)


def pointing_from_bml(parameters: dict, runtime, character: str, activation) -> Pointing:
    controller = pointing(parameters, activation)
    resolve_target(runtime, controller.target)
    return controller


def _realized(activation, stage, from_bml, cannot: str):
    """The controller ``from_bml`` builds for ``activation``, activated until its end; a failure warns that
    the behaviour ``cannot`` (what it cannot do) and why."""
    parameters = _resolved(activation, stage)
    if parameters is None:
        return None
    try:
        controller = from_bml(parameters, stage.runtime, activation.character, activation)
        return stage.activate(activation, controller, end_s(activation))
    except InfuseError as exc:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> {cannot}: {exc}")
        return None


def realize_pointing(activation, stage):
    return _realized(activation, stage, pointing_from_bml, "cannot point")


# -- constraints ------------------------------------------------------------------------------------------
def constraint(parameters: dict) -> IKConstraint:
    offset = parameters.get("offset")
    return IKConstraint(parameters.get("effector") or "", _target(parameters),
                        offset_m=(0.0, 0.0, 0.0) if offset is None else check_point(offset, "the constraint's offset"),
                        root=parameters.get("effector_root"), blend_in_s=parameters.get("fade_in_s"),
                        blend_out_s=parameters.get("fade_out_s"), handle=parameters.get("handle"))


def constraint_from_bml(parameters: dict, runtime, character: str, activation) -> IKConstraint:
    controller = constraint(parameters)
    resolve_target(runtime, controller.target)
    if controller.handle:  # SmartBody: the same handle names the same constraint, which the new one replaces
        for activity in runtime.activities:
            old = activity.controller
            if activity.rig.name == character and isinstance(old, IKConstraint) and old.handle == controller.handle \
                    and activity.start_s <= activation.start and (activity.end_s is None or activity.end_s > activation.start):
                runtime.stop(activity, activation.start)
    return controller


def realize_constraint(activation, stage):
    return _realized(activation, stage, constraint_from_bml, "cannot hold its effector")


# -- grabbing ---------------------------------------------------------------------------------------------
def grab_from_bml(parameters: dict, runtime, character: str, activation):
    """A bare runtime's grab: with a reaching pack when ``pack`` names one, else by arm IK."""
    if (parameters.get("state") or "start").lower() in RELEASING:
        if release(runtime, character, parameters.get("target"), activation.start) is None:
            raise UsageError("the character holds nothing to let go")
        return None
    grab, _ = start_grab(runtime, character, activation, parameters, parameters.get("pack"),
                         lambda controller, end, **options: runtime.activate(
                             character, controller, activation.start, end, source=activation, **options))
    return grab


def realize_grab(activation, stage):
    p = activation.parameters
    character = activation.character
    if (p.get("state") or "start").lower() in RELEASING:  # whichever plugin's hand took it
        name = stage.resolve(p["target"]) if p.get("target") else None
        held = stage.let_go(character, activation.start, obj=name, hand=_hand(p))
        if held is None:
            stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> release: the character holds "
                       + (f"no {name!r}" if name else "nothing"))
        else:
            stage.note_object_move(held.obj, activation.start)
        return None
    name = stage.resolve(p.get("target") or "")
    if stage.what(name) != "object":
        kind = stage.what(name)
        stage.warn(activation, NO_SUCH_TARGET if kind is None else CANNOT_CREATE_BEHAVIOR,
                   f"<{activation.element}>: " + (f"no object named {p.get('target')!r}" if kind is None
                                                 else f"{name!r} is a {kind}, not an object a hand can take"))
        return None
    hand = _hand(p) or stage.runtime.rig(character).side_of(stage.runtime.target(name).positions([activation.start],
                                                                                                 None)[0])
    busy = [h.obj for h in stage.held(character) if h.hand == hand]
    if busy:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot take {name!r}: the {hand} hand "
                                                       f"holds {busy[-1]!r} (let it go first)")
        return None
    space = stage.blend_space(character, "reach")
    if space is None:
        stage.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: no reaching pack infused: "
                                                  "the arm reaches by IK alone")
    try:
        grab, held = start_grab(stage.runtime, character, activation, {**p, "target": name, "hand": hand}, space,
                                lambda controller, end, **options: stage.activate(activation, controller, end,
                                                                                  **options))
    except InfuseError as exc:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot grab {name!r}: {exc}")
        return None
    stage.note_object_move(name, held.grab_s)
    activity = stage.activate(activation, grab, None)
    stage.hold(Held(character, grab.hand, name, held.grab_s,
                    lambda at_s: grab.release(stage.runtime, activity, at_s)))
    return activity


def start_grab(runtime, character: str, activation, parameters: dict, pack, activate):
    """Start the arm's reach for ``parameters["target"]`` (an object's runtime target name) with
    ``activate(controller, end_s, **options)`` (at the activation's start), and make the object a
    :class:`HeldObject`. Returns the :class:`Grab` to play from the activation's start on, and the object."""
    from infuse.runtime import controller as build

    name = parameters.get("target")
    if not name:
        raise UsageError("a grab names the object it takes")
    rig = runtime.rig(character)
    before = runtime.target(name)
    start = activation.start
    ready = _time(activation, "ready", start + 1.0)
    stroke = _time(activation, "stroke", ready + GRASP_S)
    hand = _hand(parameters) or rig.side_of(before.positions([start], None)[0])
    wrist = rig.joint(f"{hand[0]}_wrist")
    if wrist is None:
        raise UsageError(f"{character!r} has no mapped {hand} wrist")
    reach_s = max(ready - start, MIN_REACH_S)
    back = start + reach_s + (stroke - ready) + GRAB_HOLD_S + GRAB_RETURN_S
    if pack is not None:
        arm = build("reach", target=approach(rig, hand, before), hand=hand, pack=pack, action="touch", hold_s=GRAB_HOLD_S,
                    stroke_s=reach_s)  # the wrist arrives at ready
        activate(arm, back, blend_out_s=GRAB_RETURN_S)
    else:
        arm = IKConstraint(f"{hand[0]}_wrist", approach(rig, hand, before), blend_in_s=reach_s, blend_out_s=GRAB_RETURN_S,
                           purpose=f"the {hand} hand reaching for {name!r}", straight_end=True)
        activate(arm, back)
    held = HeldObject(before, character, wrist, stroke)
    runtime.add_target(name, held)
    return Grab(held, hand, ready - start, stroke - start, obj=name), held


def release(runtime, character: str, name: str | None, at_s: float):
    """Let go of what the character holds (``name``: that object only) at ``at_s``; returns the grab's
    activity, or None when it holds nothing (of that name)."""
    for activity in reversed(runtime.activities):
        c = activity.controller
        if activity.rig.name == character and isinstance(c, Grab) and not c.released and \
                activity.start_s <= at_s and (name is None or c.obj.lower() == name.lower()):
            c.release(runtime, activity, at_s)
            return activity
    return None


# -- shared -----------------------------------------------------------------------------------------------
def _target(parameters: dict):
    if parameters.get("target_position") is not None:
        return check_point(parameters["target_position"], "the target position")
    target = parameters.get("target")
    if not target:
        raise UsageError("it has no target")
    return target


def _resolved(activation, stage) -> dict | None:
    """The activation's parameters with its target named as the scene spells it; None (warned) when the
    scene has no such character, object or target."""
    p = dict(activation.parameters)
    if p.get("target_position") is not None or not p.get("target"):
        return p
    name = stage.resolve(p["target"])
    head = name.partition(":")[0]
    if stage.what(head) is None:
        stage.warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: no character, object or target named "
                                               f"{p['target']!r}")
        return None
    p["target"] = name
    return p


def _time(activation, sync: str, default: float) -> float:
    t = activation.time(sync)
    return default if t is None else float(t)


def _hand(parameters: dict) -> str | None:
    hand = (parameters.get("hand") or "").lower()
    if hand in ("left", "right"):
        return hand
    wrist = (parameters.get("wrist") or "").lower()
    if wrist[:2] in ("l_", "r_"):
        return "left" if wrist[0] == "l" else "right"
    return None
