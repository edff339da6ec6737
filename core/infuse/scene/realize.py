"""How a scene realizes scheduled BML activations (:class:`~infuse.bml.Activation`) on its characters.

The registry maps an activation's behaviour kind (``activation.controller``) to the installed controller
that realizes it (:func:`infuse.registry.realizer`); that controller's plugin realizes it through the
scene's :class:`~infuse.stage.Stage`. The scene itself keeps only the kinds no controller owns:

| kind | realized by |
|---|---|
| ``wait``, ``event`` | nothing to show (their sync points still give feedback) |
| ``speech`` | the scene synthesizes it and keeps its audio for the exported WAV; the controller realizing ``speech`` moves the mouth (without one the character speaks without lip sync, and saccades pause) |
| ``gesture``, ``animation``, ``posture``, ``blend`` | a clip of the character (from its behaviour packs, or its own file) of that name, played on the base layer; without one, warningFeedback. A behaviour naming a behaviour pack (``pack``) or asking for SmartBody noise over it (``noise``) goes to the controller realizing its kind |
| any other kind | the realizing controller's ``realize(activation, stage)``; without one, the controller its ``from_bml`` builds, from the activation's start to its end; targets name scene objects, characters or ``character:joint`` |

A behaviour that cannot be realized, or only partly, gives warningFeedback; the rest of its block plays.
"""
from __future__ import annotations

from .. import registry
from ..bml import Activation
from ..bml.model import BEHAVIOR_TYPE_NOT_SUPPORTED, CANNOT_CREATE_BEHAVIOR
from ..runtime import Clip
from ..stage import end_s as _end
from ..stage import until_s as _until

#: Kinds with nothing to show.
SILENT_KINDS = frozenset({"wait", "event"})
#: Kinds played from a clip of the character, and the priority of that clip on the base layer (above the
#: base-layer controllers, whose priorities stay below 10,000).
CLIP_KINDS = {"gesture": 20_000, "animation": 20_000, "posture": 10_000, "blend": 10_000}
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
    if kind in CLIP_KINDS and (descriptor is None or not (activation.parameters.get("pack")
                                                          or activation.parameters.get("noise"))):
        return play_clip(scene, activation)
    if descriptor is None:
        scene.warn(activation, BEHAVIOR_TYPE_NOT_SUPPORTED,
                   f"<{activation.element}>: no installed controller realizes {kind!r} behaviours")
        return None
    return _through(descriptor, scene, activation)


def _through(descriptor, scene, activation: Activation):
    """The activation realized by the controller ``descriptor``: its ``realize``, else the generic way."""
    if descriptor.realize is not None:
        return descriptor.realize(activation, scene.stage)
    return scene.stage.play_with(descriptor, activation)


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
        activity = _through(descriptor, scene, activation)
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
                   f"<{activation.element}> {name!r}: no clip named {name!r} in the scene (neither the character's "
                   f"own nor one of its behaviour packs')")
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
