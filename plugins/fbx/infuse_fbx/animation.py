"""FBX animation: stacks, their base layer, curve nodes driving model T/R/S, and curve sampling.

Graph: AnimationStack <- AnimationLayer <- AnimationCurveNode (-> a model's ``Lcl Translation``,
``Lcl Rotation`` or ``Lcl Scaling``) <- AnimationCurve (``d|X``, ``d|Y``, ``d|Z``). A curve has
``KeyTime`` (int64 ticks, 46186158000 per second), ``KeyValueFloat``, and per-key attributes
shared through ``KeyAttrRefCount``: ``KeyAttrFlags`` (constant 0x2, linear 0x4, cubic 0x8;
0x100 = constant takes the next key's value) and ``KeyAttrDataFloat`` (right slope, next key's
left slope, in value units per second, ...). Cubic segments are sampled as Hermite splines with
those slopes (tangent weights are ignored). Curves hold their end values outside their keys.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .document import Document, FbxObject, number

TICKS_PER_SECOND = 46_186_158_000

#: GlobalSettings TimeMode -> frames per second (0 = the default, 14 = CustomFrameRate).
TIME_MODES = {0: 30.0, 1: 120.0, 2: 100.0, 3: 60.0, 4: 50.0, 5: 48.0, 6: 30.0, 7: 30.0, 8: 29.97, 9: 29.97,
              10: 25.0, 11: 24.0, 12: 1000.0, 13: 23.976, 15: 96.0, 16: 72.0, 17: 59.94, 18: 119.88}

CHANNELS = {"Lcl Translation": 0, "Lcl Rotation": 1, "Lcl Scaling": 2}

_CONSTANT, _LINEAR, _CUBIC, _CONSTANT_NEXT = 0x2, 0x4, 0x8, 0x100


@dataclass
class Curve:
    times: np.ndarray  # seconds (K,)
    values: np.ndarray  # (K,)
    flags: np.ndarray  # (K,) interpolation flags of the segment starting at each key
    right_slopes: np.ndarray  # (K,)
    next_left_slopes: np.ndarray  # (K,)


@dataclass
class Take:
    """One stack's base layer: per model id and channel (0 T, 1 R, 2 S), three curves or defaults."""

    name: str
    start: float
    stop: float
    tracks: dict[tuple[int, int], list[Curve | float]]
    layers: int


def frame_rate(doc: Document, settings: dict) -> float:
    mode = int(number(doc, settings, "TimeMode", 0.0))
    if mode == 14:
        fps = number(doc, settings, "CustomFrameRate", 30.0)
        return fps if fps > 0 else 30.0
    return TIME_MODES.get(mode, 30.0)


def takes(doc: Document) -> list[Take]:
    """Every animation stack that animates at least one model transform."""
    out = []
    for stack in (o for o in doc.objects.values() if o.kind == "AnimationStack"):
        layers = [o for o, _ in doc.children_of(stack.id, "AnimationLayer")]
        if not layers:
            continue
        tracks: dict[tuple[int, int], list[Curve | float]] = {}
        for node, _ in doc.children_of(layers[0].id, "AnimationCurveNode"):
            for model, prop in doc.parents_of(node.id, "Model"):
                if prop in CHANNELS:
                    tracks[(model.id, CHANNELS[prop])] = _components(doc, node)
        if not tracks:
            continue
        keyed = [c.times for track in tracks.values() for c in track if isinstance(c, Curve)]
        first = min((float(t[0]) for t in keyed), default=0.0)
        last = max((float(t[-1]) for t in keyed), default=0.0)
        start = _time(doc, stack, "LocalStart", first)
        stop = _time(doc, stack, "LocalStop", last)
        if stop < start:
            raise doc.error(stack.node, f"animation stack {stack.name!r} stops before it starts")
        out.append(Take(stack.name, start, stop, tracks, len(layers)))
    return out


def _time(doc: Document, obj: FbxObject, name: str, default: float) -> float:
    values = obj.props.get(name)
    if not values:
        return default
    if not isinstance(values[0], int):
        raise doc.error(obj.node, f"{obj.name!r}: {name} is not a time")
    return values[0] / TICKS_PER_SECOND


def _components(doc: Document, node: FbxObject) -> list[Curve | float]:
    comps: list[Curve | float] = []
    for axis in "XYZ":
        curves = [c for c, _ in doc.children_of(node.id, "AnimationCurve", f"d|{axis}")]
        if curves:
            comps.append(_curve(doc, curves[0]))
        else:
            comps.append(number(doc, node.props, f"d|{axis}", np.nan, node.node))
    return comps


def _array(doc: Document, obj: FbxObject, name: str, required: bool = True) -> np.ndarray | None:
    rec = obj.node.find(name)
    if rec is None or not rec.props or not isinstance(rec.props[0], np.ndarray):
        if required:
            raise doc.error(obj.node, f"curve {obj.name!r} has no {name} array")
        return None
    return rec.props[0]


def _curve(doc: Document, obj: FbxObject) -> Curve:
    times = _array(doc, obj, "KeyTime").astype(np.float64) / TICKS_PER_SECOND
    values = _array(doc, obj, "KeyValueFloat").astype(np.float64)
    k = len(times)
    if k == 0 or len(values) != k:
        raise doc.error(obj.node, f"curve has {k} key times and {len(values)} values")
    if not (np.all(np.isfinite(values)) and np.all(np.isfinite(times))):
        raise doc.error(obj.node, "curve key is not finite")
    if np.any(np.diff(times) < 0):
        raise doc.error(obj.node, "curve key times decrease")
    flags = np.full(k, _LINEAR, dtype=np.int64)
    right = np.zeros(k)
    left = np.zeros(k)
    attr_flags = _array(doc, obj, "KeyAttrFlags", required=False)
    refcount = _array(doc, obj, "KeyAttrRefCount", required=False)
    if attr_flags is not None and refcount is not None:
        if len(refcount) != len(attr_flags) or np.any(refcount < 0) or int(refcount.sum()) != k:
            raise doc.error(obj.node, "KeyAttrRefCount does not cover the keys")
        per_key = np.repeat(np.arange(len(attr_flags)), refcount)
        flags = attr_flags.astype(np.int64)[per_key]
        data = _array(doc, obj, "KeyAttrDataFloat", required=False)
        if data is not None and len(data) == 4 * len(attr_flags):
            data = data.astype(np.float64).reshape(-1, 4)
            right, left = data[per_key, 0], data[per_key, 1]
            if not (np.all(np.isfinite(right)) and np.all(np.isfinite(left))):
                raise doc.error(obj.node, "curve tangent is not finite")
    return Curve(times, values, flags, right, left)


def sample(curve: Curve, t: np.ndarray) -> np.ndarray:
    """Values of ``curve`` at times ``t`` (F,) in seconds, vectorized."""
    times, values = curve.times, curve.values
    if len(times) == 1:
        return np.full(len(t), values[0])
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    tc = np.clip(t, times[0], times[-1])
    t0, t1 = times[seg], times[seg + 1]
    dt = t1 - t0
    u = np.where(dt > 0, (tc - t0) / np.where(dt > 0, dt, 1.0), 0.0)
    v0, v1 = values[seg], values[seg + 1]
    f = curve.flags[seg]
    linear = v0 + u * (v1 - v0)
    cubic = ((2 * u**3 - 3 * u**2 + 1) * v0 + (u**3 - 2 * u**2 + u) * dt * curve.right_slopes[seg]
             + (-2 * u**3 + 3 * u**2) * v1 + (u**3 - u**2) * dt * curve.next_left_slopes[seg])
    constant = np.where(f & _CONSTANT_NEXT, v1, v0)
    out = np.where(f & _CUBIC, cubic, np.where(f & _CONSTANT, constant, linear))
    return np.where(t >= times[-1], values[-1], out)
