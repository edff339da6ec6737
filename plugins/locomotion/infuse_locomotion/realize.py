"""BML ``<locomotion>`` realized in a scene through its :class:`~infuse.stage.Stage`: walk along the
activation's path with the character's locomotion pack. After the last point the character stands there
(:mod:`.walks`) until another walk goes on from where it is.
"""
from __future__ import annotations

import threading
import weakref

import numpy as np

from infuse import quaternions as quat
from infuse.bml.model import BEHAVIOR_DEGRADED, CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET

from .controller import Locomotion
from .walks import Walks

#: How far from a character a walk to that character stops, metres (when the BML gives no proximity).
CHARACTER_PROXIMITY_M = 0.9
#: SmartBody's braking factor 1 means this deceleration, m/s².
DECELERATION_M_S2 = 2.5


def walks(stage) -> Walks:
    """The scene's :class:`~.walks.Walks`."""
    return stage.stagehand("locomotion", Walks)


def warm_up(stage, character: str) -> Locomotion | None:
    """A short walk with the character's locomotion pack (None without one), to prepare its binding."""
    space = stage.blend_space(character, "locomotion")
    return None if space is None else Locomotion(pack=space, path=[(0.0, 1.0)])


def realize_walk(activation, stage):
    """Walk the activation's path (points (x, z) metres, or names of objects and characters); returns the
    activity, or None (warned)."""
    made = _walk(activation, stage, stage.warn)
    if made is None:
        return None
    walk, key, points = made
    name = activation.character
    continuity = walks(stage)
    # The walk lasts until the character stands at its last point, as the steering will take it there.
    state = continuity.expected_state(name)
    plans = _planned(stage)
    with _PLANS_LOCK:
        plan = plans.pop(_plan_key(key, state), None)
    if plan is None:
        plan = walk.plan(stage.fps, state)
    elif plan is _UNREACHABLE:
        plan = None
    if plan is None:
        stage.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: the walk cannot reach its target "
                                                  f"({points[-1][0]:.2f}, {points[-1][1]:.2f})")
    activity = stage.activate(activation, walk, activation.stop_s, blend_in_s=0.3, priority=continuity.priority(name))
    if plan is None:
        continuity.start(name, activity, activation.end)
    else:
        continuity.start(name, activity, max(activation.end, activation.start + plan.rests_s), plan.state,
                         arrives_s=activation.start + plan.arrives_s)
    stage.set_destination(name, float(points[-1][0]), float(points[-1][1]))
    return activity


def prepare_walk(activation, stage) -> None:
    """Plan the activation's walk ahead (:meth:`Locomotion.plan`, frame by frame: the costly part of
    realizing it), from where the character's last walk leaves it and where its targets are now, on the
    caller's thread; :func:`realize_walk` takes the plan when it realizes the walk from the very same
    inputs, and plans again otherwise (a walk realized meanwhile, a target that moved). Reads the stage
    only."""
    made = _walk(activation, stage, lambda *problem: None)
    if made is None:
        return
    walk, key, _ = made
    continuity = stage.stagehands.get("locomotion")  # not made here: the loop's thread makes it
    state = continuity.expected_state(activation.character) if continuity is not None else None
    plan = walk.plan(stage.fps, state)
    plans = _planned(stage)
    with _PLANS_LOCK:
        plans[_plan_key(key, state)] = _UNREACHABLE if plan is None else plan
        while len(plans) > MAX_PLANS:
            del plans[next(iter(plans))]


#: Walk plans kept ahead per scene (the oldest go first).
MAX_PLANS = 64
_PLANS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # stage -> {inputs: plan}
_PLANS_LOCK = threading.Lock()
_UNREACHABLE = object()  # a plan worked out ahead: the walk does not reach its target


def _planned(stage) -> dict:
    """The walk plans worked out ahead for ``stage``'s scene, by :func:`_plan_key`."""
    with _PLANS_LOCK:
        plans = _PLANS.get(stage)
        if plans is None:
            plans = _PLANS[stage] = {}
        return plans


def _plan_key(walk_key: tuple, state) -> tuple:
    """Everything :meth:`Locomotion.plan` depends on: the walk's own inputs and where it starts (every
    attribute of the steering state, exactly)."""
    return walk_key + (None if state is None else repr(sorted(vars(state).items())),)


def _walk(activation, stage, warn):
    """The :class:`Locomotion` an activation asks for, the inputs it is made of (pack, speed, path in the
    character's own frame, braking, fps) as a key, and the path's points (x, z) in the world; None, after
    ``warn(activation, code, message)``, when the character cannot walk it."""
    p = activation.parameters
    name = activation.character
    space = stage.blend_space(name, "locomotion")
    if space is None:
        warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: no locomotion pack infused: "
                                                 "the character does not walk")
        return None
    rig = stage.runtime.rig(name)
    points = []
    for point in p.get("path") or ():
        if isinstance(point, str):
            where = stage.locate(stage.resolve(point))
            if where is None:
                warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: no character or object named {point!r}")
                return None
            point = [where[0], where[2]]
        points.append([float(point[0]), float(point[1])])
    if not points:
        warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> has no point to walk to")
        return None
    last = points[-1]
    proximity = float(p.get("proximity_m") or 0.0)
    final = (p.get("path") or [None])[-1]
    if proximity == 0.0 and isinstance(final, str) and stage.what(stage.resolve(final)) == "character":
        proximity = CHARACTER_PROXIMITY_M  # stop in front of a character, not inside it
    if proximity > 0.0:
        start = points[-2] if len(points) > 1 else stage.locate(name)[::2]
        leg = np.subtract(last, start)
        length = float(np.hypot(*leg))
        points[-1] = list(np.asarray(start) + leg * max(length - proximity, 0.0) / max(length, 1e-9))
    world = np.array([[x, 0.0, z] for x, z in points])
    own = quat.rotate(quat.conjugate(rig.rotation), world - rig.position)[:, [0, 2]]
    if p.get("facing_deg") is not None:
        warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: the facing at the end is not realized; "
                                            "the character faces its last direction of travel")
    speed = float(p.get("speed_m_s") or 1.2)
    top = space.speed_limit()(0.0)
    if speed > top + 1e-3:
        warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: asked {speed:.2f} m/s ({p.get('manner') or 'walk'}); "
                                            f"pack {space.pack!r} realizes at most {top:.2f} m/s forward: "
                                                  f"walking at {top:.2f} m/s")
        speed = top
    max_decel = DECELERATION_M_S2 * max(float(p.get("braking") or 1.0), 0.1)
    walk = Locomotion(pack=space, speed=speed, path=own, max_decel=max_decel)
    return walk, (id(space), speed, own.shape, own.tobytes(), max_decel, stage.fps), points
