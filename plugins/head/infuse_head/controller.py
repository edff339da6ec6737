"""Head movements: angle(t) = -m sin(2π r t / d), d = r / v, split equally over the neck joints.

- ``lexeme``: NOD (pitch), SHAKE (heading), TOSS (roll), TILT (roll, one excursion and back), and
  SmartBody's WIGGLE (pitch), WAGGLE (roll) and SPIN (heading); ORIENT holds the head turned toward
  ``direction`` (words UP, DOWN, LEFT, RIGHT) for the movement's length.
- ``amount`` in [-1, 1] (default 0.5) scales the peak angle m = amount × 30° (nod, toss, tilt) or 45°
  (shake, spin); ``repeats`` r (default 1) oscillations at ``velocity_hz`` v (default 1 Hz), so the
  movement lasts d = r / v seconds.
- The angle is a pitch up, a heading to the character's left or a roll lifting its left side, in the
  aligned frames of spine4, spine5 and skullbase (whichever exist), a third (or half, or all) each.

A nod starts downward, a shake to the character's right. When r is not a multiple of 1/2 the curve
does not end at zero; the last quarter period then fades it out.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode, smoothstep
from infuse.runtime.swing import SWING_AXES, local_axes, local_offsets, local_turns, swing

#: Peak angle per unit amount, degrees.
AMPLITUDE_DEG = {"NOD": 30.0, "SHAKE": 45.0, "TOSS": 30.0, "TILT": 30.0, "WIGGLE": 30.0, "WAGGLE": 30.0,
                 "SPIN": 45.0, "ORIENT": 30.0}
#: Which angle each movement drives.
AXES = {"NOD": "pitch", "SHAKE": "heading", "TOSS": "roll", "TILT": "roll", "WIGGLE": "pitch", "WAGGLE": "roll",
        "SPIN": "heading", "ORIENT": "direction"}
NECK_JOINTS = ("spine4", "spine5", "skullbase")
_DIRECTION_WORDS = {"UP": (0.0, 1.0), "DOWN": (0.0, -1.0), "LEFT": (1.0, 0.0), "RIGHT": (-1.0, 0.0)}


def head_angle(t, lexeme: str, amount: float, repeats: float, velocity_hz: float) -> np.ndarray:
    """The movement's angle in radians at ``t`` seconds from its start (0 outside [0, r / v])."""
    t = np.asarray(t, dtype=np.float64)
    duration = repeats / velocity_hz
    m = np.radians(amount * AMPLITUDE_DEG[lexeme])
    inside = (t >= 0.0) & (t <= duration)
    if lexeme in ("TILT", "ORIENT"):  # one excursion and back, or a held turn with soft ends
        if lexeme == "TILT":
            return np.where(inside, -m * np.sin(np.pi * t / duration), 0.0)
        ramp = min(0.25 / velocity_hz, duration / 2)
        return np.where(inside, m * smoothstep(t / ramp) * smoothstep((duration - t) / ramp), 0.0)
    angle = -m * np.sin(2.0 * np.pi * repeats * t / duration)
    if abs(2 * repeats - round(2 * repeats)) > 1e-9:
        fade = 0.25 / velocity_hz
        angle = angle * smoothstep((duration - t) / fade)
    return np.where(inside, angle, 0.0)


@dataclass(frozen=True, eq=False)
class HeadBinding:
    """A head movement bound to one character: the neck ``joints`` (K,) it turns, their ``aligned`` frames
    (K, 4), and the ``axes`` (K, 3) of the movement's angle in the joints' local frames (None for ORIENT, which
    turns toward a direction in the aligned frames)."""

    joints: np.ndarray
    aligned: np.ndarray
    axes: np.ndarray | None


class HeadMovement(Controller):
    """A nod, shake, toss or tilt (see the module doc); lasts ``repeats / velocity_hz`` seconds."""

    kind = "head"
    layer = Layer.HEAD
    mode = Mode.ADDITIVE
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, lexeme: str = "NOD", amount: float = 0.5, repeats: float = 1.0, velocity_hz: float = 1.0,
                 direction=None):
        lexeme = lexeme.upper()
        if lexeme not in AMPLITUDE_DEG:
            raise UsageError(f"head movement {lexeme!r}: expected one of {', '.join(AMPLITUDE_DEG)}")
        if not (np.isfinite(amount) and -1.0 <= amount <= 1.0):
            raise UsageError(f"head amount must lie in [-1, 1], got {amount}")
        if not (np.isfinite(repeats) and repeats > 0) or not (np.isfinite(velocity_hz) and velocity_hz > 0):
            raise UsageError("head repeats and velocity must be positive")
        self.lexeme, self.amount, self.repeats, self.velocity_hz = lexeme, float(amount), float(repeats), float(velocity_hz)
        self.direction = _direction(direction) if lexeme == "ORIENT" else (0.0, 0.0)
        self.duration_s = self.repeats / self.velocity_hz

    def describe(self) -> str:
        return f"head {self.lexeme.lower()}"

    def angle(self, t) -> np.ndarray:
        """Radians at ``t`` seconds from the start (see :func:`head_angle`)."""
        return head_angle(t, self.lexeme, self.amount, self.repeats, self.velocity_hz)

    def bind(self, rig, report) -> HeadBinding:
        joints = [rig.joint(n) for n in NECK_JOINTS if rig.joint(n) is not None]
        if not joints:
            raise MissingJointsError(rig.name, "no neck or head joint is mapped for a head movement")
        axis = AXES[self.lexeme]
        if axis != "direction":  # one axis of each joint's aligned frame
            axis = SWING_AXES[("heading", "pitch", "roll").index(axis)]
        return HeadBinding(joints=np.array(joints), aligned=rig.aligned[joints],
                           axes=None if isinstance(axis, str) else local_axes(rig.aligned[joints], axis))

    def evaluate_one(self, job, block) -> None:
        b: HeadBinding = job.binding
        share = (self.angle(job.local_times) / len(b.joints))[:, None]  # (F, 1), the same for each joint
        if b.axes is not None:
            offsets = local_turns(b.axes, np.broadcast_to(share, (len(share), len(b.joints))))
        else:
            delta = swing(share * self.direction[0], share * self.direction[1])
            offsets = local_offsets(b.aligned, np.broadcast_to(delta, (len(share), len(b.joints), 4)))
        job.pose.set_rotations(b.joints, offsets, job.weight, job.mode)


def _direction(words) -> tuple[float, float]:
    """(heading, pitch) unit weights of direction words (a list or a string such as ``"DOWN_RIGHT"``)."""
    if words is None:
        return 0.0, -1.0
    if isinstance(words, str):
        words = words.replace("-", "_").replace(" ", "_").split("_")
    h = v = 0.0
    for w in words:
        dh, dv = _DIRECTION_WORDS.get(str(w).upper(), (0.0, 0.0))
        h, v = h + dh, v + dv
    norm = np.hypot(h, v)
    return (0.0, -1.0) if norm == 0 else (h / norm, v / norm)


def head_from_bml(parameters: dict, runtime, character: str, activation=None) -> HeadMovement:
    """A :class:`HeadMovement` from a BML ``<head>`` activation's parameters."""
    return HeadMovement(parameters.get("lexeme") or "NOD", float(parameters.get("amount", 0.5)),
                        float(parameters.get("repeats", 1.0)), float(parameters.get("velocity_hz", 1.0)),
                        parameters.get("direction"))
