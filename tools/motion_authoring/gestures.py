"""Procedural conversational gestures on the canonical skeleton, standing.

A gesture is a few key poses of the hand at its phases (ready, stroke_start, stroke, stroke_end,
relax), between the standing pose at its start and end. A key pose gives the wrist's place relative
to the shoulder (metres; +X out toward the hand's side, +Y up, +Z forward), the hand's orientation
(finger direction and palm normal), a finger shape and how far the shoulder is raised. The wrist
moves between keys with quintic easing (at rest at each key), plus an optional oscillation over the
stroke phase (a wave, a rolling cycle); the arm is solved by two-bone IK, the forearm takes the
hand's twist about the forearm. Specs are written for the left hand; the right hand mirrors them.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.motion import Motion

from .body import Y, Z, Body, frame_rotation, rot, smooth, two_bone
from .gait import FPS

PHASES = ("ready", "stroke_start", "stroke", "stroke_end", "relax")
FINGERS = ("index", "middle", "ring", "pinky")
#: Hand orientations in left-hand coordinates: (finger direction, palm normal).
PALMS = {
    "in": ((-0.15, 0.0, 1.0), (-1.0, 0.0, 0.0)),     # fingers forward, palm toward the midline (thumb up)
    "up": ((-0.25, 0.0, 1.0), (0.0, 1.0, 0.0)),      # offered, palm up
    "down": ((-0.15, 0.0, 1.0), (0.0, -1.0, 0.0)),
    "out": ((0.0, 1.0, 0.15), (0.0, 0.0, 1.0)),      # fingers up, palm to the listener
    "self": ((-1.0, 0.0, -0.6), (0.0, -1.0, 0.0)),   # fingers toward one's own chest
    "chin": ((-0.25, 1.0, 0.1), (0.0, 0.0, -1.0)),   # knuckles up, palm toward the body
    "fist": ((-1.0, 0.0, 0.35), (0.0, 0.0, -1.0)),   # fingers across the body, thumb up
    "back": ((0.15, 0.45, -1.0), (-1.0, 0.0, 0.0)),  # fingers back over the shoulder, palm toward the head
    "ahead": ((0.0, -0.1, 1.0), (0.0, -1.0, -0.1)),  # fingers forward, palm down
    "floor": ((-0.1, -0.8, 0.6), (0.0, -0.6, -0.8)),  # fingers down and forward, palm toward the body
    "belly": ((-1.0, -0.1, 0.15), (0.0, 0.0, -1.0)),  # fingers across the belly, palm on it
}
#: Finger shapes: curl (radians per joint) of index, middle, ring, pinky, and the thumb's bend.
SHAPES = {
    "relaxed": (0.3, 0.38, 0.45, 0.52, 0.15),
    "open": (0.06, 0.06, 0.08, 0.1, 0.0),
    "point": (0.05, 1.45, 1.45, 1.4, 0.7),
    "fist": (1.35, 1.45, 1.45, 1.4, 0.7),
    "thumb": (1.35, 1.45, 1.45, 1.4, -0.35),
    "think": (0.8, 1.25, 1.35, 1.35, 0.3),
    "two": (0.05, 0.05, 1.45, 1.4, 0.7),
    "three": (0.05, 0.05, 0.08, 1.4, 0.7),
    "four": (0.05, 0.05, 0.08, 0.1, 0.7),
    "five": (0.05, 0.05, 0.08, 0.1, -0.2),
    "pinch": (0.6, 1.3, 1.4, 1.4, 0.3),
}


@dataclass(frozen=True)
class Key:
    """One key pose of a hand: ``wrist`` (3,) metres from the shoulder, a :data:`PALMS` orientation,
    a :data:`SHAPES` finger shape and ``shrug`` radians of shoulder elevation."""

    wrist: tuple
    palm: str = "in"
    shape: str = "relaxed"
    shrug: float = 0.0


@dataclass(frozen=True)
class GestureSpec:
    """A gesture: ``times`` of its phases and ``end`` (seconds), ``keys`` per phase (``relax`` defaults to
    ``stroke_end``), optional ``extra`` keys (seconds, Key) between them, an ``oscillation`` over
    [stroke_start, stroke_end] ((3,) amplitude metres, Hz, (3,) second axis at a quarter period or None),
    the BML ``lexemes`` it realizes, its ``hands``, for two hands that differ, the right hand's keys
    (``right``, in the right hand's own mirrored coordinates), and ``strokes``: the finger shapes of the
    second, third… repeated stroke when they differ from the first (a count), each a clip of its own."""

    name: str
    times: dict
    end: float
    keys: dict
    lexemes: tuple = ()
    extra: tuple = ()
    oscillation: tuple | None = None
    hands: tuple = ("left", "right", "both")
    right: dict = field(default_factory=dict)
    strokes: tuple = ()


def _beat(name: str, size: float, lexemes: tuple) -> GestureSpec:
    ready = Key((-0.03, -0.30, 0.27), "in", "relaxed")
    up = Key((-0.03, -0.30 + 0.5 * size, 0.27 + 0.15 * size), "in", "relaxed")
    down = Key((-0.02, -0.30 - 0.5 * size, 0.29 + 0.1 * size), "in", "relaxed")
    slow = 0.08 * size / 0.14
    return GestureSpec(name, {"ready": 0.32, "stroke_start": 0.4 + slow, "stroke": 0.5 + slow, "stroke_end": 0.64 + slow,
                              "relax": 0.8 + slow}, 1.25 + slow,
                       {"ready": ready, "stroke_start": up, "stroke": down, "stroke_end": ready}, lexemes)


#: The gestures of the pack. BML 1.0 gives no gesture lexicon of its own; the lexemes are the names used
#: by BML realizers and corpora for the same movements.
SPECS = (
    _beat("beat_small", 0.04, ("BEAT_SMALL", "SMALL_BEAT")),
    _beat("beat_medium", 0.08, ("BEAT", "BEAT_MEDIUM", "BEAT_LOW", "BEAT_MID", "STROKE")),
    _beat("beat_large", 0.14, ("BEAT_LARGE", "BEAT_HIGH", "BIG_BEAT", "EMPHASIS")),
    GestureSpec("offer", {"ready": 0.4, "stroke_start": 0.45, "stroke": 0.68, "stroke_end": 0.9, "relax": 1.1}, 1.6,
                {"ready": Key((-0.02, -0.32, 0.22), "in"), "stroke_start": Key((-0.02, -0.32, 0.24), "in"),
                 "stroke": Key((0.06, -0.30, 0.38), "up", "open"), "stroke_end": Key((0.06, -0.30, 0.37), "up", "open")},
                ("OFFER", "PALM_UP", "GIVE", "YOU", "PRESENT", "PALMUP", "OPENHANDS", "OPEN_HANDS", "CONDUIT", "METAPHORIC",
                 "ASK", "SUGGEST", "INFORM", "SPREAD", "EXPLAIN")),
    GestureSpec("reject", {"ready": 0.38, "stroke_start": 0.42, "stroke": 0.6, "stroke_end": 0.85, "relax": 1.05}, 1.55,
                {"ready": Key((-0.02, -0.28, 0.22), "in"), "stroke_start": Key((-0.02, -0.24, 0.24), "out", "open"),
                 "stroke": Key((0.0, -0.10, 0.38), "out", "open"), "stroke_end": Key((0.0, -0.10, 0.36), "out", "open")},
                ("REJECT", "PALM_OUT", "STOP", "NO", "NEGATION", "REFUSE", "HALT")),
    GestureSpec("shrug", {"ready": 0.35, "stroke_start": 0.4, "stroke": 0.6, "stroke_end": 0.9, "relax": 1.05}, 1.6,
                {"ready": Key((0.04, -0.36, 0.18), "in"), "stroke_start": Key((0.06, -0.35, 0.2), "up", "open", 0.05),
                 "stroke": Key((0.16, -0.32, 0.22), "up", "open", 0.26), "stroke_end": Key((0.16, -0.33, 0.22), "up", "open", 0.22)},
                ("SHRUG", "DONT_KNOW", "UNCERTAIN", "WHATEVER")),
    GestureSpec("count", {"ready": 0.38, "stroke_start": 0.44, "stroke": 0.58, "stroke_end": 0.85, "relax": 1.0}, 1.5,
                {"ready": Key((-0.02, -0.26, 0.24), "in", "point"), "stroke_start": Key((-0.03, -0.2, 0.26), "out", "point"),
                 "stroke": Key((-0.04, -0.12, 0.3), "out", "point"), "stroke_end": Key((-0.04, -0.13, 0.3), "out", "point")},
                ("COUNT", "ONE", "ENUMERATE", "FIRST", "LIST", "INDEX"), strokes=("two", "three", "four", "five")),
    GestureSpec("wave", {"ready": 0.45, "stroke_start": 0.55, "stroke": 0.65, "stroke_end": 1.55, "relax": 1.65}, 2.2,
                {"ready": Key((0.08, -0.05, 0.16), "out", "open"), "stroke_start": Key((0.1, 0.02, 0.16), "out", "open"),
                 "stroke": Key((0.1, 0.02, 0.16), "out", "open"), "stroke_end": Key((0.1, 0.02, 0.16), "out", "open")},
                ("WAVE", "GREET", "GREETING", "HELLO", "BYE", "GOODBYE", "WAVE_HAND"),
                oscillation=((0.07, 0.0, 0.0), 2.5, None)),
    GestureSpec("this_big", {"ready": 0.4, "stroke_start": 0.45, "stroke": 0.7, "stroke_end": 1.0, "relax": 1.15}, 1.7,
                {"ready": Key((-0.08, -0.32, 0.25), "in", "open"), "stroke_start": Key((-0.06, -0.32, 0.26), "in", "open"),
                 "stroke": Key((0.24, -0.30, 0.26), "in", "open"), "stroke_end": Key((0.24, -0.30, 0.26), "in", "open")},
                ("THIS_BIG", "BIG", "SIZE", "LARGE", "WIDE", "EXPANSE", "ICONIC_SIZE")),
    GestureSpec("cycle", {"ready": 0.4, "stroke_start": 0.45, "stroke": 0.62, "stroke_end": 1.35, "relax": 1.45}, 1.95,
                {"ready": Key((-0.02, -0.30, 0.26), "in"), "stroke_start": Key((-0.02, -0.30, 0.26), "in"),
                 "stroke": Key((-0.02, -0.30, 0.26), "in"), "stroke_end": Key((-0.02, -0.30, 0.26), "in")},
                ("CYCLE", "ROLL", "CONTINUE", "AND_SO_ON", "ITERATE", "PROCESS"),
                oscillation=((0.0, 0.06, 0.0), 1.4, (0.0, 0.0, 0.06))),
    GestureSpec("contrast", {"ready": 0.4, "stroke_start": 0.5, "stroke": 0.9, "stroke_end": 1.05, "relax": 1.2}, 1.75,
                {"ready": Key((-0.04, -0.32, 0.24), "in"), "stroke_start": Key((-0.14, -0.3, 0.3), "up", "open"),
                 "stroke": Key((0.16, -0.3, 0.3), "up", "open"), "stroke_end": Key((0.16, -0.3, 0.29), "up", "open")},
                ("CONTRAST", "ON_THE_OTHER_HAND", "COMPARE", "WEIGH", "BALANCE", "EITHER_OR"),
                # Two hands: the left presents one side at stroke_start, the right the other at the stroke.
                right={"ready": Key((-0.04, -0.34, 0.22), "in"), "stroke_start": Key((-0.02, -0.36, 0.22), "in"),
                       "stroke": Key((0.14, -0.3, 0.3), "up", "open"), "stroke_end": Key((0.14, -0.3, 0.3), "up", "open")}),
    GestureSpec("self_point", {"ready": 0.38, "stroke_start": 0.42, "stroke": 0.6, "stroke_end": 0.9, "relax": 1.05}, 1.55,
                {"ready": Key((-0.04, -0.3, 0.24), "in", "point"), "stroke_start": Key((-0.06, -0.27, 0.24), "self", "point"),
                 "stroke": Key((-0.08, -0.22, 0.19), "self", "point"), "stroke_end": Key((-0.08, -0.22, 0.2), "self", "point")},
                ("SELF", "ME", "I", "MYSELF", "SELF_POINT", "POINT_SELF", "MINE")),
    GestureSpec("chin_touch", {"ready": 0.5, "stroke_start": 0.6, "stroke": 0.8, "stroke_end": 2.0, "relax": 2.15}, 2.8,
                {"ready": Key((-0.08, -0.25, 0.22), "chin", "think"), "stroke_start": Key((-0.12, -0.1, 0.16), "chin", "think"),
                 "stroke": Key((-0.15, -0.03, 0.13), "chin", "think"), "stroke_end": Key((-0.15, -0.03, 0.13), "chin", "think")},
                ("THINK", "THINKING", "CHIN", "CHIN_TOUCH", "PONDER", "CONSIDER", "HMM"), hands=("left", "right")),
    GestureSpec("thumbs_up", {"ready": 0.38, "stroke_start": 0.45, "stroke": 0.6, "stroke_end": 0.95, "relax": 1.1}, 1.6,
                {"ready": Key((-0.02, -0.3, 0.24), "fist", "fist"), "stroke_start": Key((-0.03, -0.24, 0.27), "fist", "thumb"),
                 "stroke": Key((-0.04, -0.18, 0.3), "fist", "thumb"), "stroke_end": Key((-0.04, -0.18, 0.3), "fist", "thumb")},
                ("THUMBS_UP", "THUMBSUP", "OK", "GOOD", "APPROVE", "YES_GESTURE", "LIKE")),
    # Time on a line from behind (the past) to ahead (the future), the speaker at now.
    GestureSpec("past", {"ready": 0.4, "stroke_start": 0.48, "stroke": 0.72, "stroke_end": 0.95, "relax": 1.1}, 1.65,
                {"ready": Key((0.0, -0.28, 0.2), "in"), "stroke_start": Key((0.04, -0.2, 0.2), "in", "open"),
                 "stroke": Key((0.1, -0.05, 0.02), "back", "open"), "stroke_end": Key((0.1, -0.06, 0.03), "back", "open")},
                ("PAST", "BEFORE", "AGO", "EARLIER", "PREVIOUS", "YESTERDAY", "FORMERLY")),
    GestureSpec("future", {"ready": 0.4, "stroke_start": 0.46, "stroke": 0.7, "stroke_end": 0.95, "relax": 1.1}, 1.65,
                {"ready": Key((-0.02, -0.3, 0.22), "in"), "stroke_start": Key((-0.02, -0.29, 0.26), "ahead", "open"),
                 "stroke": Key((0.02, -0.2, 0.44), "ahead", "open"), "stroke_end": Key((0.02, -0.2, 0.43), "ahead", "open")},
                ("FUTURE", "LATER", "AHEAD", "TOMORROW", "SOON", "AFTERWARDS", "NEXT")),
    GestureSpec("here", {"ready": 0.38, "stroke_start": 0.44, "stroke": 0.6, "stroke_end": 0.85, "relax": 1.0}, 1.5,
                {"ready": Key((-0.02, -0.3, 0.24), "in", "point"), "stroke_start": Key((-0.03, -0.22, 0.3), "floor", "point"),
                 "stroke": Key((-0.03, -0.33, 0.33), "floor", "point"), "stroke_end": Key((-0.03, -0.32, 0.33), "floor", "point")},
                ("HERE", "NOW", "RIGHT_HERE", "THIS_PLACE", "TODAY", "DEICTIC_HERE")),
    GestureSpec("tiny", {"ready": 0.38, "stroke_start": 0.46, "stroke": 0.62, "stroke_end": 0.95, "relax": 1.1}, 1.6,
                {"ready": Key((-0.03, -0.28, 0.24), "in"), "stroke_start": Key((-0.05, -0.2, 0.28), "in", "pinch"),
                 "stroke": Key((-0.06, -0.16, 0.3), "in", "pinch"), "stroke_end": Key((-0.06, -0.16, 0.3), "in", "pinch")},
                ("TINY", "LITTLE", "A_LITTLE", "A_BIT", "PINCH", "PRECISE", "FEW", "MINOR")),
    GestureSpec("belly", {"ready": 0.42, "stroke_start": 0.55, "stroke": 0.7, "stroke_end": 1.3, "relax": 1.45}, 2.0,
                {"ready": Key((-0.03, -0.36, 0.2), "in"), "stroke_start": Key((-0.07, -0.39, 0.2), "belly", "open"),
                 "stroke": Key((-0.08, -0.4, 0.17), "belly", "open"), "stroke_end": Key((-0.08, -0.4, 0.17), "belly", "open")},
                ("BELLY", "STOMACH", "GUT", "TUMMY", "GUT_FEELING"), hands=("left", "right")),
)


def _mirror(v) -> np.ndarray:
    """Left-hand coordinates to the right hand's (x flipped); works on (..., 3)."""
    return np.asarray(v, dtype=np.float64) * np.array([-1.0, 1.0, 1.0])


def _timeline(spec: GestureSpec, keys: dict, rest: Key, end: float) -> list[tuple[float, Key]]:
    """(seconds, Key) from the rest pose at 0 through the phases (and extra keys) to rest at ``end``."""
    keys = dict(keys)
    keys.setdefault("relax", keys["stroke_end"])
    line = [(0.0, rest)] + [(spec.times[p], keys[p]) for p in PHASES] + list(spec.extra) + [(end, rest)]
    return sorted(line, key=lambda k: k[0])


def _track(times: np.ndarray, line: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """Values (F, D) at ``times`` (F,), eased between consecutive (seconds, (D,)) keys."""
    key_t = np.array([t for t, _ in line])
    values = np.stack([np.asarray(v, dtype=np.float64) for _, v in line])
    seg = np.clip(np.searchsorted(key_t, times, side="right") - 1, 0, len(key_t) - 2)
    span = np.maximum(key_t[seg + 1] - key_t[seg], 1e-9)
    u = smooth((times - key_t[seg]) / span)[:, None]
    return values[seg] + (values[seg + 1] - values[seg]) * u


def _hand_frame(body: Body, side: str, times: np.ndarray, line, hang_d: np.ndarray, hang_n: np.ndarray):
    """Finger direction and palm normal (F, 3) each, in the body frame, of one hand over ``times``."""
    def vec(k: Key, which: int, hang: np.ndarray) -> np.ndarray:
        if k.palm == "rest":
            return hang
        v = np.asarray(PALMS[k.palm][which], dtype=np.float64)
        v = v / np.linalg.norm(v)
        return v if side == "l" else _mirror(v)
    d = _track(times, [(t, vec(k, 0, hang_d)) for t, k in line])
    n = _track(times, [(t, vec(k, 1, hang_n)) for t, k in line])
    return d, n


def _oscillation(spec: GestureSpec, times: np.ndarray) -> np.ndarray:
    """(F, 3) wrist offset (left-hand coordinates) of the stroke's oscillation, eased in and out, anchored so
    the stroke itself is at a swing's extreme."""
    if spec.oscillation is None:
        return np.zeros((len(times), 3))
    amplitude, hz, second = spec.oscillation
    a, s, b = spec.times["stroke_start"], spec.times["stroke"], spec.times["stroke_end"]
    envelope = smooth((times - a) / max(s - a, 1e-6)) * smooth((b - times) / max(0.25 * (b - a), 1e-6))
    phase = 2.0 * np.pi * hz * (times - s)
    out = np.cos(phase)[:, None] * np.asarray(amplitude)
    if second is not None:
        out = out + np.sin(phase)[:, None] * np.asarray(second)
    return out * envelope[:, None]


def _set_fingers(body: Body, local: np.ndarray, side: str, shape: np.ndarray) -> None:
    """Curl one hand's fingers in place; ``shape`` (F, 5) as in :data:`SHAPES`."""
    sign = 1.0 if side == "l" else -1.0
    for f, finger in enumerate(FINGERS):
        for k in (1, 2, 3):
            name = f"{side}_{finger}{k}"
            if name in body.skeleton.index:
                local[:, body.i(name)] = rot(Z, -sign * shape[:, f] * (0.8 if k == 1 else 1.0))
    for k in (1, 2, 3):
        name = f"{side}_thumb{k}"
        if name in body.skeleton.index:
            local[:, body.i(name)] = rot(Y, sign * shape[:, 4] * 0.5)


def _twist(q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The twist part (F, 4) of rotations ``q`` (F, 4, scalar-last) about ``axis`` (3,), unit."""
    proj = np.sum(q[:, :3] * axis, axis=-1, keepdims=True) * axis
    t = np.concatenate([proj, q[:, 3:]], axis=-1)
    norm = np.linalg.norm(t, axis=-1, keepdims=True)
    return np.where(norm > 1e-9, t / np.maximum(norm, 1e-9), quat.identity((len(q),)))


def gesture_motion(body: Body, stand: Motion, spec: GestureSpec, hand: str, name: str) -> Motion:
    """``spec`` played by ``hand`` ("left", "right", "both") from the first frame of ``stand``; the motion's
    ``sync_points`` are the phases in seconds."""
    n = int(round(spec.end * FPS))
    t = np.arange(n + 1) / FPS
    local = np.repeat(stand.local_rotations[:1], n + 1, axis=0).copy()
    root = np.repeat(stand.root_translations[:1], n + 1, axis=0)
    sk = body.skeleton
    sides = ("l", "r") if hand == "both" else (hand[0],)
    g_rot0, g_pos0 = forward_kinematics(sk, local[:1], root[:1])
    for side in sides:
        sign = 1.0 if side == "l" else -1.0
        keys = spec.right if side == "r" and hand == "both" and spec.right else spec.keys
        s_i, e_i, f_i, w_i = (body.i(f"{side}_{j}") for j in ("shoulder", "elbow", "forearm", "wrist"))
        hang = g_pos0[0, w_i] - g_pos0[0, s_i]
        hang_d = quat.rotate(g_rot0[0, w_i], body.offset(f"{side}_middle1"))
        hang_n = quat.rotate(g_rot0[0, w_i], -Y)
        rest = Key(tuple(hang * np.array([sign, 1.0, 1.0])), "rest", "relaxed")
        line = _timeline(spec, keys, rest, n / FPS)  # back at rest on the last frame
        shrug = _track(t, [(k_t, [k.shrug]) for k_t, k in line])[:, 0]
        shape = _track(t, [(k_t, SHAPES[k.shape]) for k_t, k in line])
        wrist = _track(t, [(k_t, np.asarray(k.wrist, dtype=np.float64)) for k_t, k in line]) + _oscillation(spec, t)
        if side == "r":
            wrist = _mirror(wrist)
        ac = body.i(f"{side}_acromioclavicular")
        local[:, ac] = quat.multiply(local[:, ac], rot(Z, sign * shrug))
        g_rot, g_pos = forward_kinematics(sk, local, root)
        shoulder = g_pos[:, s_i]
        rest_upper = body.offset(f"{side}_elbow")
        rest_lower = body.offset(f"{side}_forearm") + body.offset(f"{side}_wrist")
        # The elbow hangs down, a little out and back, as in a relaxed gesture space.
        pole = np.broadcast_to(np.array([sign * 0.45, -1.0, -0.35]), wrist.shape)
        g_upper, g_lower, _ = two_bone(shoulder, shoulder + wrist, float(np.linalg.norm(rest_upper)),
                                       float(np.linalg.norm(rest_lower)), pole, rest_upper, rest_lower, -Z, max_reach=0.995)
        d, nrm = _hand_frame(body, side, t, line, hang_d, hang_n)
        g_hand = frame_rotation(body.offset(f"{side}_middle1"), -Y, d, nrm)
        relative = quat.multiply(quat.conjugate(g_lower), g_hand)  # the hand in the forearm's frame
        axis = rest_lower / np.linalg.norm(rest_lower)
        twist = _twist(relative, axis)
        local[:, s_i] = quat.multiply(quat.conjugate(g_rot[:, sk.parents[s_i]]), g_upper)
        local[:, e_i] = quat.multiply(quat.conjugate(g_upper), g_lower)
        local[:, f_i] = twist
        local[:, w_i] = quat.multiply(quat.conjugate(twist), relative)
        _set_fingers(body, local, side, shape)
    sync = {p: spec.times[p] for p in PHASES}
    return Motion(sk, FPS, quat.normalize(local), root, name=name, sync_points=sync)


def stroke_variants(spec: GestureSpec) -> list[GestureSpec]:
    """The gesture of each repeated stroke after the first that :attr:`GestureSpec.strokes` gives: the same
    movement with every key's fingers in that stroke's shape."""
    def shaped(keys: dict, shape: str) -> dict:
        return {p: replace(k, shape=shape) for p, k in keys.items()}
    return [replace(spec, keys=shaped(spec.keys, shape), right=shaped(spec.right, shape), strokes=())
            for shape in spec.strokes]


def gesture_clips(body: Body, stand: Motion) -> list[tuple[GestureSpec, str, Motion]]:
    """Every gesture for every hand it is made for: (spec, hand, motion named ``<gesture>_<hand>``), each
    followed by its stroke variants (:func:`stroke_variants`), named ``<gesture>_<hand>@<stroke>`` from
    stroke 2 on: what the ``gesture`` controller plays for that repeated stroke."""
    out = []
    for spec in SPECS:
        for hand in spec.hands:
            name = f"{spec.name}_{hand}"
            out.append((spec, hand, gesture_motion(body, stand, spec, hand, name)))
            for n, variant in enumerate(stroke_variants(spec), start=2):
                out.append((variant, hand, gesture_motion(body, stand, variant, hand, f"{name}@{n}")))
    return out
