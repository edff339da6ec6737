"""Transition clips played whole: a pack's starts and turns on the spot from standing, and its stops.

The pack builder recognizes what a clip does (:func:`infuse.packs.cycles.transition_kind`); an
infused clip carries it (``BlendClip.transition``). A walk to a point that begins standing plays:

- a **turn on the spot** when the point lies :data:`~.steering.TURN_IN_PLACE` or more off the
  facing: the one whose turn is closest to the point's bearing (if that is closer than not turning),
  the rest of the turn left to the steering; then it decides again, standing;
- else a **start** (standing, then walking): of the starts after which the point lies within
  :data:`START_BEARING` of the facing and at least :data:`START_ROOM_M` beyond where the start hands
  over (and where it is the last point, far enough for the stop the walk would end with), the one
  leaving it nearest straight ahead;
- else nothing: the steering starts the walk from the cycles as without transitions.

On its way to its last point a walk ends with a **stop** where it heads for the point, walks at
about the stop's speed, is at the stop's gait phase where it begins and has about as far to go as
the stop travels (:data:`STOP_BEARING`, :data:`STOP_SPEEDS`, :data:`STOP_SCALES`): the stop's root
travel is turned and scaled so it stands exactly on the point.

A clip plays with its own root motion, turned and moved as a whole (``placement``) so that it starts
where the character stands (its pelvis over the point the steering stands at) and faces. The steering
takes over :data:`HANDOVER_S` before the clip's end, from the clip's state then (where its pelvis is,
its facing at its end, its speed at its end; the gait phase from its last strikes), and the clip
fades into what follows over those last frames. Turns on the spot and stops are played only if they
end standing (slower than :data:`~.controller.STAND_FRACTION` of the slowest walk).

Core frame: metres, seconds, +Y up, +Z forward; angles radians about +Y, + turns left.
"""
from __future__ import annotations

import math

import numpy as np

from infuse import footing

from .steering import SteeringState

#: Seconds before a transition's end at which the steering takes over and the clip starts fading out.
HANDOVER_S = 0.25
#: A start is played when the point lies at most this far (radians) off its facing where it hands over...
START_BEARING = math.radians(15.0)
#: ...and at least this far (metres) beyond that, besides the braking distance at the start's end speed.
START_ROOM_M = 0.6

#: A start eases its travel down to the walk's speed by at most this share.
EASE_MOST = 0.75

#: A stop is played from a frame heading for the path's last point within this (radians)...
STOP_BEARING = math.radians(10.0)
#: ...walking within this ratio of the stop's speed where it begins, and as far from the point as the
#: stop travels to where the steering takes over within this ratio (its ground travel scaled to it).
STOP_SPEEDS = 1.33
STOP_SCALES = 1.25


def played(space, still_m_s: float) -> list:
    """The transition clips of a :class:`~infuse.packs.BlendSpace` that a walk plays: its starts (they
    begin standing), and its turns on the spot and stops that end slower than ``still_m_s`` m/s."""
    return [c for c in space.clips.values() if c.transition == "start"
            or (c.transition in ("turn", "stop") and c.parameters["speed_end"] < still_m_s)]


def handover_s(clip, fps: float) -> float:
    """Seconds into ``clip`` at which the steering takes over (on a frame of ``fps``)."""
    return math.floor(max(clip.duration - HANDOVER_S, 0.0) * fps + 1e-9) / fps


def placement(clip, x: float, z: float, heading: float, speed: float | None = None) -> tuple[float, np.ndarray, np.ndarray, float, float]:
    """How ``clip`` is placed to start at ground point (``x``, ``z``) facing ``heading``: the turn
    (radians) about +Y, the clip's pelvis ground point (2,) (x, z) at its first frame that goes to
    (``x``, ``z``) (2,), the scale of its ground travel (1) and its easing (:func:`eased_travel`): a
    start ending faster than the walk's ``speed`` (m/s) that follows it eases its travel down to that
    speed where it hands over (by :data:`EASE_MOST` at most), so its last steps are the walk's."""
    ease = 1.0
    if clip.transition == "start" and speed is not None and speed < clip.parameters["speed_end"]:
        ease = max(speed / clip.parameters["speed_end"], EASE_MOST)
    return heading - clip.parameters["facing_start"], pelvis_at(clip, np.zeros(1))[0], np.array([x, z]), 1.0, ease


def pelvis_at(clip, t: np.ndarray) -> np.ndarray:
    """(T, 2) the clip's own pelvis ground points (x, z) at its times ``t`` (T,) seconds, interpolated
    (its root joint's where it carries no pelvis path)."""
    m = clip.motion
    f = np.clip(np.asarray(t, dtype=np.float64) * m.fps, 0.0, m.num_frames - 1)
    i = np.minimum(np.floor(f).astype(np.int64), max(m.num_frames - 2, 0))
    u = (f - i)[:, None]
    r = (m.root_translations if clip.pelvis is None else clip.pelvis)[:, [0, 2]]
    return r[i] * (1.0 - u) + r[np.minimum(i + 1, m.num_frames - 1)] * u


def _heading_of(v) -> float:
    return math.atan2(float(v[0]), float(v[1]))


def eased_travel(clip, t: np.ndarray, fps: float) -> np.ndarray:
    """(T, 2) the clip's pelvis ground travel (x, z) to its times ``t`` (T,) seconds, each frame's
    step weighted by how far the clip is toward where the steering takes over (a smoothstep from 0
    at its start to 1 there): a placement's easing ``e`` adds ``(e - 1)`` times it to the travel, so
    the clip's speed comes to ``e`` times its own there, continuously."""
    m = clip.motion
    r = (m.root_translations if clip.pelvis is None else clip.pelvis)[:, [0, 2]]
    mid = (np.arange(max(m.num_frames - 1, 0)) + 0.5) / m.fps
    w = footing.smoothstep(mid / max(handover_s(clip, fps), 1e-9))[:, None]
    cum = np.concatenate((np.zeros((1, 2)), np.cumsum(w * np.diff(r, axis=0), axis=0)))
    f = np.clip(np.asarray(t, dtype=np.float64) * m.fps, 0.0, m.num_frames - 1)
    i = np.minimum(np.floor(f).astype(np.int64), max(m.num_frames - 2, 0))
    u = (f - i)[:, None]
    return cum[i] * (1.0 - u) + cum[np.minimum(i + 1, m.num_frames - 1)] * u


def placed_pelvis(clip, place, t: np.ndarray, fps: float) -> np.ndarray:
    """(T, 2) the clip's own pelvis ground points (x, z) at its times ``t`` (T,) seconds, eased as
    ``place`` says (:func:`eased_travel`), before the placement's scale, turn and move."""
    ease = place[4]
    return pelvis_at(clip, t) if ease == 1.0 else pelvis_at(clip, t) + (ease - 1.0) * eased_travel(clip, t, fps)


def placed_root(clip, place, t: np.ndarray, fps: float) -> np.ndarray:
    """(T, 2) ground points (x, z) of the placed clip's pelvis at its times ``t`` (T,) seconds."""
    turn, root0, at, scale, _ = place
    d = (placed_pelvis(clip, place, t, fps) - root0) * scale
    c, s = math.cos(turn), math.sin(turn)
    return at + np.stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]), axis=-1)


def stop_phase(clip) -> float | None:
    """The gait phase (left strike 0, right strike 0.5) at a stop clip's first frame, from its first two
    strikes (one of each foot); None without them."""
    strikes = strikes_of(clip)
    if len(strikes) < 2 or strikes[0][1] == strikes[1][1] or strikes[1][0] - strikes[0][0] < 1e-3:
        return None
    (t1, foot), (t2, _) = strikes[0], strikes[1]
    return float((0.5 * foot - 0.5 * t1 / (t2 - t1)) % 1.0)


def start_phase(clip, fps: float, half_s: float) -> float:
    """The gait phase (left strike 0, right strike 0.5) where the steering takes over a start ``clip``
    at ``fps``: from its last strike before then and the one of the other foot before it (``half_s``
    seconds apart where there is none)."""
    at = handover_s(clip, fps)
    strikes = [(t, k) for t, k in strikes_of(clip) if t <= at + 1e-9]
    if not strikes:
        return 0.0
    last, foot = strikes[-1]
    other = [t for t, k in strikes if k != foot]
    half = last - other[-1] if other and last - other[-1] > 1e-3 else half_s
    return float((0.5 * foot + 0.5 * (at - last) / half) % 1.0)


def strikes_of(clip) -> list[tuple[float, int]]:
    """(seconds, foot: 0 left, 1 right) of each landing in ``clip``, in time order (its contact flags)."""
    flags = clip.contacts.astype(np.int8)
    return sorted((f / clip.motion.fps, k) for k in range(2) for f in np.flatnonzero(np.diff(flags[:, k]) == 1) + 1)


def stops(clips: list) -> list:
    """The stops among played ``clips`` whose gait phase at their start is known (:func:`stop_phase`)."""
    return [c for c in clips if c.transition == "stop" and stop_phase(c) is not None]


def stop_due(clips: list, st: SteeringState, point, fps: float):
    """The stop among ``clips`` that a walk in state ``st`` (``x``, ``z``, ``heading``, ``speed``) plays to
    stand at ``point`` (x, z) when it goes no farther than the stop travels, heading for the point and
    at about the stop's speed (see :data:`STOP_BEARING`, :data:`STOP_SPEEDS`); None while there is none."""
    bearing, dist = _bearing(st, point)
    if abs(bearing) >= STOP_BEARING:
        return None
    for c in clips:
        if abs(math.log(max(st.speed, 1e-9) / c.parameters["speed_start"])) < math.log(STOP_SPEEDS) and dist <= stop_travel(c, fps):
            return c
    return None


def stop_travel(clip, fps: float) -> float:
    """Metres the pelvis of ``clip`` travels on the ground from its start to where the steering takes over."""
    return float(np.hypot(*(pelvis_at(clip, np.array([handover_s(clip, fps)]))[0] - pelvis_at(clip, np.zeros(1))[0])))


def stop_placement(clip, fps: float, x: float, z: float, target) -> tuple[float, np.ndarray, np.ndarray, float, float]:
    """``clip`` (a stop) placed to start at (``x``, ``z``) with its pelvis where the steering takes over
    at ``target`` (x, z): turned so its travel points there, its ground travel scaled to reach it."""
    root0 = pelvis_at(clip, np.zeros(1))[0]
    travel = pelvis_at(clip, np.array([handover_s(clip, fps)]))[0] - root0
    want = np.asarray(target, dtype=np.float64) - (x, z)
    scale = float(np.hypot(*want) / max(np.hypot(*travel), 1e-9))
    return _heading_of(want) - _heading_of(travel), np.array(root0), np.array([x, z]), scale, 1.0


def end_state(clip, place, fps: float) -> SteeringState:
    """The steering's state where the steering takes over the placed ``clip``: ``x``, ``z`` (its pelvis),
    ``heading`` (its facing at its end), ``speed`` (its speed at its end, m/s; 0 for a turn or a stop)."""
    x, z = placed_root(clip, place, np.array([handover_s(clip, fps)]), fps)[0]
    # A turn or a stop ends standing; a start at its end speed, eased.
    speed = clip.parameters["speed_end"] * place[4] if clip.transition == "start" else 0.0
    return SteeringState(x=float(x), z=float(z), heading=float(place[0] + clip.parameters["facing_end"]), speed=float(speed))


def _bearing(st: SteeringState, point) -> tuple[float, float]:
    """Bearing (radians off the facing, + left) and distance (m) of ``point`` (x, z) from state ``st``."""
    dx, dz = point[0] - st.x, point[1] - st.z
    return (math.atan2(dx, dz) - st.heading + math.pi) % (2.0 * math.pi) - math.pi, math.hypot(dx, dz)


def choose(clips: list, st: SteeringState, path, fps: float, max_decel: float, turn_in_place: float, stay_m: float,
           speed: float | None = None):
    """The transition a walk standing in state ``st`` (``x``, ``z``, ``heading``) plays on its way along
    ``path`` (K, 2) (see the module doc), or None. ``turn_in_place``: radians off the facing from which
    the steering turns on the spot; ``stay_m``: a point this near is where the character stands;
    ``speed``: the speed (m/s) the walk then goes at (a start eases down to it)."""
    if not clips or path is None:
        return None
    k = st.waypoint
    bearing, dist = _bearing(st, path[min(k, len(path) - 1)])
    if dist < stay_m and k >= len(path) - 1:
        return None
    if abs(bearing) >= turn_in_place:
        turns = [c for c in clips if c.transition == "turn"]
        if turns:
            best = min(turns, key=lambda c: abs(c.parameters["turn"] - bearing))
            if abs(best.parameters["turn"] - bearing) < abs(bearing):
                return best
        return None
    best, best_off = None, START_BEARING
    ends = stops(clips)
    for c in clips:
        if c.transition != "start":
            continue
        end = end_state(c, placement(c, st.x, st.z, st.heading, speed), fps)
        off, room = _bearing(end, path[min(k, len(path) - 1)])
        braking = end.speed ** 2 / (2.0 * max_decel)
        # Where the point is the last, room for the stop the walk would end with (begun at its speed).
        if ends and k >= len(path) - 1 and end.speed > 0.0:
            stop = min(ends, key=lambda e: abs(math.log(max(e.parameters["speed_start"], 1e-9) / end.speed)))
            braking = max(braking, stop_travel(stop, fps) / STOP_SCALES - START_ROOM_M)
        if abs(off) <= best_off and room >= START_ROOM_M + braking:
            best, best_off = c, abs(off)
    return best


def grounded(phases: np.ndarray, heights: np.ndarray, heel_m: float, ball_m: float, share: float) -> np.ndarray:
    """A played clip's (F, 2, 2) heel and ball contact flags with each landing moved back to where the
    heel reached the ground (within ``heel_m`` metres of its height at the detected landing) and each
    push off on to where the ball leaves it (risen ``ball_m`` past its height there), at most
    ``share`` of the swing next to it: a detector finds a landing once the foot has slowed down and
    a push off once it has sped up, while a take's feet land and push off moving; pinned over these
    frames too, they do not slide. ``heights`` (F, 2, 2) metres of each foot's ankle and ball."""
    out = np.array(phases, dtype=bool)
    frames = len(out)
    for k in range(2):
        down = out[:, k].any(axis=1).astype(np.int8)
        edges = np.diff(np.concatenate(([0], down, [0])))
        starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]  # contacts [start, end)
        for n, (a, b) in enumerate(zip(starts, ends)):
            if a > 0:  # a landing: back over the swing while the heel is as low as where it landed
                gap = a - (ends[n - 1] if n else 0)
                back = np.nonzero(heights[a - 1::-1, k, 0][:gap] > heights[a, k, 0] + heel_m)[0]
                reach = min(int(back[0]) if back.size else gap, int(share * gap) if n else gap)
                out[a - reach:a, k, 0] = True
            if b < frames:  # a push off: on over the swing while the ball is as low as where it left
                gap = (starts[n + 1] if n + 1 < len(starts) else frames) - b
                on = np.nonzero(heights[b:b + gap, k, 1] > heights[b - 1, k, 1] + ball_m)[0]
                reach = min(int(on[0]) if on.size else gap, int(share * gap) if n + 1 < len(starts) else gap)
                out[b:b + reach, k, 1] = True
    return out
