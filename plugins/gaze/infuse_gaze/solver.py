"""The gaze solver, batched over every gazing character and vectorized over the frames of a block.

Everything is expressed in the chain's *slots* (:data:`~infuse_gaze.model.SLOTS`, pelvis to eyes) and
in their aligned frames (:mod:`infuse.runtime.swing`; a slot the character lacks repeats its parent).
For each character and frame the caller gives, from the pose below the gaze, each slot's aligned
frame and position in the world, where the gaze starts and where the priority joint points. The
solver derives each slot's frame relative to its parent slot and its view of the gaze origin and
direction when it first reaches the slot: the chain above a slot is rigid until its group is solved,
so one matrix product per slot and frame gives the whole picture.

Per frame, groups are solved bottom-up (Thiebaux et al. 2009): with the groups above still at the
pose below, the turn left to do is the heading and pitch from where the priority joint points to
where the target is (seen from the eyes, or the head), in the group's aligned frame. A group below
the priority group takes 1/(p + 1 - i) of it (i its rank, p the priority's, among the groups that
move), clamped to its elliptical limits; the priority group and the groups above take all of it.
The result is weighted by the activity's blend weight, smoothed and speed-limited, and the chain is
moved before the next group is solved, so the groups above make up for what lags below. Each eye
finally aims from its own position. Outputs are (heading, pitch) offsets in radians per slot.

A group's wish at a frame depends only on the groups below it at that frame, so the solver runs
group by group over all frames at once; only the smoothing (:func:`follow`) steps frame by frame.
"""
from __future__ import annotations

import functools
import math

from dataclasses import dataclass, replace

import numpy as np

from infuse.runtime.swing import direction_angles

from .model import EYES, SLOT_GROUPS, SLOT_PARENTS, SLOTS

_S = len(SLOTS)
_EYE_SLOTS = (7, 8)
_FIRST_SLOT = {g: SLOT_GROUPS.index(g) for g in set(SLOT_GROUPS)}


@dataclass
class SolverInput:
    """Arrays over C characters, F frames, S slots, G groups (angles in radians, lengths in metres).

    - ``frames_world`` (C, F, S, 3, 3), ``positions`` (C, F, S, 3): each slot's aligned frame (a matrix
      acting on column vectors) and position in the world, in the pose below the gaze;
    - ``origin`` (C, F, 3): where the gaze starts (the eyes, or the head); ``forward`` (C, F, 3): where the
      priority joint points (a unit vector), both in the world and the pose below;
    - ``present`` (C, S) bool; ``counts`` (C, G): joints each group has (eyes: 1, they act side by side);
    - ``targets`` (C, F, 3); ``weights`` (C, F) blend weights;
    - per frame (the gaze in charge may change within a block): ``active`` (C, F, G) bool: groups that
      move; ``fractions`` (C, F, G): share of the remaining turn; ``limits`` (C, F, G, 4): heading, up,
      down, roll; ``smoothing`` (C, F, G): share per frame; ``max_step`` (C, F, G): radians per frame;
      ``offsets`` (C, F, 2): heading and pitch added to the target direction.
    - ``refine``: (c, c2, slots) triples: character c looks at the mean of ``slots`` of character c2,
      taken from a first solve of the block.
    """

    frames_world: np.ndarray
    positions: np.ndarray
    origin: np.ndarray
    forward: np.ndarray
    present: np.ndarray
    counts: np.ndarray
    targets: np.ndarray
    weights: np.ndarray
    active: np.ndarray
    fractions: np.ndarray
    limits: np.ndarray
    smoothing: np.ndarray
    max_step: np.ndarray
    offsets: np.ndarray
    refine: tuple = ()


def swing_matrices(heading: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """(..., 3, 3) matrices of ``R_Y(heading) R_X(-pitch)``: +Z turned to (heading, pitch)."""
    ch, sh, cv, sv = np.cos(heading), np.sin(heading), np.cos(pitch), np.sin(pitch)
    out = np.empty(np.shape(heading) + (3, 3))
    out[..., 0, 0] = ch
    out[..., 0, 1] = -sh * sv
    out[..., 0, 2] = sh * cv
    out[..., 1, 0] = 0.0
    out[..., 1, 1] = cv
    out[..., 1, 2] = sv
    out[..., 2, 0] = -sh
    out[..., 2, 1] = -ch * sv
    out[..., 2, 2] = ch * cv
    return out


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(..., 3, 3) matrices of unit quaternions (..., 4) (x, y, z, w)."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(q.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[..., 0, 1] = 2.0 * (x * y - z * w)
    out[..., 0, 2] = 2.0 * (x * z + y * w)
    out[..., 1, 0] = 2.0 * (x * y + z * w)
    out[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[..., 1, 2] = 2.0 * (y * z - x * w)
    out[..., 2, 0] = 2.0 * (x * z - y * w)
    out[..., 2, 1] = 2.0 * (y * z + x * w)
    out[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return out


def _angles(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.arctan2(v[..., 0], v[..., 2]), np.arctan2(v[..., 1], np.hypot(v[..., 0], v[..., 2]))


def _clamp(h, v, limits):
    """(h, v) (...) scaled onto the ellipse of ``limits`` (..., 4) when outside it; an axis with a zero
    limit does not turn at all."""
    vertical = np.where(v >= 0.0, limits[..., 1], limits[..., 2])
    h = np.where(limits[..., 0] > 0, h, 0.0)
    v = np.where(vertical > 0, v, 0.0)
    a = h / np.where(limits[..., 0] > 0, limits[..., 0], 1.0)
    b = v / np.where(vertical > 0, vertical, 1.0)
    f = 1.0 / np.maximum(np.sqrt(a * a + b * b), 1.0)
    return h * f, v * f


def follow(desired: np.ndarray, smoothing: np.ndarray, max_step: np.ndarray, state: np.ndarray):
    """Smoothed, speed-limited path (C, F, 2) toward ``desired`` (C, F, 2) from ``state`` (C, 2).

    Each frame covers ``smoothing`` (C, F) of the distance left, at most ``max_step`` (C, F) radians.
    Returns the final state (C, 2) and the path. Without the speed limit at work and with one share
    per row the path is a linear filter (:func:`_follow_linear`); else it is stepped frame by frame,
    the only loop over frames in the solver (rows at rest with nothing to follow stay at rest without it).
    """
    if (smoothing >= 1.0).all():  # no smoothing: the path is the target unless a step is too long
        steps = np.diff(np.concatenate((state[:, None], desired), axis=1), axis=1)
        if (np.sqrt(np.sum(steps * steps, axis=-1)) <= max_step).all():
            return desired[:, -1].copy(), desired.copy()
    linear = _follow_linear(desired, smoothing, max_step, state)
    if linear is not None:
        return linear
    rows = np.flatnonzero((desired != 0.0).any(axis=(1, 2)) | (state != 0.0).any(axis=1))
    if rows.size == len(state):
        return _step_frames(desired, smoothing, max_step, state)
    final, path = state.copy(), np.zeros_like(desired)
    if rows.size:
        final[rows], path[rows] = _step_frames(desired[rows], smoothing[rows], max_step[rows], state[rows])
    return final, path


@functools.lru_cache(maxsize=64)
def _smoothing_filter(shares: tuple[float, ...], frames: int) -> tuple[np.ndarray, np.ndarray]:
    """The smoothing over ``frames`` frames as a linear map, per row of constant share s per frame
    (a = 1 - s): the path is ``x_f = a^(f+1) x_0 + sum_(k<=f) s a^(f-k) d_k``. Returns the (R, F, F)
    lower triangular matrices of ``s a^(f-k)`` and the (R, F) powers ``a^(f+1)`` (read-only, cached)."""
    share = np.array(shares)[:, None, None]
    lag = np.arange(frames)[:, None] - np.arange(frames)[None]
    matrix = np.where(lag >= 0, share * (1.0 - share) ** np.maximum(lag, 0), 0.0)
    powers = (1.0 - share[:, 0]) ** np.arange(1, frames + 1)
    matrix.flags.writeable = powers.flags.writeable = False
    return matrix, powers


def _follow_linear(desired, smoothing, max_step, state):
    """:func:`follow` in closed form (:func:`_smoothing_filter`) when each row's share is the same over
    the block; None when it is not, or when a step of that path exceeds the speed limit (then the
    limit shapes the path and it is stepped frame by frame). Equal to the stepped path up to rounding."""
    shares = smoothing[:, 0]
    if not (smoothing == shares[:, None]).all():
        return None
    matrix, powers = _smoothing_filter(tuple(shares.tolist()), desired.shape[1])
    path = matrix @ desired + powers[..., None] * state[:, None]
    steps = np.diff(path, axis=1, prepend=state[:, None])
    if (np.sqrt(np.sum(steps * steps, axis=-1)) > max_step).any():
        return None
    return path[:, -1].copy(), path


def _step_frames(desired, smoothing, max_step, state):
    """:func:`follow` frame by frame: on Python floats for a few rows, else on arrays over the rows."""
    if desired.shape[0] <= SCALAR_FOLLOW_MAX_CHARACTERS:
        return _follow_scalar(desired, smoothing, max_step, state)
    frames = desired.shape[1]
    path = np.empty_like(desired)
    share = smoothing[..., None]
    for f in range(frames):
        step = share[:, f] * (desired[:, f] - state)
        norm = np.sqrt(step[:, 0] * step[:, 0] + step[:, 1] * step[:, 1])
        limit = max_step[:, f]
        state = state + step * np.where(norm > limit, limit / np.maximum(norm, 1e-300), 1.0)[:, None]
        path[:, f] = state
    return state, path


#: Below this many characters the per-frame step runs on Python floats: numpy's per-call overhead on
#: arrays of a few elements costs more than the arithmetic. Both paths give bit-identical results.
SCALAR_FOLLOW_MAX_CHARACTERS = 8


def _follow_scalar(desired: np.ndarray, smoothing: np.ndarray, max_step: np.ndarray, state: np.ndarray):
    """:func:`follow` for a few characters, one Python float operation at a time (same arithmetic)."""
    paths = []
    finals = []
    for wish, share, limit, (x, y) in zip(desired.tolist(), smoothing.tolist(), max_step.tolist(), state.tolist()):
        row = []
        for (wx, wy), s, lim in zip(wish, share, limit):
            dx = s * (wx - x)
            dy = s * (wy - y)
            norm = math.sqrt(dx * dx + dy * dy)
            if norm > lim:
                k = lim / max(norm, 1e-300)
                dx *= k
                dy *= k
            x += dx
            y += dy
            row.append((x, y))
        paths.append(row)
        finals.append((x, y))
    return np.array(finals, dtype=np.float64).reshape(state.shape), np.array(paths, dtype=np.float64).reshape(desired.shape)


def apply_matrices(m, v):
    """Matrices (..., 3, 3) times vectors (..., 3)."""
    return (m @ v[..., None])[..., 0]


def _apply_t(m, v):
    """Transposed matrices (..., 3, 3) times vectors (..., 3)."""
    return (v[..., None, :] @ m)[..., 0, :]


def _pairs(h, v, gain):
    """(..., 2) heading and pitch (...) times ``gain`` (...)."""
    out = np.empty(h.shape + (2,))
    np.multiply(h, gain, out=out[..., 0])
    np.multiply(v, gain, out=out[..., 1])
    return out


def _direction(frame, vector, forward_h, forward_v, fixed):
    """Heading and pitch left to turn: from the forward angles to ``vector`` seen in ``frame``, plus the fixed offsets."""
    ht, vt = _angles(_apply_t(frame, vector))
    return (ht + fixed[..., 0] - forward_h + np.pi) % (2 * np.pi) - np.pi, vt + fixed[..., 1] - forward_v


class _PoseBelow:
    """What the solver reads from the pose below, per slot, computed when first asked (the slots below
    the first that turns need none of it) and shared by both passes of a block."""

    def __init__(self, inp: SolverInput):
        self.inp = inp
        self._relative: dict = {}
        self._views: dict = {}

    def relative(self, slots: list[int]):
        """Sibling slots' aligned frames (C, F, K, 3, 3) and positions (C, F, K, 3) relative to their
        parent slot's aligned frame."""
        key = tuple(slots)
        if key not in self._relative:
            frames, positions = self.inp.frames_world, self.inp.positions
            p = SLOT_PARENTS[slots[0]]
            inverse = np.swapaxes(frames[:, :, p, None], -1, -2)  # (C, F, 1, 3, 3)
            self._relative[key] = (inverse @ frames[:, :, slots],
                                   apply_matrices(inverse, positions[:, :, slots] - positions[:, :, p, None]))
        return self._relative[key]

    def view(self, slot: int):
        """Where the gaze starts (C, F, 3), and the heading and pitch (C, F) of where the priority joint
        points, seen from a slot's aligned frame."""
        if slot not in self._views:
            inverse = np.swapaxes(self.inp.frames_world[:, :, slot], -1, -2)
            origin = apply_matrices(inverse, self.inp.origin - self.inp.positions[:, :, slot])
            self._views[slot] = (origin, direction_angles(apply_matrices(inverse, self.inp.forward)))
        return self._views[slot]


def solve(inp: SolverInput, groups_state: np.ndarray, eyes_state: np.ndarray):
    """Run the block; returns (offsets (C, F, S, 2), positions (C, F, S, 3) of the solved chain).

    ``groups_state`` (C, G, 2) and ``eyes_state`` (C, 2, 2) hold the current offsets and are updated
    in place. Characters looking at another one's eyes or head (``refine``) get a second pass with
    that character's solved positions.
    """
    below = _PoseBelow(inp)
    if not inp.refine:
        return _solve_once(inp, below, groups_state, eyes_state)
    # The first pass only places the chains (no joint's position depends on the eyes' turn).
    _, positions = _solve_once(inp, below, groups_state.copy(), eyes_state, eyes=False)
    targets = inp.targets.copy()
    for c, c2, slots in inp.refine:
        targets[c] = positions[c2][:, list(slots)].mean(axis=1)
    return _solve_once(replace(inp, targets=targets), below, groups_state, eyes_state)


def _solve_once(inp: SolverInput, below: _PoseBelow, groups_state: np.ndarray, eyes_state: np.ndarray,
                eyes: bool = True):
    """Groups bottom-up, each over all frames at once: a group's wish at a frame depends only on the
    groups below it at that frame, so only the smoothing runs frame by frame (:func:`follow`). A group
    no character turns (and none is on its way back) is skipped: its joints stay as they are. Without
    ``eyes`` the eyes keep still (their offsets are 0 and their state is left as it was)."""
    c_count, frames = inp.targets.shape[:2]
    out = np.zeros((c_count, frames, _S, 2))
    w_rot = np.empty((c_count, frames, _S, 3, 3))
    w_pos = np.empty((c_count, frames, _S, 3))
    counts = np.maximum(inp.counts, 1)[:, None, :, None]  # (C, 1, G, 1)
    present = inp.present[:, None, :, None]  # (C, 1, S, 1)
    target = inp.targets
    gains = inp.active * inp.weights[..., None]  # (C, F, G)
    turning = (np.any(gains != 0.0, axis=(0, 1)) | np.any(groups_state != 0.0, axis=(0, 2))).tolist()
    absent = (~inp.present.any(axis=0)).tolist()  # slots no character has: they repeat their parent
    moved = False  # until a slot turns, the chain stands as in the pose below
    share = None
    for s in range(_EYE_SLOTS[0]):
        p = SLOT_PARENTS[s]
        if not moved:
            pre = inp.frames_world[:, :, s]
            w_pos[:, :, s] = inp.positions[:, :, s]
        elif absent[s]:
            pre = w_rot[:, :, p]
            w_pos[:, :, s] = w_pos[:, :, p]
        else:
            rotation, position = below.relative([s])
            pre = w_rot[:, :, p] @ rotation[:, :, 0]
            w_pos[:, :, s] = w_pos[:, :, p] + apply_matrices(w_rot[:, :, p], position[:, :, 0])
        g = SLOT_GROUPS[s]
        if turning[g] and _FIRST_SLOT[g] == s:
            origin, (forward_h, forward_v) = below.view(s)
            dh, dv = _direction(pre, target - w_pos[:, :, s] - apply_matrices(pre, origin), forward_h, forward_v,
                                inp.offsets)
            fraction = inp.fractions[:, :, g]
            dh, dv = _clamp(dh * fraction, dv * fraction, inp.limits[:, :, g])
            groups_state[:, g], path = follow(_pairs(dh, dv, gains[:, :, g]), inp.smoothing[:, :, g],
                                              inp.max_step[:, :, g], groups_state[:, g])
            share = path / counts[:, :, g]
        if not turning[g] or absent[s]:
            w_rot[:, :, s] = pre
            continue
        hv = np.where(present[:, :, s], share, 0.0)
        out[:, :, s] = hv
        w_rot[:, :, s] = pre @ swing_matrices(hv[..., 0], hv[..., 1])
        moved = True
    # The eyes, side by side: each turns from its own position, all the way (within its limits).
    pair, p = list(_EYE_SLOTS), SLOT_PARENTS[_EYE_SLOTS[0]]
    if moved:
        parent = w_rot[:, :, p, None]
        rotation, position = below.relative(pair)
        w_pos[:, :, pair] = w_pos[:, :, p, None] + apply_matrices(parent, position)
    else:
        w_pos[:, :, pair] = inp.positions[:, :, pair]
    if not (eyes and (inp.present[:, pair].any() or eyes_state.any())):
        return out, w_pos
    pre = parent @ rotation if moved else inp.frames_world[:, :, pair]
    dh, dv = _direction(pre, target[:, :, None] - w_pos[:, :, pair], 0.0, 0.0,
                        inp.offsets[:, :, None])
    dh, dv = _clamp(dh, dv, inp.limits[:, :, EYES, None])
    gain = gains[:, :, EYES, None] * inp.present[:, None, pair]  # (C, F, 2)
    desired = _pairs(dh, dv, gain).transpose(0, 2, 1, 3)  # (C, 2, F, 2): one row per eye
    final, path = follow(desired.reshape(2 * c_count, frames, 2), np.repeat(inp.smoothing[:, :, EYES], 2, axis=0),
                         np.repeat(inp.max_step[:, :, EYES], 2, axis=0), eyes_state.reshape(2 * c_count, 2))
    eyes_state[:] = final.reshape(c_count, 2, 2)
    out[:, :, pair] = np.where(present[:, :, pair], path.reshape(c_count, 2, frames, 2).transpose(0, 2, 1, 3), 0.0)
    return out, w_pos
