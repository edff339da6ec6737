"""Coarticulation: phoneme intervals with target poses -> smooth channel weights over time.

All steps work on every time sample at once (numpy), ``(K,)`` sample times against ``(P,)``
phoneme intervals with ``(P, C)`` targets in some channel space:

1. Cohen-Massaro dominance blend: each phoneme ``i`` pulls towards its target ``T_i`` with
   dominance ``D_i(t) = alpha_i * exp(-theta_i * d_i(t))``, ``d_i`` the distance in seconds from
   ``t`` to the phoneme's interval (0 inside it, so a long phoneme holds its shape), ``theta`` its
   anticipation rate before the interval and carry-over rate after it. The output is
   ``sum_i D_i T_i / sum_i D_i``. Only the ``band`` nearest phonemes on each side count (further
   ones have dominance ~exp(-6) or less).
2. Smoothing with a Gaussian of ``smoothing_s`` (zero phase).
3. A speed limit of ``speed_limit`` units/s per channel, without delay: the mean of the smallest
   speed-limited curve above the signal and the largest one below it (both from grey
   dilation/erosion with a cone), which leaves curves already within the limit unchanged.
4. Holds: intervals where the pose must be exact (bilabial closures, rest during pauses) blend to
   their pose with a trapezoid envelope that is 1 on a plateau and ramps linearly to 0; these are
   applied last so that closures are complete whatever the speed limit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage


@dataclass(frozen=True)
class Hold:
    """Where a pose must be exact: ``plateau_start``/``plateau_end`` (s) at full weight, reached from 0
    over ``ramp_in_s`` before and left over ``ramp_out_s`` after; ``target`` (C,) the pose."""

    plateau_start: np.ndarray
    plateau_end: np.ndarray
    ramp_in_s: np.ndarray
    ramp_out_s: np.ndarray
    target: np.ndarray


def sample_times(duration_s: float, fps: float) -> np.ndarray:
    """``ceil(duration * fps) + 1`` frame times from 0: the last is at or after the end, by less than a frame."""
    count = int(np.ceil(duration_s * fps - 1e-9)) + 1
    return np.arange(count) / fps


def dominance_blend(times: np.ndarray, starts: np.ndarray, ends: np.ndarray, targets: np.ndarray, alpha: np.ndarray,
                    theta_before: np.ndarray, theta_after: np.ndarray, rest: np.ndarray, band: int = 4) -> np.ndarray:
    """``(K, C)`` weights: the dominance-weighted mean of the phoneme targets (see the module doc).

    ``starts``, ``ends`` (P,) sorted, non-overlapping, seconds; ``targets`` (P, C); ``alpha``,
    ``theta_*`` (P,). Samples where no phoneme has any dominance get ``rest`` (C,).
    """
    P = len(starts)
    if P == 0:
        return np.tile(rest, (len(times), 1))
    nearest = np.clip(np.searchsorted(ends, times, side="left"), 0, P - 1)           # (K,)
    offsets = np.arange(-band, band + 1)
    idx = nearest[:, None] + offsets[None, :]                                          # (K, 2b+1)
    valid = (idx >= 0) & (idx < P)
    idx = np.clip(idx, 0, P - 1)
    t = times[:, None]
    before = t < starts[idx]
    dist = np.where(before, starts[idx] - t, np.maximum(t - ends[idx], 0.0))
    theta = np.where(before, theta_before[idx], theta_after[idx])
    dom = np.where(valid, alpha[idx] * np.exp(-theta * dist), 0.0)                   # (K, 2b+1)
    total = dom.sum(axis=1, keepdims=True)
    blended = np.einsum("kn,knc->kc", dom, targets[idx])
    out = np.where(total > 1e-12, blended / np.maximum(total, 1e-12), rest[None, :])
    return out


def smooth(weights: np.ndarray, sigma_s: float, fps: float) -> np.ndarray:
    """Zero-phase Gaussian smoothing along time (axis 0); ``sigma_s`` in seconds."""
    sigma = sigma_s * fps
    if sigma < 0.25:  # less than a quarter frame: nothing to do
        return weights
    return ndimage.gaussian_filter1d(weights, sigma, axis=0, mode="nearest")


def limit_speed(weights: np.ndarray, speed_limit: float, fps: float) -> np.ndarray:
    """Each channel changes by at most ``speed_limit`` units/s, with no delay (see the module doc)."""
    if not np.isfinite(speed_limit) or speed_limit <= 0 or len(weights) < 2:
        return weights
    step = speed_limit / fps
    span = float(np.ptp(weights)) if weights.size else 0.0
    radius = int(np.ceil(span / step)) if span > 0 else 0
    if radius == 0:
        return weights
    radius = min(radius, len(weights))
    cone = -step * np.abs(np.arange(-radius, radius + 1, dtype=float))[:, None]       # (2r+1, 1)
    upper = ndimage.grey_dilation(weights, structure=cone, mode="nearest")
    lower = ndimage.grey_erosion(weights, structure=cone, mode="nearest")
    return 0.5 * (upper + lower)


def hold_envelope(times: np.ndarray, hold: Hold) -> np.ndarray:
    """(K,) trapezoid envelope of the hold intervals (max over them), 0..1."""
    n = len(hold.plateau_start)
    if n == 0:
        return np.zeros(len(times))
    # the holds are disjoint and ordered: each sample only sees the one before it and the one after
    after = np.clip(np.searchsorted(hold.plateau_start, times, side="right"), 0, n - 1)
    before = np.clip(after - 1, 0, n - 1)
    env = np.zeros(len(times))
    for k in (before, after):
        s, e = hold.plateau_start[k], hold.plateau_end[k]
        rise = np.where(hold.ramp_in_s[k] > 0, (times - (s - hold.ramp_in_s[k])) / np.maximum(hold.ramp_in_s[k], 1e-12), 0.0)
        fall = np.where(hold.ramp_out_s[k] > 0, ((e + hold.ramp_out_s[k]) - times) / np.maximum(hold.ramp_out_s[k], 1e-12), 0.0)
        inside = (times >= s) & (times <= e)
        value = np.where(inside, 1.0, np.where(times < s, rise, fall))
        env = np.maximum(env, np.clip(value, 0.0, 1.0))
    return env


def apply_hold(times: np.ndarray, weights: np.ndarray, hold: Hold) -> np.ndarray:
    """``weights`` blended towards ``hold.target`` by the hold envelope."""
    env = hold_envelope(times, hold)[:, None]
    return weights * (1.0 - env) + hold.target[None, :] * env
