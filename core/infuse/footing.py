"""Planted feet: where a foot rests while it is down, and the goals that hold it there over frames.

The middle of the foot-contact component: :mod:`infuse.contacts` finds when each foot point (ankle
for the heel, ball of the foot) is down; this module turns those flags into pinning goals; the
two-bone leg IK of :mod:`infuse.runtime.limb_ik` enforces them. Retargeting pins a whole clip at
once (:func:`pinned`: each contact held at one place, the correction gliding between contacts);
locomotion pins block by block as it plays (:func:`anchors` says which point of each foot holds,
:func:`heel_rise` lets the heel rise about a pinned ball where the leg would not reach,
:func:`within_reach` draws a goal beyond reach in toward the hip).

Trajectories here are component-major (3, F) world metres, +Y up, as the retargeter keeps them;
the streaming helpers take frame-major (F, ..., 3) arrays, as the runtime's pose blocks are.
"""
from __future__ import annotations

import numpy as np

from . import quaternions as quat
from .contacts import contact_runs

#: What holds a foot in a frame (:func:`anchors`): nothing (swinging), the ankle (heel down), the
#: ball (heel off, the foot pivoting about its ball).
FREE, ANKLE, BALL = 0, 1, 2
#: Share of the leg's full length (thigh + shin) a pinned ankle may lie from the hip (:func:`heel_rise`,
#: :func:`within_reach`).
REACH = 0.99
#: Share of the leg's full length from which :func:`within_reach` draws a goal toward the hip.
SOFT_REACH = 0.98
#: The heel rises further about the ball (:func:`heel_rise`) only while each step of its rise brings the
#: ankle toward the hip by at least this share of how far the ankle moves: near the closest the ankle's arc
#: about the ball comes to the hip, a hip a millimetre farther would take tens of degrees more rise.
RISE_GAIN = 0.3
#: The heel rises about the ball in 1 degree steps, up to 60 degrees (:func:`heel_rise`).
_RISES = np.radians(np.arange(0.0, 61.0))
_RISE_COS, _RISE_SIN = np.cos(_RISES), np.sin(_RISES)


def smoothstep(x: np.ndarray | float) -> np.ndarray:
    """``3x² - 2x³`` of ``x`` clipped to [0, 1]: 0 and 1 with zero slope at both ends."""
    x = np.minimum(np.maximum(np.asarray(x, dtype=np.float64), 0.0), 1.0)  # a clip, cheaper than np.clip on few values
    out: np.ndarray = x * x * (3.0 - 2.0 * x)
    return out


def _length(v: np.ndarray) -> np.ndarray:
    """Lengths (...) of vectors ``v`` (..., 3), as ``np.linalg.norm(v, axis=-1)`` gives them, for less
    on a block's few frames."""
    out: np.ndarray = np.sqrt((v * v).sum(axis=-1))
    return out


def planted_height(heights: np.ndarray, flags: np.ndarray) -> float:
    """The height (m) a point rests at while planted: the median of ``heights`` (F,) over the
    frames ``flags`` (F,) marks, else (a point that never touches down, a sprinter's heel) their
    5th percentile."""
    return float(np.median(heights[flags]) if flags.any() else np.percentile(heights, 5.0))


def _neighbours(inside: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each frame, the nearest frame at or before / at or after it where ``inside`` (F,) holds
    (-1 / F when there is none)."""
    f = len(inside)
    idx = np.arange(f)
    prev = np.maximum.accumulate(np.where(inside, idx, -1))
    nxt = np.minimum.accumulate(np.where(inside, idx, f)[::-1])[::-1]
    return prev, nxt


def glide(values: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """``values`` (3, F) kept where ``inside`` (F,) holds and smoothstep-interpolated across the gaps
    between such frames (held flat before the first and after the last); zeros if none holds."""
    if not inside.any():
        return np.zeros_like(values)
    prev, nxt = _neighbours(inside)
    f = len(inside)
    lo = np.where(prev >= 0, prev, nxt)
    hi = np.where(nxt < f, nxt, prev)
    w = smoothstep((np.arange(f) - lo) / np.maximum(hi - lo, 1))
    out: np.ndarray = values[:, lo] * (1.0 - w) + values[:, hi] * w
    return out


def weight_near(inside: np.ndarray, frames: float) -> np.ndarray:
    """(F,) 1 where ``inside`` (F,) holds, falling smoothly to 0 ``frames`` frames away from it."""
    if not inside.any():
        return np.zeros(len(inside))
    prev, nxt = _neighbours(inside)
    f = len(inside)
    idx = np.arange(f)
    dist = np.minimum(np.where(prev >= 0, idx - prev, f), np.where(nxt < f, nxt - idx, f)).astype(np.float64)
    return smoothstep(1.0 - dist / max(frames, 1e-9))


def plant_positions(path: np.ndarray, flags: np.ndarray, height: float) -> np.ndarray:
    """(3, F) one held position per contact run of ``flags`` (F,): the mean XZ of ``path`` (3, F)
    over the run, at ``height`` (m); other frames keep ``path``."""
    pins = np.array(path, dtype=np.float64)
    for _, a, b in contact_runs(flags[:, None]):
        pins[[0, 2], a:b] = path[[0, 2], a:b].mean(axis=1, keepdims=True)
        pins[1, a:b] = height
    return pins


def pinned(
    ankle_path: np.ndarray,
    ankle_flags: np.ndarray,
    ankle_height: float,
    ball_path: np.ndarray | None = None,
    ball_flags: np.ndarray | None = None,
    ball_height: float = 0.0,
    foot_length: float = 0.0,
    blend_frames: float = 4.0,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Goals (3, F) for an ankle and (optionally) the ball of the same foot, over a whole clip.

    ``*_path`` (3, F): where each point would go unpinned; ``*_flags`` (F,): its planted frames;
    ``*_height``: world Y at which it rests when planted; ``foot_length``: ankle-to-ball distance.
    Each planted run is held at one position (:func:`plant_positions`); the offset from the path
    glides between runs, so nothing pops. A ball planted while the ankle is too gets a pin exactly
    ``foot_length`` from the ankle's, in the direction the foot points, so both hold at once; while
    only the ball is planted the ankle goal is kept ``foot_length`` from it, with a smooth ramp of
    ``blend_frames`` frames around the ball's contacts. The ball's goal is None without a ball.
    """
    ankle_goal = ankle_path + glide(plant_positions(ankle_path, ankle_flags, ankle_height) - ankle_path, ankle_flags)
    if ball_path is None or ball_flags is None:
        return ankle_goal, None
    ball_pins = plant_positions(ball_path, ball_flags, ball_height)
    drop = ankle_height - ball_height
    across = np.sqrt(max(foot_length * foot_length - drop * drop, 0.0))
    for _, a, b in contact_runs(ball_flags[:, None]):
        both = ankle_flags[a:b]
        if not both.any():
            continue
        k = a + int(np.argmax(both))
        direction = (ball_path[[0, 2], a:b] - ankle_path[[0, 2], a:b])[:, both].mean(axis=1)
        size = np.linalg.norm(direction)
        if size > 1e-9:
            ball_pins[[0, 2], a:b] = (ankle_goal[[0, 2], k] + across * direction / size)[:, None]
    ball_goal = ball_path + glide(ball_pins - ball_path, ball_flags)
    w = weight_near(ball_flags, blend_frames) * ~ankle_flags  # a pinned ankle stays pinned
    away = ankle_goal - ball_goal
    on_sphere = ball_goal + foot_length * away / np.maximum(np.sqrt(np.sum(away * away, axis=0)), 1e-12)
    return ankle_goal * (1.0 - w) + on_sphere * w, ball_goal


def anchors(heel: np.ndarray, ball: np.ndarray, has_ball: np.ndarray, risen: np.ndarray | None = None) -> np.ndarray:
    """(F, K) :data:`FREE`, :data:`ANKLE` or :data:`BALL` per frame and foot, from how much the heel
    and the ball of each foot are down, ``heel`` and ``ball`` (F, K) in [0, 1] (blended contact
    flags): a foot holds while either is more than half down, by its ball where the ball is the
    more down or the pose has lifted its heel (``risen`` (F, K) bool, optional: flags that say only
    that the foot is down, as a standing pose's share of a blend does, cannot tell which point) and
    the foot has one (``has_ball`` (K,) bool), else by its ankle."""
    down = np.maximum(heel, ball) > 0.5
    by_ball = ((ball > heel) if risen is None else (ball > heel) | risen) & np.asarray(has_ball, dtype=bool)
    return np.where(down, np.where(by_ball, BALL, ANKLE), FREE)


def within_reach(goal: np.ndarray, leg: np.ndarray) -> np.ndarray:
    """Ankle goals (F, 3) ``goal`` drawn toward the hip so that none lies farther from it than the
    animated ankle does or :data:`REACH` of the leg's full length, whichever is the farther; ``leg``
    (F, 3, 3) the animated hip, knee and ankle positions.

    Goals nearer than that, or than :data:`SOFT_REACH` of the length, stay; farther ones are brought
    in along the line from the hip, their distance eased toward that bound (a tanh: value and slope
    continuous), so the knee bends at least as much as the animation's or as :data:`REACH` leaves it,
    and never locks straight: a goal pinned beyond reach that comes back within it would bend a
    straight knee by tens of degrees in one frame.
    """
    length = np.maximum(_length(leg[:, 1] - leg[:, 0]) + _length(leg[:, 2] - leg[:, 1]), 1e-12)
    away = goal - leg[:, 0]
    share = _length(away) / length
    start = np.maximum(_length(leg[:, 2] - leg[:, 0]) / length, SOFT_REACH)
    band = np.maximum(REACH - start, 0.0)
    excess = np.maximum(share - start, 0.0)
    eased = start + np.where(band > 1e-9, band * np.tanh(excess / np.maximum(band, 1e-9)), 0.0)
    out: np.ndarray = leg[:, 0] + away * (np.minimum(share, eased) / np.maximum(share, 1e-12))[:, None]
    return out


def heel_rise(ankle_rotation: np.ndarray, leg: np.ndarray, ankle_goal: np.ndarray,
              ball_goal: np.ndarray, across: np.ndarray | None = None,
              on_ball: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Ankle goals (F, 3) for a foot pinned by its ball at ``ball_goal`` (F, 3) with its ankle
    wanted at ``ankle_goal`` (F, 3), and the further heel rise that needs as rotation vectors (F, 3)
    in the foot's frame (zero where the hip reaches).

    Where the hip cannot reach the ankle (farther than :data:`REACH` of the leg's length), the heel
    rises about the ball by the whole degree that minimizes how far the ankle stays beyond reach plus
    :data:`RISE_GAIN` times the length of its arc: the smallest rise that brings it within reach, but
    no more than the rise past which a further degree brings the ankle toward the hip by less than
    :data:`RISE_GAIN` of the arc it travels. The rise so follows the hip continuously, by at most
    1 / (:data:`RISE_GAIN` × ankle-to-ball distance) radians per metre the hip moves, where the nearest
    reach would jump by tens of degrees between two frames as the hip passes the arc's closest point.
    ``ankle_rotation`` (F, 4) is the ankle's global rotation (x, y, z, w), ``leg`` (F, 3, 3) the hip,
    knee and ankle positions. ``across`` ((3,) or (F, 3)): the horizontal axis across the foot to rise
    about (the ball-to-ankle direction x +Y as it lay when the ball took over), with which the heel
    rises no further than the ankle straight above the ball; without it, the axis across the
    ball-to-ankle direction, which turns over with it once the ankle passes over the ball. With
    ``on_ball`` (F,) bool, only those frames' feet are pinned by the ball: the others keep their goals
    (and no rise).
    """
    reach = REACH * (_length(leg[:, 1] - leg[:, 0]) + _length(leg[:, 2] - leg[:, 1]))
    v = ankle_goal - ball_goal
    out, rise = ball_goal + v, np.zeros_like(ankle_goal)
    beyond_reach = _length(out - leg[:, 0]) > reach
    if on_ball is not None:
        out = np.where(on_ball[:, None], out, ankle_goal)
        beyond_reach &= on_ball
    short = np.nonzero(beyond_reach)[0]
    if not short.size:
        return out, rise
    v, ball, hip = v[short], ball_goal[short], leg[short, 0]
    # The horizontal axis across the foot (v x +Y unless given); up = axis x v: v turned 90 degrees toward
    # +Y about the ball; level: v's part along the axis, which the turn keeps.
    ax, az = -v[:, 2], v[:, 0]
    if across is not None:
        across = np.asarray(across, dtype=np.float64)
        given = across[short] if across.shape == ankle_goal.shape else np.broadcast_to(across, ankle_goal.shape)[short]
        usable = np.hypot(given[:, 0], given[:, 2]) > 1e-9
        ax, az = np.where(usable, given[:, 0], ax), np.where(usable, given[:, 2], az)
    size = np.maximum(np.sqrt(ax * ax + az * az), 1e-12)
    ax, az = ax / size, az / size
    axis = np.zeros(v.shape)
    axis[:, 0], axis[:, 2] = ax, az
    up = np.empty(v.shape)
    up[:, 0], up[:, 1], up[:, 2] = -az * v[:, 1], az * v[:, 0] - ax * v[:, 2], ax * v[:, 1]
    level = axis * (ax * v[:, 0] + az * v[:, 2])[:, None]
    flat = v - level
    # Each rise's ankle (F, 3, R), all coordinates at once, and its squared distance from the hip.
    swung, lifted = flat[:, :, None] * _RISE_COS, up[:, :, None] * _RISE_SIN
    far = (((ball + level)[:, :, None] + swung + lifted - hip[:, :, None]) ** 2).sum(axis=1)
    beyond = np.maximum(np.sqrt(far) - reach[short, None], 0.0)
    arc = RISE_GAIN * _length(v)[:, None] * _RISES
    if across is not None:  # no further than the ankle straight above the ball (ahead = axis x +Y)
        turned = swung + lifted
        ahead = (-az[:, None]) * turned[:, 0] + ax[:, None] * turned[:, 2]
        arc = np.where((ahead > 0.0) & (_RISES > 0.0), np.inf, arc)
    pick = np.argmin(beyond + arc, axis=1)
    out[short] = ball + level + flat * _RISE_COS[pick][:, None] + up * _RISE_SIN[pick][:, None]
    rise[short] = quat.rotate(quat.conjugate(ankle_rotation[short]), axis * _RISES[pick][:, None])
    return out, rise
