"""The ``gesture`` controller: one clip of a gestures pack on the arms, over whatever plays below.

The clip (retargeted onto the character by infusing it with the pack) drives the joints of the hands it
is made for (shoulder girdle to fingertips), on the posture layer. Its phases land on the wanted times
(:func:`~infuse_gestures.timewarp.phase_warp`: BML sync points, holds, repeated strokes). ``amplitude``
scales each joint's movement away from the clip's ready pose (1: as authored). A gesture that starts
before the previous one of the same character with a hand in common has retracted co-articulates: the
previous one stays at its stroke's end and the new one blends from there to its own ready pose, never
passing through rest (an arm the new one leaves free retracts meanwhile). Gestures of different hands
overlap freely. A gesture whose repeated strokes differ (a count: one finger, two, three…) has a clip
per stroke from the second on, named ``<clip>@<stroke>``: each stroke plays its own, the hand changing
from one to the next over the return between them.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from infuse import Motion, quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode, sample_motion

from .aim import AimedArm, aim_arms, aim_weight, bind_arm
from .timewarp import PHASES, phase_warp, stroke_times

#: A gesture that starts less than this after the previous one ends follows on from its stroke, seconds.
COARTICULATION_GAP_S = 0.5
_LEGS = ("hip", "knee", "ankle", "forefoot", "toe")


@lru_cache(maxsize=256)
def authored_phases(pack, clip: str) -> tuple[dict, frozenset]:
    """Seconds of every phase of :data:`PHASES` of ``clip`` as the pack authored it, and its hands
    (``{"left"}``, ``{"right"}`` or both)."""
    from infuse.packs import load_pack

    doc = load_pack(pack).require_built()
    info = next((c for c in doc["clips"] if c["name"] == clip), None)
    if info is None or "sync" not in info:
        raise UsageError(f"pack {pack!r} has no gesture {clip!r}")
    hand = info.get("hand") or "right"
    hands = frozenset(("left", "right") if hand == "both" else (hand,))
    return {"start": 0.0, **info["sync"], "end": float(info["duration"])}, hands


@dataclass(frozen=True, eq=False)
class GestureBinding:
    """A gesture bound to one character: ``motion``, its pack clip infused on the character; ``joints``
    (K,): the arm joints it drives; ``ready`` (K, 4): their local rotations in the clip's ready pose;
    ``strokes``: the clips of its repeated strokes from the second on (``<clip>@2``, ``@3``… as far as the
    pack has them; a later stroke plays the last)."""

    motion: Motion
    joints: np.ndarray
    ready: np.ndarray
    strokes: tuple = ()
    aimed: tuple[AimedArm, ...] = ()


class Gesture(Controller):
    """Play gesture ``clip`` of ``pack``.

    ``phases``: seconds from the start each phase of :data:`PHASES` is wanted at (default: as authored,
    divided by ``speed``); ``repeats``: strokes; ``amplitude``: > 0, 1 as authored; ``target``: what the
    stroke is aimed at (a runtime target's name, ``"character:joint"`` or a point; :mod:`.aim`), or None.
    """

    kind = "gesture"
    layer = Layer.POSTURE
    mode = Mode.OVERRIDE

    def __init__(self, clip: str, pack: str = "gestures", phases: dict | None = None, repeats: int = 1,
                 amplitude: float = 1.0, speed: float = 1.0, target=None):
        if not (np.isfinite(amplitude) and amplitude > 0) or not (np.isfinite(speed) and speed > 0):
            raise UsageError(f"gesture {clip!r}: amplitude and speed must be positive numbers")
        if int(repeats) < 1:
            raise UsageError(f"gesture {clip!r}: repeats must be at least 1, got {repeats}")
        self.clip, self.pack = clip, pack
        authored, self.hands = authored_phases(pack, clip)
        self.authored = dict(authored)
        wanted = phases or {p: t / speed for p, t in self.authored.items()}
        missing = [p for p in PHASES if p not in wanted]
        if missing:
            raise UsageError(f"gesture {clip!r}: no time for {', '.join(missing)}")
        times = [float(wanted[p]) for p in PHASES]
        if any(b < a - 1e-9 for a, b in zip(times, times[1:])):
            raise UsageError(f"gesture {clip!r}: phases out of order: {dict(zip(PHASES, times))}")
        self.phases = dict(zip(PHASES, times))
        self.repeats, self.amplitude, self.speed = int(repeats), float(amplitude), float(speed)
        self.target = target
        self.enter_ready = False        # set when it follows on from another gesture's stroke
        self.leave_at_stroke_end = False  # set when another gesture follows on from its stroke
        self.duration_s = self.phases["end"]
        self.blend_in_s = min(0.2, self.phases["ready"])
        self.blend_out_s = min(0.2, self.phases["end"] - self.phases["relax"])

    def describe(self) -> str:
        return f"gesture {self.clip}"

    def bind(self, rig, report) -> GestureBinding:
        from infuse.packs import space_on  # packs load lazily: importing a plugin stays cheap

        space = space_on(rig, self.pack)
        if self.clip not in space.clips:
            raise UsageError(f"pack {space.pack!r} has no gesture {self.clip!r}")
        clip = space.clips[self.clip]
        sides = tuple(hand[0] for hand in sorted(self.hands))
        canonical = rig.mapping.inverse()
        arm = [j for j, name in enumerate(rig.skeleton.names) if j > 0 and canonical.get(name, "")[:2] in
               {f"{s}_" for s in sides} and canonical[name].split("_", 1)[1] not in _LEGS]
        if not arm:
            raise MissingJointsError(rig.name, f"no arm joints are mapped for gesture {self.clip!r}")
        joints = np.array(arm, dtype=np.int64)
        ready, _, _, _ = sample_motion(clip.motion, np.array([self.authored["ready"]]), loop=False, joints=joints)
        strokes: list[Motion] = []
        while len(strokes) < self.repeats - 1 and f"{self.clip}@{len(strokes) + 2}" in space.clips:
            strokes.append(space.clips[f"{self.clip}@{len(strokes) + 2}"].motion)
        aimed = () if self.target is None else tuple(
            arm for arm in (bind_arm(rig, s, clip.motion, self.authored["stroke"]) for s in sides) if arm is not None)
        return GestureBinding(clip.motion, joints, ready[0], tuple(strokes), aimed)

    def clip_times(self, local_times) -> np.ndarray:
        """Clip seconds (F,) at ``local_times`` (F,) seconds from the gesture's start."""
        return phase_warp(local_times, self.phases, self.authored, self.repeats, self.enter_ready,
                          self.leave_at_stroke_end, self.speed)

    def evaluate_one(self, job, block) -> None:
        b: GestureBinding = job.binding
        times = self.clip_times(job.local_times)
        rotations, _, _, _ = sample_motion(b.motion, times, loop=False, joints=b.joints)
        if b.strokes:
            rotations = self._stroke_by_stroke(b, rotations, times, job.local_times)
        if self.amplitude != 1.0:
            rotations = self._scaled(rotations, b.ready, job.local_times)
        job.pose.set_rotations(b.joints, rotations, job.weight, job.mode)
        if b.aimed:
            aim_arms(job, block, b.aimed, self.target,
                     job.weight * aim_weight(job.local_times, self.phases, self.leave_at_stroke_end))

    def _stroke_by_stroke(self, b: GestureBinding, first: np.ndarray, clip_times: np.ndarray,
                          local_times: np.ndarray) -> np.ndarray:
        """(F, K, 4) rotations with each repeated stroke from its own clip: ``first`` (F, K, 4) the first
        stroke's clip at ``clip_times`` (F,); between two strokes the hand turns from one's to the next's
        over the return (slerp by the time between them, ``local_times`` (F,) seconds)."""
        sampled = np.stack([first] + [sample_motion(m, clip_times, loop=False, joints=b.joints)[0] for m in b.strokes])
        at = np.interp(local_times, stroke_times(self.phases, self.authored, self.repeats), np.arange(self.repeats))
        lower = np.floor(at).astype(np.int64)
        upper = np.minimum(lower + 1, self.repeats - 1)
        frames = np.arange(len(local_times))
        last = len(sampled) - 1
        return quat.slerp(sampled[np.minimum(lower, last), frames], sampled[np.minimum(upper, last), frames],
                          np.broadcast_to((at - lower)[:, None], first.shape[:2]))

    def _scaled(self, rotations: np.ndarray, ready: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(F, K, 4) rotations whose turn away from the ready pose (K, 4) is scaled by the amplitude, from
        ready to the stroke's end, easing back to as authored by relax."""
        p = self.phases
        fade = np.clip((t - p["strokeEnd"]) / max(p["relax"] - p["strokeEnd"], 1e-6), 0.0, 1.0)
        exponent = np.where((t >= p["ready"]) & (t <= p["relax"]), self.amplitude + (1.0 - self.amplitude) * fade, 1.0)
        away = quat.multiply(quat.conjugate(np.broadcast_to(ready, rotations.shape)), rotations)
        return quat.multiply(np.broadcast_to(ready, rotations.shape),
                             quat.from_rotvec(quat.to_rotvec(away) * exponent[:, None, None]))


def _previous(runtime, character: str, start_s: float, hands: frozenset):
    """The character's latest gesture activity with a hand in ``hands`` that started before ``start_s`` and
    ends after ``start_s - COARTICULATION_GAP_S``, or None."""
    found = [a for a in runtime.activities if a.rig.name == character and isinstance(a.controller, Gesture)
             and a.controller.hands & hands and a.start_s < start_s - 1e-9
             and (a.end_s is None or a.end_s > start_s - COARTICULATION_GAP_S)]
    return max(found, key=lambda a: a.start_s, default=None)


def gesture_from_bml(parameters: dict, runtime, character: str, activation=None) -> Gesture:
    """A :class:`Gesture` from a planned BML ``<gesture>``: its phases at the activation's sync times; a
    gesture that follows another co-articulates with it (see the module doc)."""
    start = activation.start if activation is not None else runtime.time
    phases = None
    if activation is not None and all(activation.time(p) is not None for p in PHASES[1:-1]):
        phases = {p: activation.time(p) - start for p in PHASES[1:-1]}
        phases.update(start=0.0, end=activation.end - start)
    gesture = Gesture(parameters["clip"], parameters.get("pack") or "gestures", phases,
                      int(parameters.get("repeats") or 1), float(parameters.get("amplitude") or 1.0),
                      float(parameters.get("speed") or 1.0), parameters.get("target"))
    previous = _previous(runtime, character, start, gesture.hands)
    if previous is not None:
        ready_s = start + gesture.phases["ready"]
        previous.controller.leave_at_stroke_end = True
        if previous.controller.hands <= gesture.hands:  # the new one takes over every arm it moved
            previous.end_s, previous.blend_out_s = max(ready_s, previous.start_s), 0.0
        else:  # an arm the new one leaves free retracts through the blend, over the new one's preparation
            previous.end_s = max(ready_s, previous.start_s)
            previous.blend_out_s = max(ready_s - max(start, previous.start_s), 1.0 / runtime.fps)
        gesture.enter_ready = True
        gesture.blend_in_s = max(gesture.phases["ready"], 1.0 / runtime.fps)
    return gesture
