"""Correspondence keys of each foot (heel strike, foot flat, heel off, toe off) and the phase maps they give.

The blend runs one phase in [0, 1) (see :func:`warp`: left strike at 0, right strike at 0.5). Each
clip's contact events are expressed in that phase; the blend's own events are the weighted means of
the clips', and each clip maps the blend's phase to its own through the piecewise-linear map that
sends the blend's events of a foot to the clip's. Played alone a clip maps onto itself; blended, every
clip has each foot in the same support phase (heel rocker, foot flat, heel off, swing) at the same
phase, so the blend's contact phases follow from its events alone.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from infuse.packs.analysis import steps

#: The events of a foot's stance, in time order.
EVENTS = ("strike", "flat", "heel_off", "off")


def warp(keys: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Clip times (seconds) of ``phase`` in [0, 1) through the clip's keys (left strike, right strike,
    next left strike; seconds) at phases 0, 0.5, 1. ``keys`` (..., 3): several clips' keys, their
    leading axes broadcast against ``phase``."""
    k0, k1, k2 = keys[..., 0], keys[..., 1], keys[..., 2]
    return np.where(phase < 0.5, k0 + (k1 - k0) * phase * 2.0, k1 + (k2 - k1) * (phase - 0.5) * 2.0)


def unwarp(keys: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The phase in [0, 1) of clip time ``t`` (seconds): the inverse of :func:`warp`."""
    u = keys[0] + np.mod(np.asarray(t, dtype=np.float64) - keys[0], keys[2] - keys[0])
    return np.where(u < keys[1], 0.5 * (u - keys[0]) / (keys[1] - keys[0]), 0.5 + 0.5 * (u - keys[1]) / (keys[2] - keys[1]))


#: How far (leg lengths) a heel may sit above its height at a strike and count as on the ground
#: (about 2.7 mm on an adult), and a ball above its height at a toe off (about 9 mm: a ball pushing
#: off rolls over the toes, rising a little while it still slides forward).
GROUNDED = 0.003
LIFTED = 0.01


#: Share of a swing each of its ends may give to the stance next to it (:func:`grounded_frames`).
GROUNDED_SHARE = 0.25


def grounded_frames(heights: np.ndarray, swinging: np.ndarray, frame: int, tolerance: float, way: int) -> int:
    """How many frames of the swing (``swinging`` (F,) flags) before (``way`` -1) or after (+1)
    frame ``frame`` a foot point stays on the ground: within ``tolerance`` metres of its height
    at that frame, going from it until the first frame it is not, at most :data:`GROUNDED_SHARE`
    of the swing (a shuffling foot may skim the ground all through it). ``heights`` (F,) metres of
    a cycle whose last frame repeats the first (indices wrap over F - 1 frames).

    A contact detector finds a strike once the heel has slowed down and a toe off once the ball
    has sped up: a heel that lands moving (as real takes do) reaches the ground a few frames before
    its strike and slides there, a ball that pushes off moving slides a few frames after its toe off
    before it lifts. Pinned over these frames, neither slides."""
    n = max(len(heights) - 1, 1)
    frames = (frame + way * np.arange(1, n)) % n
    swing = swinging[frames]
    down = (heights[frames] <= heights[frame % n] + tolerance) & swing
    within = int(np.argmin(down)) if not down.all() else 0
    return min(within, int(GROUNDED_SHARE * (np.argmin(swing) if not swing.all() else 0)))


#: Seconds: a foot's contact flags broken for no longer than this are one contact (:func:`looped`).
GAP_S = 0.1


def looped(flags: np.ndarray, gap: int) -> np.ndarray:
    """(F,) contact flags of a cycle whose last frame repeats the first, made one loop: the first
    and the last frame down if either is (a contact that starts on the cycle's seam is found on one
    side only), and breaks of at most ``gap`` frames (going round the seam) filled."""
    f = np.array(flags[:-1], dtype=bool)
    if len(flags) > 1:
        f[0] |= bool(flags[-1])
    if f.any() and not f.all():
        start = int(np.argmax(f))
        r = np.roll(f, -start)  # begins down
        d = np.diff(np.concatenate((r.astype(np.int8), [1])))
        for a, b in zip(np.nonzero(d == -1)[0] + 1, np.nonzero(d == 1)[0] + 1):
            if b - a <= gap:
                r[a:b] = True
        f = np.roll(r, start)
    return np.concatenate((f, f[:1]))


def foot_events(clip, heights: np.ndarray | None = None, leg_length: float = 1.0) -> np.ndarray | None:
    """(2, 4) phases of each foot's (left, right) strike, flat, heel off and toe off in a looping
    clip's cycle, non-decreasing from the strike (in [0, 1)); None when a foot does not step once,
    unless the other steps once and it not at all (a running take's foot that lands moving is not
    found down): the feet of a gait cycle alternate, its events are then the other's half a cycle
    later. With the feet's heights (F, 2, 2) metres over the cycle (ankle, ball), a strike is where
    the heel reached the ground and a toe off where the ball left it (:func:`grounded_frames`, within
    :data:`GROUNDED` and :data:`LIFTED` leg lengths of ``leg_length`` metres)."""
    fps = clip.motion.fps
    gap = int(round(GAP_S * fps))
    contacts = np.stack([looped(clip.contacts[:, k], gap) for k in range(2)], axis=1)
    phases = None if clip.phases is None else \
        np.stack([np.stack([looped(clip.phases[:, k, n], gap) for n in range(2)], axis=-1) for k in range(2)], axis=1)
    found = steps(contacts, fps, True, phases)
    mine = [[s for s in found if s["foot"] == foot] for foot in ("left", "right")]
    counts = [len(m) for m in mine]
    if counts != [1, 1] and sorted(counts) != [0, 1]:
        return None
    out = np.zeros((2, 4))
    for k in range(2):
        if not mine[k]:
            continue
        times = np.array([mine[k][0][e] for e in EVENTS])
        if heights is not None:
            swinging = ~contacts[:, k]
            times[0] -= grounded_frames(heights[:, k, 0], swinging, int(round(times[0] * fps)), GROUNDED * leg_length, -1) / fps
            # The toe off's frame is the first of the swing (a contact's end is exclusive).
            off = int(round(times[3] * fps))
            times[3] += grounded_frames(heights[:, k, 1], swinging, off - 1, LIFTED * leg_length, 1) / fps
        # A contact flag holds for its frame's half-frame either side (frames are sampled nearest).
        ph = unwarp(clip.keys, times - 0.5 / fps)
        ph = np.where(ph > 1.0 - 1e-6, ph - 1.0, ph)  # a strike on a key rounded just below it
        ph[1:] += np.where(ph[1:] < ph[0], 1.0, 0.0)  # events past the cycle's end
        out[k] = np.maximum.accumulate(ph)
    if 0 in counts:
        k = counts.index(0)
        out[k] = out[1 - k] + 0.5 - np.floor(out[1 - k, 0] + 0.5)
    return out


class FootKeys(NamedTuple):
    """What :func:`foot_phase` reads of the blend's events ``theirs`` (F, [2,] 4) and the clips' ``mine``
    ([U,] [2,] 4), worked out once for both: the blend's events closed by the next strike (P, 5) (its rows
    flat, P = F or 2F), the events after its strikes (F, [2,] 4) and its strikes (F, [2]), each row's index
    into those (F, [2]) and its foot's among the clips' events closed alike ([U,] feet, 5)."""

    events: np.ndarray
    later: np.ndarray
    strikes: np.ndarray
    rows: np.ndarray
    feet: np.ndarray
    mine: np.ndarray


def foot_keys(mine: np.ndarray, theirs: np.ndarray) -> FootKeys:
    """The :class:`FootKeys` of the clips' events ``mine`` and the blend's ``theirs`` (see :func:`foot_phase`)."""
    x = np.concatenate((theirs, theirs[..., :1] + 1.0), axis=-1)  # (F, [2,] 5)
    y = np.concatenate((mine, mine[..., :1] + 1.0), axis=-1)  # ([U,] [2,] 5)
    start = x[..., 0]
    rows = np.arange(start.size).reshape(start.shape)
    y = y.reshape(y.shape[:y.ndim - theirs.ndim + 1] + (-1, 5))  # ([U,] feet, 5), one foot's row when alone
    return FootKeys(x.reshape(-1, 5), x[..., 1:], start, rows, rows % y.shape[y.ndim - 2], y)


def foot_phase(mine: np.ndarray, theirs: np.ndarray, phase: np.ndarray, keys: FootKeys | None = None) -> np.ndarray:
    """Clip phases (F,) in [0, 1) of blend ``phase`` (F,) for one foot: piecewise linear from the
    blend's events ``theirs`` (F, 4) to the clip's ``mine`` (4,), one cycle after the strike closing it.
    Both feet at once with ``mine`` (2, 4) and ``theirs`` (F, 2, 4): phases (F, 2); and U clips' both
    feet with ``mine`` (U, 2, 4): phases (U, F, 2). ``keys``: their :func:`foot_keys`, if already made."""
    x, later, start, rows, foot, y = foot_keys(mine, theirs) if keys is None else keys
    p = start + np.mod(phase.reshape((-1,) + (1,) * (start.ndim - 1)) - start, 1.0)
    seg = np.minimum((p[..., None] >= later).sum(axis=-1), 3)  # (np.clip costs more on a block's few rows)
    # Each row's segment ends picked from the rows flattened (fancy indexing beats take_along_axis here).
    x0, x1 = x[rows, seg], x[rows, seg + 1]
    y0, y1 = y[..., foot, seg], y[..., foot, seg + 1]
    frac = np.minimum(np.maximum((p - x0) / np.maximum(x1 - x0, 1e-9), 0.0), 1.0)
    return np.mod(y0 + frac * (y1 - y0), 1.0)


def stance_of(events: np.ndarray, phase: np.ndarray, handover: float = 1.0, ramp: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Each foot's contacts and stance share at ``phase`` (F,) from the blend's ``events`` (F, 2, 4).

    - (F, 2, 2) flags of the heel and the ball being down: the heel from strike to heel off, the
      ball from foot flat to toe off. ``handover`` < 1 ends the heel's flag that share of the way
      from foot flat to heel off instead, for a controller that pins the ball from there on: in the
      middle of foot flat the foot rests still, so the anchor changes while nothing moves (at foot
      flat the foot is still rolling down about its heel, at heel off it has started to roll about
      its ball).
    - (F, 2) how much each foot is in its stance: 1 from ``ramp`` after heel strike to ``ramp``
      before toe off, 0 in the swing, linear in between (continuous in the phase, for adjustments
      that must not jump at strike or toe off)."""
    strike, flat, heel_off, off = (events[:, :, k] for k in range(4))
    p = strike + np.mod(phase[:, None] - strike, 1.0)  # (F, 2) from each foot's strike
    flags = np.empty(p.shape + (2,), dtype=bool)  # heel and ball (np.stack costs more on a block's few rows)
    np.less(p, flat + handover * (heel_off - flat), out=flags[..., 0])
    flags[..., 1] = (p >= flat) & (p < off)
    support = np.minimum(np.maximum((p - strike) / ramp, 0.0), 1.0) * np.minimum(np.maximum((off - p) / ramp, 0.0), 1.0)
    return flags, support
