"""The ``grab`` controller: a hand closes on an object, holds it, and lets it go.

The hand gets to the object by the installed ``reach`` controller when the character has a reaching
pack (its examples blended, then arm IK), else by arm IK alone (:class:`~.constraint.IKConstraint` on
the wrist, faded in); either way the wrist arrives at ``ready`` short of the object by half the hand's
length along the line from the shoulder (:class:`Approach`), so the object lies in the palm. The fingers close from
``ready`` to ``stroke`` (:data:`~.hands.GRIP_SHAPE`); from ``stroke`` the object follows the wrist at
the offset it had then (:class:`HeldObject`, the object's runtime target); the arm then returns to the
pose below, carrying it. :meth:`Grab.release` opens the hand at a time: the object stays where the hand
let it go.

A hand that closes further than :data:`TAKE_DISTANCE_M` from the object (out of reach) does not take
it: the grab reports that, and the object stays where it is.

It runs last on the head layer, after the gazes and the IK constraints, so the hand it reads is where
the arm finally is.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.layers import smoothstep
from infuse.runtime.targets import Target

from .hands import GRIP_SHAPE, Hand, bind_hand, reference_globals, set_shape

#: Closing (and opening) the hand, seconds.
GRASP_S = 0.3
#: Furthest the wrist may be from an object's centre for the closing hand to take it, metres.
TAKE_DISTANCE_M = 0.15


class HeldObject(Target):
    """Where an object is when a hand may hold it: where ``before`` (its target until now) puts it until
    the grab; from ``grab_s`` at the offset from ``character``'s ``wrist`` it had then; from
    ``release_s`` (once set) where the hand let it go. Positions are world metres."""

    def __init__(self, before: Target, character: str, wrist: int, grab_s: float):
        self.before, self.character, self.wrist = before, character, int(wrist)
        self.grab_s = float(grab_s)
        self.release_s: float | None = None  # global seconds, once the hand lets go
        self.offset: np.ndarray | None = None  # (3,) in the wrist's frame, once attached
        self.missed_m: float | None = None  # how far the hand closed from it, when it could not take it
        self.left_at: np.ndarray | None = None  # (3,) where it was let go
        self.last: np.ndarray | None = None

    def attach(self, block) -> None:
        """Fix the offset at the grab frame (or find the hand too far: :attr:`missed_m`), and the place it
        is let go at the release frame, when they fall in ``block`` (the holding character's pose there
        must be final)."""
        times = block.times
        grabbed = np.nonzero(times >= self.grab_s - 1e-9)[0]
        released = np.nonzero(times >= self.release_s - 1e-9)[0] if self.release_s is not None else grabbed[:0]
        taking = self.offset is None and self.missed_m is None and grabbed.size
        if taking or (self.offset is not None and self.left_at is None and released.size):
            rot, pos = block.pose(self.character).chain_pose([self.wrist])
            if taking:
                f = grabbed[0]
                where = self.before.positions(times, block)[f]
                distance = float(np.linalg.norm(where - pos[f, 0]))
                if distance > TAKE_DISTANCE_M:
                    self.missed_m = distance
                    return
                self.offset = quat.rotate(quat.conjugate(rot[f, 0]), where - pos[f, 0])
            if self.offset is not None and self.left_at is None and released.size:
                f = released[0]
                self.left_at = pos[f, 0] + quat.rotate(rot[f, 0], self.offset)

    def positions(self, times, block=None) -> np.ndarray:
        times = np.asarray(times, dtype=np.float64)
        out = np.array(self.before.positions(times, block), dtype=np.float64)
        if self.offset is None:
            return out
        held = times >= self.grab_s - 1e-9
        if self.release_s is not None:
            held &= times < self.release_s - 1e-9
        if held.any():
            if block is not None and len(times) == len(block) and self.character in block.poses:
                rot, pos = block.pose(self.character).chain_pose([self.wrist])
                hand = pos[:, 0] + quat.rotate(rot[:, 0], self.offset)
                out[held] = hand[held]
                self.last = hand[held][-1]
            elif self.last is not None:
                out[held] = self.last
        if self.left_at is not None and self.release_s is not None:
            out[times >= self.release_s - 1e-9] = self.left_at
        return out


class Approach(Target):
    """Where a wrist goes to take an object: ``distance_m`` short of it (its target ``target``) along the
    line from ``shoulder`` (3,), a world point, metres."""

    def __init__(self, target: Target, shoulder, distance_m: float):
        self.target, self.shoulder, self.distance_m = target, np.asarray(shoulder, dtype=np.float64), float(distance_m)

    def positions(self, times, block=None) -> np.ndarray:
        where = np.asarray(self.target.positions(times, block), dtype=np.float64)
        along = where - self.shoulder
        return where - self.distance_m * along / np.maximum(np.linalg.norm(along, axis=-1, keepdims=True), 1e-9)


def approach(rig, hand: str, target: Target) -> Approach:
    """The :class:`Approach` of ``hand`` to ``target``: from the shoulder as the character stands (its
    reference pose),
    half the wrist-to-middle-knuckle length short (none without fingers)."""
    s = hand[0]
    positions = reference_globals(rig)[1]
    shoulder = rig.joint(f"{s}_shoulder")
    wrist = rig.joint(f"{s}_wrist")
    knuckle = next((j for j in (rig.joint(f"{s}_{f}1") for f in ("middle", "index", "ring")) if j is not None), None)
    half_hand = 0.5 * float(np.linalg.norm(positions[knuckle] - positions[wrist])) if knuckle is not None else 0.0
    own = positions[shoulder] if shoulder is not None else positions[wrist]
    return Approach(target, quat.rotate(rig.rotation, own) + rig.position, half_hand)


@dataclass(frozen=True, eq=False)
class GrabBinding:
    """A grab bound to one character: the ``hand`` that closes (its fingers may be none)."""

    hand: Hand


class Grab(Controller):
    """Close ``hand`` ("left" or "right") on the object whose runtime target is ``held`` (a
    :class:`HeldObject`): the fingers close from ``ready_s`` to ``stroke_s`` (seconds from the start)
    and stay closed until :meth:`release`."""

    kind = "grab"
    layer = Layer.HEAD
    mode = Mode.OVERRIDE
    priority = 2_000  # after the IK constraints (which may carry the arm to the object)
    blend_in_s = 0.0
    blend_out_s = GRASP_S

    def __init__(self, held: HeldObject, hand: str, ready_s: float, stroke_s: float, obj: str = ""):
        if hand not in ("left", "right"):
            raise UsageError(f"a grab's hand is left or right, got {hand!r}")
        if not (0.0 <= ready_s <= stroke_s and np.isfinite(stroke_s)):
            raise UsageError(f"a grab's phases must satisfy 0 <= ready <= stroke, got {ready_s}, {stroke_s}")
        self.held, self.hand, self.obj = held, hand, obj
        self.ready_s, self.stroke_s = float(ready_s), float(stroke_s)

    def describe(self) -> str:
        return f"grab ({self.hand} hand{', ' + self.obj if self.obj else ''})"

    @property
    def released(self) -> bool:
        return self.held.release_s is not None

    def release(self, runtime, activity, at_s: float) -> None:
        """Open the hand from ``at_s`` (global seconds): the object stays where it is then."""
        self.held.release_s = float(at_s)
        runtime.stop(activity, at_s, blend_out_s=GRASP_S)

    def bind(self, rig, report) -> GrabBinding:
        hand = bind_hand(rig, self.hand)
        if hand is None:
            raise MissingJointsError(rig.character.asset.path, f"{rig.name} has no mapped {self.hand} wrist: it cannot hold anything")
        if not hand.has_fingers:
            report(f"no fingers are mapped on the {self.hand} hand: it holds without closing them")
        return GrabBinding(hand)

    def evaluate_one(self, job, block) -> None:
        closing = smoothstep((job.local_times - self.ready_s) / max(self.stroke_s - self.ready_s, 1e-6))
        b: GrabBinding = job.binding
        set_shape(job.pose, b.hand, GRIP_SHAPE, closing * job.weight)
        self.held.attach(block)
        if self.held.missed_m is not None:
            job.report(f"the {self.hand} hand closed {self.held.missed_m * 100:.0f} cm from {self.obj or 'the object'} "
                       "(out of reach): it is not taken")

