"""The gaze solver, batched over every gazing character and vectorized over the frames of a block.

Everything is expressed in the chain's *slots* (:data:`~infuse_gaze.model.SLOTS`, pelvis to eyes) and
in their aligned frames (:mod:`infuse.runtime.swing`; a slot the character lacks repeats its parent).
For each character and frame the caller gives, from the pose below the gaze, each slot's aligned
frame and position in the world, where the gaze starts and where the priority joint points.

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
Up the chain it carries one vector per frame, the target seen from the current slot: the chain
above a slot is rigid until its group is solved, so what a slot sees is what its parent sees,
moved into the slot's frame (a rotation and an offset from the pose below, worked out once per
block for all slots, :class:`_Block`) and turned back by the slot's own swing. Positions are only
needed when another character looks at this one's face: that pass also carries the world's origin
and axes, from which a slot's position follows at the end.
Inside a block, vectors and matrices are component-major ((3, C, F), (3, 3, C, F)): each component
is one contiguous array over the characters and frames, so a product over a block is a few calls on
long arrays (numpy's products of stacks of 3 x 3 matrices cost far more per frame). A block of one
frame of a few characters (a live scene's) turns each group on Python floats (:func:`_turn_rows`):
there numpy's fixed cost per call is more than the arithmetic.
"""
from __future__ import annotations

import functools
import math

from dataclasses import dataclass

import numpy as np

from .model import EYE_SLOTS, EYES, SLOT_GROUPS, SLOT_PARENTS, SLOTS

_S = len(SLOTS)
_EYE_SLOTS = list(EYE_SLOTS)
_BELOW_EYES = min(EYE_SLOTS)  # the slots before the eyes: the chain up to the head
_EYE_PAIR = slice(min(EYE_SLOTS), max(EYE_SLOTS) + 1)  # the eyes, side by side, as a view
_FIRST_SLOT = {g: SLOT_GROUPS.index(g) for g in set(SLOT_GROUPS)}
_PARENT_SLOTS = np.maximum(SLOT_PARENTS, 0)  # the pelvis slot stands in for its own parent (the world)
#: The slots a group's turn is worked out from (each group's first, the eyes' aside), and their rows in
#: the arrays of what they see.
_AIMED_SLOTS = sorted(s for g, s in _FIRST_SLOT.items() if g != EYES)
_AIM_ROW = {s: k for k, s in enumerate(_AIMED_SLOTS)}


@dataclass
class SolverInput:
    """Arrays over C characters, F frames, S slots, G groups (angles in radians, lengths in metres).

    - ``frames_world`` (C, F, S, 3, 3), ``positions`` (C, F, S, 3): each slot's aligned frame (a rotation
      matrix, acting on column vectors) and position in the world, in the pose below the gaze;
    - ``origin`` (C, F, 3): where the gaze starts (the eyes, or the head); ``forward`` (C, F, 3): where the
      priority joint points (a unit vector), both in the world and the pose below;
    - ``present`` (C, S) bool; ``counts`` (C, G): joints each group has (eyes: 1, they act side by side);
    - ``targets`` (C, F, 3); ``weights`` (C, F) blend weights;
    - per frame (the gaze in charge may change within a block): ``active`` (C, F, G) bool: groups that
      move; ``fractions`` (C, F, G): share of the remaining turn; ``limits`` (C, F, G, 4): heading, up,
      down, roll; ``smoothing`` (C, F, G): share per frame; ``max_step`` (C, F, G): radians per frame;
      ``offsets`` (C, F, 2): heading and pitch added to the target direction.
    - ``refine``: (c, c2, slots, frames) entries: character c looks at the mean of ``slots`` of
      character c2 on ``frames`` (a slice or an (F,) mask), taken from a first solve of the block;
      ``faces``: the same as :class:`Faces` (made from ``refine`` when None).
    - ``kept``: None, or a dict the solver keeps what it works out of the settings in (the groups'
      limits and smoothing), for the next blocks given the very same settings.
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
    faces: "Faces | None" = None
    kept: dict | None = None


#: ``(R_Y(h) R_X(-p))^T`` row by row (nine entries) from (ch, sh, cp, sp, ch cp, ch sp, sh cp, sh sp) (c: cosine,
#: s: sine): each entry one of them or its negative, or 0 (see :func:`unswing_matrices`).
_UNSWING_TABLE = np.zeros((9, 8))
for _entry, (_source, _sign) in enumerate(((0, 1), (None, 0), (1, -1), (7, -1), (2, 1), (5, -1), (6, 1), (3, 1), (4, 1))):
    if _source is not None:
        _UNSWING_TABLE[_entry, _source] = _sign
_SINE_PHASE = np.array([0.0, 0.5 * np.pi])[None, :, None]  # cos(x - pi/2) = sin(x): both in one call
_HALF_TURN = np.array([np.pi, 0.0])[:, None, None]  # added to (heading, pitch) before the heading's wrap


def unswing_matrices(hv: np.ndarray) -> np.ndarray:
    """Component-major matrices (3, 3, ...) of ``(R_Y(h) R_X(-p))^T``, the inverse of the turn taking +Z
    to (h, p), for (heading, pitch) rows ``hv`` (2, ...) in radians."""
    lead = hv.shape[1:]
    trig = np.cos(hv.reshape(2, 1, -1) - _SINE_PHASE)  # (2, 2, M): (cos, sin) of h, then of p
    products = (trig[0, :, None] * trig[1, None, :]).reshape(4, -1)  # (ch cp, ch sp, sh cp, sh sp)
    # Each entry is one value times 1, -1 or 0: the table product is exact.
    return (_UNSWING_TABLE @ np.concatenate((trig.reshape(4, -1), products))).reshape((3, 3) + lead)


class _Clamp:
    """Scales (heading, pitch) onto the ellipse of ``limits`` (..., 4) (heading, up, down, roll radians)
    when outside it; an axis with a zero limit does not turn at all."""

    def __init__(self, limits: np.ndarray):
        turns = limits[..., :3] > 0
        inverse = np.divide(1.0, limits[..., :3], out=np.zeros(turns.shape), where=turns)  # 0 where locked
        self.inverse = np.ascontiguousarray(np.moveaxis(inverse, -1, 0))  # (3, ...): heading, up, down
        self.locked = not turns.all()
        self.level = bool((self.inverse[1] == self.inverse[2]).all())  # as far up as down

    def __call__(self, hv: np.ndarray) -> None:
        """Clamps (heading, pitch) rows ``hv`` (2, ...) (the limits' shape, or with leading axes) in place."""
        inverse = self.inverse
        vertical = inverse[1] if self.level else np.where(hv[1] >= 0.0, inverse[1], inverse[2])
        hv /= np.maximum(np.hypot(hv[0] * inverse[0], hv[1] * vertical), 1.0)
        if self.locked:
            hv[0] = np.where(inverse[0] > 0, hv[0], 0.0)
            hv[1] = np.where(vertical > 0, hv[1], 0.0)


def follow(desired: np.ndarray, smoothing: np.ndarray, max_step: np.ndarray, state: np.ndarray):
    """Smoothed, speed-limited path (C, F, 2) toward ``desired`` (C, F, 2) from ``state`` (C, 2).

    Each frame covers ``smoothing`` (C, F) of the distance left, at most ``max_step`` (C, F) radians.
    Returns the final state (C, 2) and the path (``desired`` itself when it is followed exactly). See
    :class:`_Smoothing`, which keeps what depends only on the rates for several calls.
    """
    return _Smoothing(smoothing, max_step)(desired, state)


class _Smoothing:
    """:func:`follow` for given ``smoothing`` and ``max_step`` (R, F) rows.

    Without smoothing and with no step above the limit the path is the target. Without the speed
    limit at work and with one share per row the path is a linear filter (:func:`_smoothing_filter`);
    else it is stepped frame by frame, the only loop over frames in the solver (rows at rest with
    nothing to follow stay at rest without it). A block of one frame is one step
    (:meth:`one_frame`).
    """

    def __init__(self, smoothing: np.ndarray, max_step: np.ndarray):
        self.smoothing, self.max_step = smoothing, max_step
        self.share, self.limit = np.ascontiguousarray(smoothing[:, 0]), np.ascontiguousarray(max_step[:, 0])
        self.instant = bool((smoothing >= 1.0).all())
        shares = smoothing[:, 0]
        self.filter = None
        if (smoothing == shares[:, None]).all():
            matrix, powers = _smoothing_filter(tuple(shares.tolist()), smoothing.shape[1])
            self.filter = matrix, powers[..., None]

    def __call__(self, desired: np.ndarray, state: np.ndarray):
        if self.instant and self._within_limit(desired, state):
            return desired[:, -1].copy(), desired
        if self.filter is not None:  # in closed form, equal to the stepped path up to rounding
            matrix, powers = self.filter
            path = matrix @ desired + powers * state[:, None]
            if self._within_limit(path, state):
                return path[:, -1].copy(), path
        rows = np.flatnonzero((desired != 0.0).any(axis=(1, 2)) | (state != 0.0).any(axis=1))
        if rows.size == len(state):
            return _step_frames(desired, self.smoothing, self.max_step, state)
        final, path = state.copy(), np.zeros_like(desired)
        if rows.size:
            final[rows], path[rows] = _step_frames(desired[rows], self.smoothing[rows], self.max_step[rows], state[rows])
        return final, path

    def one_frame(self, desired: np.ndarray, state: np.ndarray) -> np.ndarray:
        """The state (2, R) after one frame toward ``desired`` (2, R) from ``state`` (2, R), as :meth:`__call__`
        steps it (heading and pitch rows; for rows of one frame)."""
        step = (desired - state) * self.share
        step *= self.limit / np.maximum(np.hypot(step[0], step[1]), self.limit)  # 1 within the limit (> 0)
        step += state
        return step

    def _within_limit(self, path: np.ndarray, state: np.ndarray) -> bool:
        """Whether no step of ``path`` (R, F, 2) from ``state`` (R, 2) is longer than the limit."""
        steps = path - np.concatenate((state[:, None], path[:, :-1]), axis=1)
        return bool((np.hypot(steps[..., 0], steps[..., 1]) <= self.max_step).all())


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


def _angles(local: np.ndarray) -> np.ndarray:
    """Heading and pitch rows (2, ...) of component-major vectors (3, ...) given in an aligned frame."""
    x, y, z = local
    hv = np.empty((2,) + x.shape)
    np.arctan2(x, z, out=hv[0])
    np.hypot(x, z, out=hv[1])
    np.arctan2(y, hv[1], out=hv[1])
    return hv


def _wrap_heading(hv: np.ndarray) -> None:
    """Headings ``hv[0]`` given plus pi brought into [-pi, pi), in place."""
    hv[0] %= 2 * np.pi
    hv[0] -= np.pi


def _contiguous(a: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
    """A contiguous copy of ``a`` with its axes in the order ``axes``."""
    return np.ascontiguousarray(a.transpose(axes))


def _follow(smoothing: "_Smoothing", desired: np.ndarray, state: np.ndarray) -> np.ndarray:
    """The path (2, R, F) from ``state`` (R, 2) toward ``desired`` (2, R, F); ``state`` is updated in place."""
    if desired.shape[-1] == 1:
        final = smoothing.one_frame(desired[..., 0], state.T)
        state[:] = final.T
        return final[..., None]
    state[:], path = smoothing(desired.transpose(1, 2, 0), state)
    return path.transpose(2, 0, 1)


class _Group:
    """One joint group over a block, for every character: the share of the turn it takes
    (``fraction`` (C, F)), its limits, its gain (``gain`` (C, F): moves times the blend weight), its
    smoothing and the joints it has (``counts`` (C, 1))."""

    def __init__(self, inp: SolverInput, gains: np.ndarray, g: int):
        self.inp, self.g = inp, g
        self.fraction = inp.fractions[:, :, g]
        self.gain = gains[:, :, g]
        self.clamp, self.smoothing, self.counts = _kept(inp, g, lambda: (
            _Clamp(inp.limits[:, :, g]), _Smoothing(inp.smoothing[:, :, g], inp.max_step[:, :, g]),
            np.maximum(inp.counts[:, g], 1)[:, None].astype(np.float64)))

    def turn(self, hv: np.ndarray, state: np.ndarray) -> np.ndarray:
        """The path (2, C, F) each of the group's joints turns, given the turn left to do ``hv`` (2, C, F)
        from the group's first slot (changed in place); ``state`` (C, 2) (the group's offsets so far) is
        updated in place."""
        hv *= self.fraction
        self.clamp(hv)
        hv *= self.gain
        path = _follow(self.smoothing, hv, state)
        path /= self.counts
        return path

    def turn_one_frame(self, local: np.ndarray, aim: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`turn` of a block of one frame from the target seen from the group's first slot, less
        where the gaze starts, ``local`` (3, C), and ``aim`` (2, C) (see :class:`_Block`), on Python
        floats (:func:`_turn_rows`); also returns the unswing matrices (3, 3, C, 1) of the path."""
        settings = _kept(self.inp, (self.g, "one frame"), lambda: list(zip(*(
            a.tolist() for a in (self.fraction[:, 0], *self.clamp.inverse[..., 0], self.smoothing.share, self.smoothing.limit,
                                 self.counts[:, 0])))))
        return _turn_rows(local, aim, self.gain[:, 0], settings, state)


#: Up to this many characters a block of one frame turns each group on Python floats
#: (:func:`_turn_rows`): numpy's fixed cost per call on arrays of a few values is then more than the
#: arithmetic.
SCALAR_TURN_MAX_CHARACTERS = 16


def _turn_rows(local, aim, gain, settings: list, state) -> tuple[np.ndarray, np.ndarray]:
    """One frame of a group's turn over R rows, one Python float at a time (the arithmetic of
    :func:`_angles`, :class:`_Clamp`, :meth:`_Smoothing.one_frame`): the target less the origin
    ``local`` (3, R) in the group's aligned frame, ``aim`` (2, R), ``gain`` (R,) and ``settings``, one
    tuple per row: the share of the turn, the clamp's inverse limits (heading, up, down), the
    smoothing's share and limit per frame, the joints. ``state`` (R, 2) is updated in place. Returns
    the path (2, R, 1) and its unswing matrices (3, 3, R, 1) (views of one array made at the end)."""
    atan2, hypot, cos, sin = math.atan2, math.hypot, math.cos, math.sin
    turn, half = 2.0 * math.pi, math.pi
    rows = len(state)
    xs, ys, zs = local.tolist()
    aim_h, aim_v = aim.tolist()
    values: list[float] = []  # per row: the state (2), the path (2), the unswing matrix (9)
    put = values.extend
    for x, y, z, ah, av, g, (f, across, up, down, share, limit, count), (x0, y0) in zip(
            xs, ys, zs, aim_h, aim_v, gain.tolist(), settings, state.tolist()):
        h = ((atan2(x, z) + ah) % turn - half) * f
        v = (atan2(y, hypot(x, z)) + av) * f
        upward = up if v >= 0.0 else down
        ellipse = hypot(h * across, v * upward)
        if ellipse > 1.0:
            h /= ellipse
            v /= ellipse
        if across == 0.0:
            h = 0.0
        if upward == 0.0:
            v = 0.0
        h *= g
        v *= g
        dx, dy = (h - x0) * share, (v - y0) * share
        step = hypot(dx, dy)
        k = limit / step if step > limit else 1.0  # limit / max(step, limit) (limit > 0)
        x0, y0 = dx * k + x0, dy * k + y0
        h, v = x0 / count, y0 / count
        ch, sh, cp, sp = cos(h), sin(h), cos(v), sin(v)
        put((x0, y0, h, v, ch, 0.0, -sh, -sh * sp, cp, -ch * sp, sh * cp, sp, ch * cp))
    table = np.fromiter(values, np.float64, 13 * rows).reshape(rows, 13)
    state[:] = table[:, :2]
    return table[:, 2:4].T[..., None], table[:, 4:].T.reshape(3, 3, rows, 1)


def _kept(inp: SolverInput, key, make):
    """``make()``, kept in ``inp.kept`` under ``key`` when the caller keeps the settings' products."""
    if inp.kept is None:
        return make()
    if key not in inp.kept:
        inp.kept[key] = make()
    return inp.kept[key]


class _Block:
    """What both passes of a block share, from the pose below, component-major, for all slots at once
    (S, then components, then C, F):

    - ``frames`` (S, 3, 3, C, F), ``positions`` (S, 3, C, F): each slot's aligned frame and position in
      the world;
    - ``to_slot`` (S, 3, 3, C, F): matrices taking a vector from the parent slot's aligned frame into
      the slot's; ``lift`` (S, 3, C, F): the parent slot's position seen from the slot, negated (the
      slot's position from its parent's, in the slot's aligned frame);
    - ``origin`` (A, 3, C, F): where the gaze starts, seen from the aligned frame of each slot a group's
      turn is worked out from (:data:`_AIMED_SLOTS`, row :data:`_AIM_ROW`);
    - ``aim`` (A, 2, C, F): heading (plus pi, for the wrap) and pitch of the fixed offsets minus those
      of where the priority joint points, seen from those slots: added to the target's angles, the
      turn left; ``eyes_aim`` (2, C, F): the offsets' alone (heading plus pi), for the eyes;
    - the groups' and eyes' settings, made when first asked.
    """

    def __init__(self, inp: SolverInput):
        self.inp = inp
        frames = _contiguous(inp.frames_world, (2, 3, 4, 0, 1))
        positions = _contiguous(inp.positions, (2, 3, 0, 1))
        self.frames, self.positions = frames, positions
        self.to_slot = np.einsum("sjicf,sjkcf->sikcf", frames, frames[_PARENT_SLOTS])
        self.lift = np.einsum("sjicf,sjcf->sicf", frames, positions - positions[_PARENT_SLOTS])
        aimed = frames[_AIMED_SLOTS]
        self.origin = np.einsum("sjicf,sjcf->sicf", aimed, _contiguous(inp.origin, (2, 0, 1)) - positions[_AIMED_SLOTS])
        forward = _angles(np.einsum("sjicf,jcf->iscf", aimed, _contiguous(inp.forward, (2, 0, 1))))
        self.eyes_aim = inp.offsets.transpose(2, 0, 1) + _HALF_TURN  # (2, C, F)
        self.aim = _contiguous(self.eyes_aim[:, None] - forward, (1, 0, 2, 3))
        self.gains = inp.active * inp.weights[..., None]  # (C, F, G)
        self.turned = np.any(self.gains != 0.0, axis=(0, 1))  # (G,) the groups some character turns
        self.present, self.everyone, self.absent = _kept(inp, "present", lambda: (
            np.ascontiguousarray(inp.present.T[:, :, None]),  # (S, C, 1)
            np.all(inp.present, axis=0).tolist(),  # slots every character has
            (~np.any(inp.present, axis=0)).tolist()))  # slots no character has: they repeat their parent
        self._groups: dict[int, _Group] = {}
        self._eyes = None

    def group(self, g: int) -> _Group:
        if g not in self._groups:
            self._groups[g] = _Group(self.inp, self.gains, g)
        return self._groups[g]

    def eyes(self):
        """The eyes' clamp, gain (2, C, F) and smoothing over 2 C rows (one per eye, eye-major)."""
        if self._eyes is None:
            inp = self.inp
            clamp, smoothing = _kept(inp, "eyes", lambda: (
                _Clamp(inp.limits[:, :, EYES]),
                _Smoothing(np.tile(inp.smoothing[:, :, EYES], (2, 1)), np.tile(inp.max_step[:, :, EYES], (2, 1)))))
            self._eyes = (clamp, self.gains[:, :, EYES] * self.present[_EYE_PAIR], smoothing)
        return self._eyes

    def start(self, s: int, target: np.ndarray, place: bool) -> np.ndarray:
        """What the walk up the chain carries, from slot ``s`` as the pose below has it: the target (3, C, F)
        seen from the slot's aligned frame, as (3, 1, C, F); with ``place`` also the world's origin and
        axes, as (3, 5, C, F) (the points first: see :func:`_solve_once`)."""
        if not place:
            return np.einsum("jicf,jcf->icf", self.frames[s], target - self.positions[s])[:, None]
        world = np.zeros((3, 5) + target.shape[1:])
        world[:, 0] = target
        world[:, :2] -= self.positions[s][:, None]
        world[:, 2:] = np.eye(3)[:, :, None, None]
        return np.einsum("jicf,jkcf->ikcf", self.frames[s], world)

    def placed(self, s: int, carried: np.ndarray) -> np.ndarray:
        """Slot ``s``'s position (3, C, F) in the world, given what the walk carried (3, 5, C, F) past its
        parent slot (as turned): the slot's offset in the parent's aligned frame, taken back to the world."""
        parent = SLOT_PARENTS[s]
        offset = np.einsum("jicf,jcf->icf", self.frames[parent], self.positions[s] - self.positions[parent])
        return np.einsum("ikcf,icf->kcf", carried[:, 2:], offset - carried[:, 1])


def solve(inp: SolverInput, groups_state: np.ndarray, eyes_state: np.ndarray, first_state: np.ndarray | None = None):
    """Run the block; returns the offsets (C, F, S, 2).

    ``groups_state`` (C, G, 2) and ``eyes_state`` (C, 2, 2) hold the current offsets and are updated
    in place. Characters looking at another one's eyes or head (``refine``) get a second pass with
    that character's solved positions. The first pass smooths its own way: ``first_state`` (C, G, 2)
    holds its offsets from block to block (updated in place, and equal to ``groups_state`` after a
    block without a first pass), so that where blocks begin does not change the result; None starts
    it from ``groups_state``.
    """
    block = _Block(inp)
    target = _contiguous(inp.targets, (2, 0, 1))  # (3, C, F)
    if not inp.refine:
        offsets, _ = _solve_once(inp, block, target, groups_state, eyes_state)
        if first_state is not None:
            first_state[:] = groups_state
        return offsets
    # The first pass only places the chains (no joint's position depends on the eyes' turn).
    first = groups_state.copy() if first_state is None else first_state
    faces = Faces(inp.refine) if inp.faces is None else inp.faces
    _, placed = _solve_once(inp, block, target, first, eyes_state, eyes=False, place=faces.slots)
    positions = inp.positions.copy()
    for s, position in placed.items():
        positions[:, :, s] = position.transpose(1, 2, 0)
    targets = inp.targets.copy()
    faces.place(targets, positions)
    return _solve_once(inp, block, _contiguous(targets, (2, 0, 1)), groups_state, eyes_state)[0]


class Faces:
    """Characters looking at others' faces: ``refine``'s (c, c2, slots, frames) entries (see
    :class:`SolverInput`), prepared once for :meth:`place`; ``slots``: every slot looked at."""

    def __init__(self, refine):
        self.slots = sorted({s for _, _, faced, _ in refine for s in faced})
        whole: dict[tuple, tuple[list, list]] = {}
        self.partial = []  # (c, c2, slots, frames) of the entries on some frames only
        for c, other, slots, these in refine:
            if isinstance(these, slice) and these == slice(None):
                gazers, others = whole.setdefault(slots, ([], []))
                gazers.append(c)
                others.append(other)
            else:
                self.partial.append((c, other, list(slots), these))
        #: Per set of slots looked at over the whole block: the gazing characters (n,), those they
        #: look at (n, 1) and the slots.
        self.whole = [(np.array(gazers), np.array(others)[:, None], list(slots)) for slots, (gazers, others) in whole.items()]

    def place(self, targets: np.ndarray, positions: np.ndarray) -> None:
        """Write into ``targets`` (C, F, 3) the mean of the ``slots`` of character ``c2``'s chain
        ``positions`` (C, F, S, 3) for each entry: at once for the whole block's entries with the same
        slots."""
        for c, other, slots, these in self.partial:
            targets[c, these] = positions[other][these][:, slots].mean(axis=1)
        for gazers, others, slots in self.whole:
            picked = positions[others, :, slots]  # (n, k, F, 3)
            targets[gazers] = picked[:, 0] if len(slots) == 1 else np.add.reduce(picked, axis=1) / len(slots)


def _solve_once(inp: SolverInput, block: _Block, target: np.ndarray, groups_state: np.ndarray, eyes_state: np.ndarray,
                eyes: bool = True, place=()):
    """Groups bottom-up, each over all frames at once: a group's wish at a frame depends only on the
    groups below it at that frame, so only the smoothing runs frame by frame (:func:`follow`). A group
    no character turns (and none is on its way back) is skipped: its joints stay as they are. Without
    ``eyes`` the eyes keep still (their offsets are 0 and their state is left as it was).

    Up the chain the walk carries the target ``target`` (3, C, F) seen from the current slot; to place
    the slots ``place`` (slot indices) in the world it also carries the world's origin and axes (points
    move with the slots' offsets, axes only turn), from which each slot's position follows. Returns the
    offsets (C, F, S, 2) (None without ``eyes``: such a pass only places) and {slot: position (3, C, F) in the
    world} of the slots ``place``.
    """
    c_count, frames = target.shape[1:]
    scalar = frames == 1 and c_count <= SCALAR_TURN_MAX_CHARACTERS
    out = np.zeros((_S, 2, c_count, frames)) if eyes else None  # component-major, each slot's rows one copy
    turning = (block.turned | np.any(groups_state != 0.0, axis=(0, 2))).tolist()
    points = 2 if place else 1  # the carried columns that are points
    carried = None  # (3, K, C, F): what the walk carries, seen from the last slot's aligned frame as turned; None until a slot turns
    past: dict[int, np.ndarray] = {}  # with ``place``: what it carried past each slot
    share = unturn = None  # the current group's turn (2, C, F) and its unswing matrices, when every character shares them
    for s in range(_BELOW_EYES):
        g = SLOT_GROUPS[s]
        first = _FIRST_SLOT[g] == s
        if carried is None:
            if not (turning[g] and first):
                continue  # the chain stands as in the pose below
            view = block.start(s, target, bool(place))
        elif block.absent[s]:
            view = carried  # the slot is its parent
        else:
            view = np.einsum("ijcf,jkcf->ikcf", block.to_slot[s], carried)
            view[:, :points] -= block.lift[s][:, None]
        if turning[g] and first:
            row = _AIM_ROW[s]
            if scalar:
                share, unturn = block.group(g).turn_one_frame(view[:, 0, :, 0] - block.origin[row, :, :, 0],
                                                              block.aim[row, :, :, 0], groups_state[:, g])
            else:
                hv = _angles(view[:, 0] - block.origin[row])
                hv += block.aim[row]
                _wrap_heading(hv)
                share, unturn = block.group(g).turn(hv, groups_state[:, g]), None
        if turning[g] and not block.absent[s]:
            assert share is not None  # set at the group's first slot, which comes before the others
            if block.everyone[s]:  # the group's slots share one turn
                unturn = unswing_matrices(share) if unturn is None else unturn
                hv, turn = share, unturn
            else:
                hv = share * block.present[s]
                turn = unswing_matrices(hv)
            if out is not None:
                out[s] = hv
            view = np.einsum("ijcf,jkcf->ikcf", turn, view)
        carried = past[s] = view
    placed = {s: block.placed(s, past[SLOT_PARENTS[s]]) if SLOT_PARENTS[s] in past else block.positions[s] for s in place}
    if out is None:
        return out, placed
    if not (inp.present[:, _EYE_SLOTS].any() or eyes_state.any()):
        return out.transpose(2, 3, 0, 1), placed
    # The eyes, side by side: each turns from its own position, all the way (within its limits).
    pair = _EYE_PAIR
    if carried is None:
        view = np.einsum("ejicf,ejcf->iecf", block.frames[pair], target - block.positions[pair])
    else:
        view = np.einsum("eijcf,jcf->iecf", block.to_slot[pair], carried[:, 0]) - block.lift[pair].swapaxes(0, 1)
    hv = _angles(view)  # (2, 2, C, F): heading and pitch, one row per eye
    hv += block.eyes_aim[:, None]
    _wrap_heading(hv)
    clamp, gain, smoothing = block.eyes()
    clamp(hv)
    hv *= gain
    state = np.ascontiguousarray(eyes_state.transpose(1, 0, 2)).reshape(2 * c_count, 2)  # eye-major rows
    path = _follow(smoothing, hv.reshape(2, 2 * c_count, frames), state)
    eyes_state[:] = state.reshape(2, c_count, 2).transpose(1, 0, 2)
    path = path.reshape(2, 2, c_count, frames) * block.present[pair]
    out[pair] = path.transpose(1, 0, 2, 3)
    return out.transpose(2, 3, 0, 1), placed
