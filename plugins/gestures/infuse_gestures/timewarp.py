"""From the times a gesture's phases are wanted at to the times of its clip: a piecewise-linear warp.

Phases, in order: ``start``, ``ready``, ``strokeStart``, ``stroke``, ``strokeEnd``, ``relax``, ``end``
(seconds from the gesture's start). Each phase of the clip lands exactly on its wanted time. Between
two phases the clip is stretched or squeezed evenly, except after the stroke: a stroke phase or a
post-stroke phase given more time than the clip's holds the pose it starts from (the stroke, then the
stroke's end) and plays its own movement at the gesture's speed (the clip's times ``speed`` times) at the
end of the phase. Repeated strokes
go back from the stroke to strokeStart (the clip played backward) and strike again, the first stroke on
``stroke``, the post-stroke movement after the last one ending on ``strokeEnd``.
"""
from __future__ import annotations

import numpy as np

PHASES = ("start", "ready", "strokeStart", "stroke", "strokeEnd", "relax", "end")


def _breakpoints(wanted: dict, authored: dict, repeats: int, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """(wanted seconds (K,), clip seconds (K,)) of the warp's corners; wanted not decreasing."""
    w = [float(wanted[p]) for p in PHASES]
    a = [float(authored[p]) for p in PHASES]
    xs, ys = [w[0]], [a[0]]

    def add(x: float, y: float) -> None:
        xs.append(max(x, xs[-1]))
        ys.append(y)

    add(w[1], a[1])
    add(w[2], a[2])
    add(w[3], a[3])
    if repeats > 1:  # (s -> ss -> s) again for each repeat, then s -> se; evenly scaled into the wanted span
        leg = _return_leg(wanted, authored, repeats)
        for _ in range(repeats - 1):
            add(xs[-1] + leg, a[2])
            add(xs[-1] + leg, a[3])
        add(w[4], a[4])
    else:
        _held(add, w[3], w[4], a[3], a[4], speed)
    _held(add, w[4], w[5], a[4], a[5], speed)
    add(w[6], a[6])
    return np.array(xs), np.array(ys)


def _return_leg(wanted: dict, authored: dict, repeats: int) -> float:
    """Wanted seconds of one way between a repeated stroke and strokeStart: the repeats and the last
    post-stroke movement share the wanted span from stroke to strokeEnd in the clip's proportions."""
    back = float(authored["stroke"]) - float(authored["strokeStart"])
    total = float(authored["strokeEnd"]) - float(authored["stroke"]) + 2.0 * back * (repeats - 1)
    return back * (float(wanted["strokeEnd"]) - float(wanted["stroke"])) / total if total > 1e-9 else 0.0


def stroke_times(wanted: dict, authored: dict, repeats: int = 1) -> np.ndarray:
    """Wanted seconds (R,) of each of the ``repeats`` strokes, the first on ``stroke``."""
    repeats = max(int(repeats), 1)
    leg = _return_leg(wanted, authored, repeats) if repeats > 1 else 0.0
    return float(wanted["stroke"]) + 2.0 * leg * np.arange(repeats)


def _held(add, w0: float, w1: float, a0: float, a1: float, speed: float) -> None:
    """A phase from (w0, a0) to (w1, a1): wanted time beyond the movement's at ``speed`` is a hold at ``a0``
    before it."""
    moving = (a1 - a0) / speed
    if w1 - w0 > moving + 1e-9:
        add(w1 - moving, a0)
    add(w1, a1)


def phase_warp(times, wanted: dict, authored: dict, repeats: int = 1, enter_ready: bool = False,
               leave_at_stroke_end: bool = False, speed: float = 1.0) -> np.ndarray:
    """Clip seconds (F,) for ``times`` (F,) seconds from the gesture's start.

    ``wanted`` / ``authored``: seconds of every phase of :data:`PHASES`; ``repeats``: strokes (>= 1);
    ``enter_ready``: the clip waits at its ready pose until the ready phase (the gesture is entered from
    another's stroke, not from rest); ``leave_at_stroke_end``: it stays at its stroke's end from then on
    (the next gesture takes over without a retraction); ``speed``: > 0, how much faster than authored
    the movement after a hold plays.
    """
    xs, ys = _breakpoints(wanted, authored, max(int(repeats), 1), float(speed))
    t = np.asarray(times, dtype=np.float64)
    # np.interp needs increasing corners: a zero-length step keeps its later value.
    keep = np.append(np.diff(xs) > 1e-12, True)
    out = np.interp(t, xs[keep], ys[keep])
    if enter_ready:
        out = np.where(t < float(wanted["ready"]), float(authored["ready"]), out)
    if leave_at_stroke_end:
        out = np.where(t >= float(wanted["strokeEnd"]), float(authored["strokeEnd"]), out)
    return out
