"""The ``tracks`` controller: plays precomputed keyed curves (lip sync, expressions, recorded face data).

Curves are sampled at ``times`` (K,) seconds from the activity's start, interpolated linearly
(rotations: normalized lerp on the shorter arc) and held at both ends:

- ``rotations``: joint -> (K, 4) local rotations (x, y, z, w), or local offsets in ADDITIVE mode;
  a joint is a canonical name or one of the character's own joint names;
- ``morph_weights``: morph target -> (K,) weights in [0, 1].

Names the character lacks are reported once and skipped.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import quaternions as quat
from ..errors import UsageError
from .controller import Block, Controller, Job
from .layers import Layer, clamp


def _interpolation(sample_times: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left sample index (T,) and fraction (T,) of ``times`` between ``sample_times`` (held at the ends)."""
    if len(sample_times) == 1:
        return np.zeros(len(times), dtype=np.int64), np.zeros(len(times))
    t = clamp(times, sample_times[0], sample_times[-1])
    i0 = clamp(np.searchsorted(sample_times, t, side="right") - 1, 0, len(sample_times) - 2)
    frac = (t - sample_times[i0]) / (sample_times[i0 + 1] - sample_times[i0])
    return i0, frac


@dataclass(frozen=True, eq=False)
class TracksBinding:
    """Tracks bound to one character: their keys' ``times`` (K,) seconds; the joints ``joints`` (R,) their
    rotation tracks drive, with their keys ``rotations`` (K, R, 4); the morph targets ``columns`` (M,)
    their weight tracks drive, with their keys ``morphs`` (K, M)."""

    times: np.ndarray
    joints: np.ndarray
    rotations: np.ndarray
    columns: np.ndarray
    morphs: np.ndarray


class Tracks(Controller):
    """Play keyed ``rotations`` and ``morph_weights`` sampled at ``times`` (see the module doc).

    ``layer`` defaults to FACE; ``speaks=True`` marks lip-sync tracks (saccades pause meanwhile). An
    activity given no end lasts until the last sample time.
    """

    kind = "tracks"
    layer = Layer.FACE
    blend_in_s = 0.1
    blend_out_s = 0.1

    def __init__(self, times, rotations: dict | None = None, morph_weights: dict | None = None,
                 layer: Layer | int | None = None, speaks: bool = False, name: str = "tracks"):
        t = np.asarray(times, dtype=np.float64).reshape(-1)
        if len(t) == 0 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise UsageError("track times must be finite, strictly increasing seconds")
        self.times = t
        self.rotations = {k: quat.normalize(np.asarray(v, dtype=np.float64).reshape(len(t), 4)) for k, v in (rotations or {}).items()}
        self.morph_weights = {k: np.asarray(v, dtype=np.float64).reshape(len(t)) for k, v in (morph_weights or {}).items()}
        for label, table in (("rotation", self.rotations), ("morph weight", self.morph_weights)):
            for key, values in table.items():
                if not np.all(np.isfinite(values)):
                    raise UsageError(f"{label} track {key!r} holds NaN or infinity")
        if layer is not None:
            self.layer = Layer(layer)
        self.speaks = bool(speaks)
        self.name = name
        self.duration_s = float(t[-1])

    def describe(self) -> str:
        return self.name

    def bind(self, rig, report) -> TracksBinding:
        joints, keys = [], []
        for key in self.rotations:
            index = rig.joint(key)
            index = rig.skeleton.index.get(key) if index is None else index
            if index is None:
                report(f"{self.name}: no joint {key!r}; its track is skipped")
                continue
            joints.append(index)
            keys.append(key)
        columns, names = [], []
        for name in self.morph_weights:
            column = rig.morph_index.get(name)
            if column is None:
                report(f"{self.name}: no morph target {name!r}; its track is skipped")
                continue
            columns.append(column)
            names.append(name)
        rot = np.stack([self.rotations[k] for k in keys], axis=1) if keys else np.zeros((len(self.times), 0, 4))
        morph = np.stack([self.morph_weights[n] for n in names], axis=1) if names else np.zeros((len(self.times), 0))
        return TracksBinding(times=self.times, joints=np.array(joints, dtype=np.int64), rotations=rot,
                             columns=np.array(columns, dtype=np.int64), morphs=morph)

    def evaluate_one(self, job: Job, block: Block) -> None:
        b: TracksBinding = job.binding
        i0, frac = _interpolation(b.times, job.local_times)
        last = len(b.times) - 1
        if b.joints.size:
            a, c = b.rotations[i0], b.rotations[np.minimum(i0 + 1, last)]
            c = np.where(np.sum(a * c, axis=-1, keepdims=True) < 0.0, -c, c)
            job.pose.set_rotations(b.joints, quat.normalize(a + frac[:, None, None] * (c - a)), job.weight, job.mode)
        if b.columns.size:
            a, c = b.morphs[i0], b.morphs[np.minimum(i0 + 1, last)]
            job.pose.set_morphs(b.columns, a + frac[:, None] * (c - a), job.weight, job.mode)
