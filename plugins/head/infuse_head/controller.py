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
from infuse.runtime.controller import table_columns
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
    return _cycles(t, m, repeats, duration, _fade_s(repeats, velocity_hz))


def _fade_s(repeats: float, velocity_hz: float) -> float:
    """Seconds the last quarter period fades an oscillation out over (0: it ends at zero, at a multiple
    of half a period)."""
    return 0.25 / velocity_hz if abs(2 * repeats - round(2 * repeats)) > 1e-9 else 0.0


def _cycles(t, peak, repeats, duration, fade_s) -> np.ndarray:
    """-peak sin(2π r t / d) radians at ``t`` seconds, faded out over the last ``fade_s`` seconds where those
    are positive, 0 outside [0, d]: of one movement (numbers), or of several at once ((n, 1) arrays against
    (n, F) times)."""
    angle = -peak * np.sin(2.0 * np.pi * repeats * t / duration)
    fading = np.asarray(fade_s) > 0.0
    if fading.any():
        angle = np.where(fading, angle * smoothstep((duration - t) / np.where(fading, fade_s, 1.0)), angle)
    return np.where((t >= 0.0) & (t <= duration), angle, 0.0)


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
        """The character's neck joints and the movement's axis in them, worked out once per character and
        angle (:class:`HeadBindings`)."""
        angle = AXES[self.lexeme]
        kept = rig.state_of(HeadBindings)
        binding = kept.get(angle)
        if binding is None:
            binding = kept[angle] = _bind(rig, angle)
        return binding

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """The oscillations (all but TILT and ORIENT) added on characters of their own at once: their angles
        worked out together and turned about every neck joint's axis side by side, in one write; the others
        one at a time (:meth:`evaluate_one`), as are all when two share a character."""
        batch = jobs.memo(_Batch.of)
        if batch is None:
            return super().evaluate(jobs, block)
        rows = batch.rows
        if rows.size:
            shares = _cycles(jobs.local_times[rows], batch.peaks, batch.repeats, batch.durations, batch.fades) / batch.counts
            turns = local_turns(batch.axes, shares[batch.owners].T)  # (F, K, 4)
            weights = jobs.weights[rows]
            block.table.add_offsets(batch.columns, turns, None if (weights >= 1.0).all() else weights[batch.owners].T,
                                    [jobs[k].pose for k in rows])
        for k in batch.alone:
            jobs[k].controller.evaluate_one(jobs[k], block)

    def evaluate_one(self, job, block) -> None:
        b: HeadBinding = job.binding
        share = (self.angle(job.local_times) / len(b.joints))[:, None]  # (F, 1), the same for each joint
        if b.axes is not None:
            offsets = local_turns(b.axes, np.broadcast_to(share, (len(share), len(b.joints))))
        else:
            delta = swing(share * self.direction[0], share * self.direction[1])
            offsets = local_offsets(b.aligned, np.broadcast_to(delta, (len(share), len(b.joints), 4)))
        job.pose.set_rotations(b.joints, offsets, job.weight, job.mode)


class HeadBindings(dict):
    """The head bindings of one runtime character by the angle they turn (a value of :data:`AXES`): they
    depend only on its neck joints' aligned frames, fixed with the rig. Kept in the character's rig
    (:meth:`~infuse.runtime.rig.Rig.state_of`), read-only, shared by its head movements."""


def _bind(rig, angle: str) -> HeadBinding:
    joints = [rig.joint(n) for n in NECK_JOINTS if rig.joint(n) is not None]
    if not joints:
        raise MissingJointsError(rig.name, "no neck or head joint is mapped for a head movement")
    axis = None if angle == "direction" else SWING_AXES[("heading", "pitch", "roll").index(angle)]
    binding = HeadBinding(joints=np.array(joints), aligned=rig.aligned[joints],
                          axes=None if axis is None else local_axes(rig.aligned[joints], axis))
    for array in (binding.joints, binding.aligned, binding.axes):
        if array is not None:
            array.flags.writeable = False
    return binding


@dataclass(frozen=True, eq=False)
class _Batch:
    """Head movements evaluated together: the oscillations ``rows`` (n,) among the jobs, their ``peaks``,
    ``repeats``, ``durations`` (seconds), ``fades`` (seconds, 0: none) and neck joint ``counts`` (n, 1); their
    neck joints' table ``columns`` (K,), the movement of each (``owners``, (K,)) and its local ``axes`` (K, 3);
    the jobs played ``alone``."""

    rows: np.ndarray
    peaks: np.ndarray
    repeats: np.ndarray
    durations: np.ndarray
    fades: np.ndarray
    counts: np.ndarray
    columns: np.ndarray
    owners: np.ndarray
    axes: np.ndarray
    alone: list

    @classmethod
    def of(cls, jobs) -> "_Batch | None":
        """The batch of ``jobs``; None when two share a character."""
        together = [k for k, job in enumerate(jobs) if job.binding.axes is not None and job.mode is Mode.ADDITIVE
                    and job.controller.lexeme != "TILT"]
        placed = table_columns(jobs, [jobs[k].binding.joints if k in together else np.zeros(0, dtype=np.int64)
                                      for k in range(len(jobs))])
        if placed is None:
            return None
        columns, owners = placed
        chosen = [jobs[k].controller for k in together]

        def per_movement(values) -> np.ndarray:
            return np.array(values, dtype=np.float64).reshape(-1, 1)

        return cls(np.array(together, dtype=np.int64),
                   per_movement([np.radians(m.amount * AMPLITUDE_DEG[m.lexeme]) for m in chosen]),
                   per_movement([m.repeats for m in chosen]), per_movement([m.repeats / m.velocity_hz for m in chosen]),
                   per_movement([_fade_s(m.repeats, m.velocity_hz) for m in chosen]),
                   per_movement([len(jobs[k].binding.joints) for k in together]),
                   columns, np.searchsorted(together, owners),
                   np.concatenate([jobs[k].binding.axes for k in together]) if together else np.zeros((0, 3)),
                   [k for k in range(len(jobs)) if k not in together])


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
