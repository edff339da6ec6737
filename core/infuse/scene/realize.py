"""How a scene realizes scheduled BML activations (:class:`~infuse.bml.Activation`) on its characters.

The registry maps an activation's behaviour kind (``activation.controller``) to the installed controller
that realizes it (:func:`infuse.registry.realizer`); that controller's plugin realizes it through the
scene's :class:`~infuse.stage.Stage`. The scene itself keeps only the kinds no controller owns:

| kind | realized by |
|---|---|
| ``wait``, ``event`` | nothing to show (their sync points still give feedback) |
| ``speech`` | the scene synthesizes it and keeps its audio for the exported WAV; the controller realizing ``speech`` moves the mouth (without one the character speaks without lip sync, and saccades pause) |
| ``gesture``, ``animation``, ``posture``, ``blend`` | a clip of the character (from its behaviour packs, or its own file) of that name, played on the base layer; without one, warningFeedback. A behaviour naming a behaviour pack (``pack``) goes to the controller realizing its kind |
| any other kind | the realizing controller's ``realize(activation, stage)``; without one, the controller its ``from_bml`` builds, from the activation's start to its end; targets name scene objects, characters or ``character:joint`` |

A behaviour that cannot be realized, or only partly, gives warningFeedback; the rest of its block plays.
"""
from __future__ import annotations

import numpy as np

from .. import quaternions as quat
from .. import registry
from ..bml import Activation
from ..bml.model import BEHAVIOR_DEGRADED, BEHAVIOR_TYPE_NOT_SUPPORTED, CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from ..runtime import Clip, controller, controller_components
from ..stage import end_s as _end
from ..stage import until_s as _until

#: Kinds with nothing to show.
SILENT_KINDS = frozenset({"wait", "event"})
#: Kinds played from a clip of the character, and the priority of that clip on the base layer (above
#: walks, whose priorities count up from 1 per character).
CLIP_KINDS = {"gesture": 20_000, "animation": 20_000, "posture": 10_000, "blend": 10_000}
#: Kinds behaviour packs provide, and what is missing when they are not installed.
PACK_KINDS = {
    "locomotion": "no locomotion pack infused: the character does not walk",
    "grab": "no reaching pack infused: the character does not grab",
    "ik_constraint": "no reaching pack infused: the effector is not held on its target",
    "pointing": "no reaching pack infused: the character does not point",
}
#: The kind of blend space each of those kinds needs.
PACK_SPACE = {"locomotion": "locomotion", "grab": "reach", "ik_constraint": "reach", "pointing": "reach"}
#: Stances a character already has without any clip.
_STANDING = {None, "STANDING"}


def realize(scene, activation: Activation):
    """Play ``activation`` on its character in ``scene``; returns the runtime activity, or None (then
    warningFeedback says why, unless the kind has nothing to show)."""
    kind = activation.controller
    if kind in SILENT_KINDS:
        return None
    if kind == "speech":
        return _speech(scene, activation)
    descriptor = registry.realizer(kind)
    if kind in CLIP_KINDS and (descriptor is None or not activation.parameters.get("pack")):
        return play_clip(scene, activation)
    if descriptor is not None and descriptor.realize is not None:
        return descriptor.realize(activation, scene.stage)
    installed = controller_components()
    if kind in PACK_KINDS and (kind not in installed or scene.pack_space(activation.character, PACK_SPACE[kind]) is None):
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: {PACK_KINDS[kind]}")
        return None
    if kind == "locomotion":
        return _locomotion(scene, activation)
    if descriptor is not None:
        return scene.stage.play(activation)
    scene.warn(activation, BEHAVIOR_TYPE_NOT_SUPPORTED,
               f"<{activation.element}>: no installed controller realizes {kind!r} behaviours")
    return None


def _speech(scene, activation: Activation):
    """The utterance the scheduler timed: its audio always, the lip sync when a controller realizes speech."""
    name = activation.character
    text = (activation.parameters.get("text") or "").strip()
    if not text:
        return None  # the scheduler already warned about empty speech
    utterance = scene.speech.utterance(activation.parameters)
    if utterance is None:
        scene.runtime.add_speech(name, activation.start, _until(activation))
        reason = scene.speech.unavailable or "it was not synthesized"
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<speech> is shown without audio or lip sync: {reason}")
        return None
    descriptor = registry.realizer("speech")
    activity = None
    if descriptor is None:
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR, "<speech>: no lip-sync plugin is installed; only its audio is kept")
    else:
        activity = descriptor.realize(activation, scene.stage) if descriptor.realize else scene.stage.play(activation)
    if activity is None:  # it speaks all the same: saccades pause
        scene.runtime.add_speech(name, activation.start, _until(activation))
    scene.keep_audio(name, activation, utterance, activity)
    return activity


def play_clip(scene, activation: Activation):
    """The activation as a clip of its character on the base layer (see the module doc)."""
    p = activation.parameters
    name = p.get("clip") or p.get("blend")
    kind = activation.controller
    if kind == "posture" and name is None:
        if p.get("stance") in _STANDING and not p.get("poses"):
            return None  # characters stand already
        what = " ".join([p.get("stance") or ""] + [f"{q.get('part')}={q.get('lexeme')}" for q in p.get("poses") or ()]).strip()
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> {what}: no behaviour pack provides that posture")
        return None
    motion = scene.find_clip(activation.character, name) if name else None
    if motion is None:
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR,
                   f"<{activation.element}> {name!r}: no behaviour pack of the character provides that clip")
        return None
    end = _end(activation)
    persistent = activation.persistent
    span = (end if end is not None else activation.end) - activation.start
    speed = float(p.get("speed") or 1.0)
    if not persistent and span > 1e-6 and motion.duration > 0:
        speed = motion.duration / span  # stretched or squeezed by the block's constraints
    clip = Clip(motion, loop=persistent, speed=speed)
    if kind in ("posture", "blend"):
        scene.stop_postures(activation.character, activation.start)
    return scene.activate(activation, clip, end, priority=CLIP_KINDS[kind], blend_in_s=0.3, blend_out_s=0.3)


#: How far from a character a walk to that character stops, metres (when the BML gives no proximity).
CHARACTER_PROXIMITY_M = 0.9
#: SmartBody's braking factor 1 means this deceleration, m/s².
DECELERATION_M_S2 = 2.5


def _locomotion(scene, activation: Activation):
    """Walk along the activation's path with the character's locomotion pack. After the last point the
    character stands there (:mod:`infuse.scene.walks`) until another walk goes on from where it is."""
    p = activation.parameters
    name = activation.character
    rig = scene.runtime.rig(name)
    points = []
    for point in p.get("path") or ():
        if isinstance(point, str):
            where = scene.locate(scene.resolve_name(point))
            if where is None:
                scene.warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: no character or object named {point!r}")
                return None
            point = [where[0], where[2]]
        points.append([float(point[0]), float(point[1])])
    if not points:
        scene.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> has no point to walk to")
        return None
    last = points[-1]
    proximity = float(p.get("proximity_m") or 0.0)
    final = (p.get("path") or [None])[-1]
    if proximity == 0.0 and isinstance(final, str) and scene.resolve_name(final) in scene.characters:
        proximity = CHARACTER_PROXIMITY_M  # stop in front of a character, not inside it
    if proximity > 0.0:
        start = points[-2] if len(points) > 1 else scene.locate(name)[::2]
        leg = np.subtract(last, start)
        length = float(np.hypot(*leg))
        points[-1] = list(np.asarray(start) + leg * max(length - proximity, 0.0) / max(length, 1e-9))
    world = np.array([[x, 0.0, z] for x, z in points])
    own = quat.rotate(quat.conjugate(rig.rotation), world - rig.position)[:, [0, 2]]
    if p.get("facing_deg") is not None:
        scene.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: the facing at the end is not realized; "
                                                    "the character faces its last direction of travel")
    space = scene.pack_space(name, "locomotion")
    speed = float(p.get("speed_m_s") or 1.2)
    top = space.speed_limit()(0.0)
    if speed > top + 1e-3:
        scene.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: asked {speed:.2f} m/s ({p.get('manner') or 'walk'}); "
                                                  f"pack {space.pack!r} realizes at most {top:.2f} m/s forward: "
                                                  f"walking at {top:.2f} m/s")
        speed = top
    walk = controller("locomotion", pack=space, speed=speed, path=own,
                      max_decel=DECELERATION_M_S2 * max(float(p.get("braking") or 1.0), 0.1))
    # The walk lasts until the character stands at its last point, as the steering will take it there.
    plan = walk.plan(scene.fps, scene.walks.expected_state(name))
    if plan is None:
        scene.warn(activation, BEHAVIOR_DEGRADED, f"<{activation.element}>: the walk cannot reach its target "
                                                  f"({points[-1][0]:.2f}, {points[-1][1]:.2f})")
    activity = scene.activate(activation, walk, activation.stop_s, blend_in_s=0.3, priority=scene.walks.priority(name))
    if plan is None:
        scene.walks.start(name, activity, activation.end)
    else:
        scene.walks.start(name, activity, max(activation.end, activation.start + plan.rests_s), plan.state,
                          arrives_s=activation.start + plan.arrives_s)
    scene.character(name).destination = (float(points[-1][0]), float(points[-1][1]))
    return activity
