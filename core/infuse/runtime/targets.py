"""Things to look at or take: a point, a moving point, or a joint of a character.

A target gives global positions (metres, core frame) at any times (seconds) at once:
``target.positions(times, block) -> (F, 3)``. :func:`as_target` turns plain values into targets:

- a point ``(x, y, z)`` -> :class:`PointTarget`;
- an ``(F, 3)`` array -> :class:`TrackTarget` sampled at the runtime's frame rate from time 0
  (or ``TrackTarget(times, positions)`` for any sample times);
- a callable ``f(times (F,)) -> (F, 3)`` (or ``f(t) -> (3,)``) -> :class:`FunctionTarget`;
- ``"character:joint"`` or ``(character, joint)`` -> :class:`JointTarget`; the joint is a canonical
  name (``"skullbase"``, ``"eyeball_left"``), one of the character's own joint names, or ``"face"``.

Names without a colon are resolved by the runtime (:meth:`Runtime.target`): a named target added with
:meth:`Runtime.add_target`, or a character (its face).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..errors import UsageError


class Target:
    """Base class: :meth:`positions` returns (F, 3) global positions in metres at ``times`` (F,) seconds."""

    def positions(self, times: np.ndarray, block) -> np.ndarray:
        raise NotImplementedError


@dataclass(frozen=True)
class PointTarget(Target):
    """A fixed point (3,) in metres."""

    point: tuple[float, float, float]

    def positions(self, times, block=None) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.point, dtype=np.float64), (len(times), 3)).copy()


@dataclass(frozen=True, eq=False)
class TrackTarget(Target):
    """A point moving along samples ``positions`` (K, 3) at ``times`` (K,) seconds, linearly
    interpolated and held at both ends. ``times=None`` means the runtime's frames from 0."""

    samples: np.ndarray
    times: np.ndarray | None = None

    def __post_init__(self):
        pos = np.asarray(self.samples, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 3 or len(pos) == 0 or not np.all(np.isfinite(pos)):
            raise UsageError(f"a target track must be finite (K, 3) positions, got shape {pos.shape}")
        object.__setattr__(self, "samples", pos)
        if self.times is not None:
            t = np.asarray(self.times, dtype=np.float64)
            if t.shape != (len(pos),) or np.any(np.diff(t) <= 0):
                raise UsageError("target track times must be (K,) strictly increasing seconds")
            object.__setattr__(self, "times", t)

    def positions(self, times, block=None) -> np.ndarray:
        times = np.asarray(times, dtype=np.float64)
        sample_times = self.times
        if sample_times is None:
            fps = block.fps if block is not None else 30.0
            sample_times = np.arange(len(self.samples)) / fps
        if len(self.samples) == 1:
            return np.repeat(self.samples, len(times), axis=0)
        return np.stack([np.interp(times, sample_times, self.samples[:, k]) for k in range(3)], axis=1)


@dataclass(frozen=True, eq=False)
class FunctionTarget(Target):
    """A point given by ``function(times (F,)) -> (F, 3)``; a function of one time ``t -> (3,)`` also works."""

    function: Callable[[Any], Any]

    def positions(self, times, block=None) -> np.ndarray:
        times = np.asarray(times, dtype=np.float64)
        try:
            out = np.asarray(self.function(times), dtype=np.float64)
        except Exception:
            out = None
        if out is None or out.shape != (len(times), 3):
            out = np.array([np.asarray(self.function(float(t)), dtype=np.float64).reshape(3) for t in times]).reshape(-1, 3)
        if not np.all(np.isfinite(out)):
            raise UsageError("a target function returned NaN or infinity")
        return out


#: The joint name of :class:`JointTarget` that means a character's face: the middle of its eyes, or its head.
FACE = "face"


@dataclass(frozen=True)
class JointTarget(Target):
    """A joint of a character in the same runtime: ``joint`` is canonical, the character's own name,
    or ``"face"`` (the middle of the eyes; the head when the character has no eyes)."""

    character: str
    joint: str = FACE

    def resolve(self, runtime) -> tuple[Any, list[int]]:
        """(rig, joint indices whose mean is the target); :class:`UsageError` when unknown."""
        rig = runtime.rig(self.character)
        if self.joint == FACE:
            eyes = [rig.joint("eyeball_left"), rig.joint("eyeball_right")]
            if None not in eyes:
                return rig, eyes
            head = next((rig.joint(n) for n in ("skullbase", "spine5", "spine4") if rig.joint(n) is not None), None)
            if head is None:
                raise UsageError(f"character {self.character!r} has neither eyes nor a head to look at")
            return rig, [head]
        index = rig.joint(self.joint)
        if index is None:
            index = rig.skeleton.index.get(self.joint)
        if index is None:
            raise UsageError(f"character {self.character!r} has no joint {self.joint!r} (canonical or own name)")
        return rig, [index]

    def positions(self, times, block) -> np.ndarray:
        rig, joints = self.resolve(block.runtime)
        return block.pose(rig.name).chain_pose(joints)[1].mean(axis=1)


def as_target(value) -> Target:
    """A :class:`Target` from a target, a point, an (F, 3) track, a callable or ``"character:joint"``."""
    if isinstance(value, Target):
        return value
    if callable(value):
        return FunctionTarget(value)
    if isinstance(value, str):
        character, sep, joint = value.partition(":")
        if not sep or not character or not joint:
            raise UsageError(f"target {value!r}: expected 'character:joint'")
        return JointTarget(character, joint)
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, str) for v in value):
        return JointTarget(*value)
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape == (3,):
        if not np.all(np.isfinite(arr)):
            raise UsageError("a target point must be finite")
        return PointTarget((float(arr[0]), float(arr[1]), float(arr[2])))
    if arr.ndim == 2 and arr.shape[1] == 3:
        return TrackTarget(arr)
    raise UsageError(f"cannot use {type(value).__name__} of shape {arr.shape} as a target")
