"""What the pack builder measures on each clip: contacts, steps, cycles, time-warp keys, parameters.

All from the motion itself (nothing typed by hand), in the core frame (metres, seconds, +Y up, +Z
forward, +X the character's left); angles in radians, headings about +Y (+ turns to the left).

- **Contacts** from :mod:`infuse.contacts` (foot speed and height, normalized by leg length, with
  hysteresis; the heel and the ball of each foot apart, :func:`~infuse.contacts.contact_phases`).
- **Steps**: a heel strike is the start of a foot's contact, a toe off its end; between them the
  foot flat (the ball comes down) and the heel off (the heel rises while the ball stays down).
- **Contact phases** per foot: the heel (ankle) is down from heel strike to heel off, the ball from
  foot flat to toe off; the controllers pin whichever is down (the ball once the heel rises).
- **Cycle**: the steadiest stride from one left heel strike to the next (:mod:`.cycles`); a looping clip of
  one stride is its own cycle.
- **Keys** (correspondence for time-warping): the times of left strike, right strike and the next left
  strike; they map to phases 0, 0.5 and 1 in every clip, so blended clips step together.
- **Locomotion parameters** over the cycle: ``speed`` = net horizontal displacement of the pelvis
  over the cycle's duration (not path length), ``direction`` of that displacement from the facing at
  mid cycle, ``turn_rate`` = change of facing from the cycle's first frame to its last (the same
  phase of the gait) over the duration; the facing comes from the hips, its line the mean about
  that turn.
  The blend coordinates are the velocity along and across the facing (speed along the arc for
  turning clips) and the turn rate.
- **Reach parameters**: the wrist position at the stroke (when the wrist settles after its fastest
  movement), in the body frame of the first frame (origin on the ground under the pelvis).
"""
from __future__ import annotations

import math

import numpy as np

from ..contacts import contact_phases, foot_contacts
from ..errors import UnusableInputError
from .cycles import steadiest_cycle, strides
from .manifest import GESTURE_PHASES

LOCOMOTION_COORDINATES = ("forward_speed", "lateral_speed", "turn_rate")
REACH_COORDINATES = ("x", "y", "z")
#: Smallest spread of each locomotion coordinate that makes it a dimension of the blend space (m/s,
#: m/s, rad/s): examples that differ less (forward walks 1 cm/s apart across the facing) lie in one.
LOCOMOTION_RESOLUTION = (0.1, 0.1, math.radians(10.0))


def headings(positions: np.ndarray, index: dict[str, int]) -> np.ndarray:
    """(F,) facing angles about +Y (radians, unwrapped) from the hips (else the shoulders)."""
    for a, b in (("l_hip", "r_hip"), ("l_shoulder", "r_shoulder")):
        if a in index and b in index:
            left = positions[:, index[a]] - positions[:, index[b]]
            break
    else:
        raise UnusableInputError(None, "no left/right hips or shoulders mapped: the facing is unknown")
    forward = np.stack((-left[:, 2], np.zeros(len(left)), left[:, 0]), axis=-1)  # left x up
    return np.unwrap(np.arctan2(forward[:, 0], forward[:, 2]))


def _runs(flags: np.ndarray, loop: bool) -> list[tuple[int, int]]:
    """(start, end exclusive) of runs of True in (F,) ``flags``; a loop's run across the seam is one run
    starting near the end (its end index may pass F)."""
    f = len(flags)
    d = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    starts, ends = list(np.nonzero(d == 1)[0]), list(np.nonzero(d == -1)[0])
    runs = list(zip(starts, ends))
    if loop and len(runs) > 1 and runs[0][0] == 0 and runs[-1][1] == f:
        first = runs.pop(0)
        last = runs.pop()
        runs.append((last[0], f - 1 + first[1]))  # the last frame repeats the first
    return [(int(a), int(b)) for a, b in runs]


def steps(foot_flags: np.ndarray, fps: float, loop: bool, phases: np.ndarray | None = None) -> list[dict]:
    """Steps of (F, 2) contact flags, in time order: ``{"foot", "strike", "flat", "heel_off", "off"}``
    seconds (heel strike, foot flat, heel off, toe off; from ``phases`` (F, 2, 2) of
    :func:`~infuse.contacts.contact_phases` when given, else flat = strike and heel off = toe off). In a loop a step
    may run past the end: its times then pass the clip's duration."""
    out = []
    f = len(foot_flags)
    for k, foot in enumerate(("left", "right")):
        for a, b in _runs(foot_flags[:, k], loop):
            if not loop and a == 0:
                continue  # already planted when the clip starts: not a strike
            flat, heel_off = a, b
            if phases is not None:
                frames = np.arange(a, b)
                wrapped = frames % max(f - 1, 1) if loop and b > f else frames
                ball = np.nonzero(phases[wrapped, k, 1])[0]
                if ball.size:
                    flat = a + int(ball[0])
                    lifted = np.nonzero(~phases[wrapped, k, 0][ball[0]:])[0]
                    heel_off = flat + int(lifted[0]) if lifted.size else b
            out.append({"foot": foot, "strike": a / fps, "flat": flat / fps, "heel_off": heel_off / fps, "off": b / fps})
    return sorted(out, key=lambda s: s["strike"])


def cycle_and_keys(step_list: list[dict], frames: int, fps: float, loop: bool,
                   speed_of=None) -> tuple[tuple[int, int], list[float], str]:
    """Cycle (first, last frame), keys (left strike, right strike, next left strike; seconds) and a note.

    A clip holding more than one stride (left strike to left strike, a right strike between; else right
    to right, :func:`~infuse.packs.cycles.strides`) gets the steadiest
    (:func:`~infuse.packs.cycles.steadiest_cycle`, by ``speed_of((first, last))`` m/s); a loop of one
    stride is its own cycle."""
    duration = (frames - 1) / fps
    lefts = [s["strike"] for s in step_list if s["foot"] == "left"]
    rights = [s["strike"] for s in step_list if s["foot"] == "right"]
    if speed_of is not None:
        stride = steadiest_cycle(step_list, speed_of, fps)
        if stride is not None:
            keys = {(int(round(a * fps)), int(round(b * fps))): k for a, b, k in strides(step_list)}
            return stride, keys[stride], ""
    if loop:
        if lefts and rights:
            t0 = lefts[0]
            later = [r for r in rights if r > t0] or [r + duration for r in rights]
            return (0, frames - 1), [t0, later[0], t0 + duration], ""
        return (0, frames - 1), [0.0, duration / 2.0, duration], "no steps: uniform keys"
    for i, t0 in enumerate(lefts[:-1]):
        t1 = lefts[i + 1]
        mids = [r for r in rights if t0 < r < t1]
        if mids:
            return (int(round(t0 * fps)), int(round(t1 * fps))), [t0, mids[0], t1], ""
    return (0, frames - 1), [0.0, duration / 2.0, duration], "no full left-right-left cycle: the whole clip, uniform keys"


def locomotion_parameters(root: np.ndarray, heading: np.ndarray, cycle: tuple[int, int], fps: float) -> dict:
    """Speed, direction, turn rate and blend coordinates of the pelvis path ``root`` (F, 3) with facing
    ``heading`` (F,) over frames ``cycle``."""
    a, b = cycle
    duration = max((b - a) / fps, 1e-9)
    d = root[b] - root[a]
    d[1] = 0.0
    speed = float(np.hypot(d[0], d[2]) / duration)
    # The facing oscillates with the pelvis, the same at both ends of a cycle (a stride from one left
    # strike to the next): the turn is the change between them, the facing the mean about that turn.
    t = np.arange(b - a + 1) / fps
    h = heading[a:b + 1]
    turn = float(h[-1] - h[0]) / duration if len(t) > 1 else 0.0
    start = float(np.mean((h - turn * t)[:max(len(t) - 1, 1)]))
    mid = float(start + turn * duration / 2.0)
    forward = np.array([np.sin(mid), 0.0, np.cos(mid)])
    left = np.array([np.cos(mid), 0.0, -np.sin(mid)])
    direction = float(np.arctan2(d @ left, d @ forward)) if speed > 1e-4 else 0.0
    half = 0.5 * abs(turn) * duration
    arc = speed * (half / np.sin(half) if half > 1e-6 else 1.0)  # speed along the arc of a turning clip
    return {"speed": speed, "direction": direction, "turn_rate": turn, "duration": duration,
            "forward_speed": float(arc * np.cos(direction)), "lateral_speed": float(arc * np.sin(direction)),
            "heading_start": float(start)}


#: Seconds at each end of a transition clip over which its facing and speed are measured.
TRANSITION_END_S = 0.4


def transition_parameters(root: np.ndarray, heading: np.ndarray, fps: float) -> dict:
    """What a transition clip does, measured over the whole clip from its pelvis path ``root`` (F, 3)
    and facing ``heading`` (F,) radians: ``facing_start``, ``facing_end`` (radians, each averaged over
    :data:`TRANSITION_END_S` at its end), ``turn`` (their difference, radians, + left), ``travel_x``,
    ``travel_z`` (metres: the pelvis's ground displacement in the starting facing's frame, +X left,
    +Z ahead), ``speed_start``, ``speed_end`` (m/s, the pelvis's net ground speed over each end) and
    ``duration`` (seconds)."""
    frames = len(root)
    span = int(min(max(round(TRANSITION_END_S * fps), 1), max(frames - 1, 1)))
    first, last = float(np.mean(heading[:span + 1])), float(np.mean(heading[-span - 1:]))
    d = (root[-1] - root[0])[[0, 2]]
    ahead = np.array([np.sin(first), np.cos(first)])
    left = np.array([np.cos(first), -np.sin(first)])
    speed = lambda a, b: float(np.hypot(*(root[b] - root[a])[[0, 2]]) * fps / max(b - a, 1))  # noqa: E731
    return {"facing_start": first, "facing_end": last, "turn": last - first, "travel_x": float(d @ left),
            "travel_z": float(d @ ahead), "speed_start": speed(0, span), "speed_end": speed(frames - 1 - span, frames - 1),
            "duration": (frames - 1) / fps}


def stroke_frame(wrist: np.ndarray, fps: float) -> int:
    """The frame the wrist (F, 3) settles after its fastest movement (10% of peak speed), else the frame
    farthest from its start."""
    if len(wrist) < 3:
        return len(wrist) - 1
    speed = np.linalg.norm(np.gradient(wrist, axis=0), axis=-1) * fps
    peak = int(np.argmax(speed))
    if speed[peak] < 1e-3:
        return len(wrist) - 1
    after = np.nonzero(speed[peak:] < 0.1 * speed[peak])[0]
    if after.size:
        return int(peak + after[0])
    return int(np.argmax(np.linalg.norm(wrist - wrist[0], axis=-1)))


def body_frame_point(point: np.ndarray, root: np.ndarray, heading: float, ground: float) -> np.ndarray:
    """(3,) ``point`` in the body frame: origin on the ground under ``root``, +Z the facing ``heading``."""
    rel = np.asarray(point, dtype=np.float64) - np.array([root[0], ground, root[2]])
    c, s = np.cos(heading), np.sin(heading)
    return np.array([c * rel[0] - s * rel[2], rel[1], s * rel[0] + c * rel[2]])


def analyse_clip(motion, entry, kind: str, index: dict[str, int], mapping, fk, cycle=None) -> dict:
    """The analysis of one clip (a JSON-ready dict); ``fk`` = (global rotations, positions) of ``motion``;
    ``cycle``: its locomotion cycle and keys, ((first, last frame), keys), when already chosen."""
    g_rot, g_pos = fk
    fps = motion.fps
    frames = motion.num_frames
    found = foot_contacts(motion, mapping, fk=fk)
    foot_flags = found.foot_flags()
    phases = contact_phases(found, g_pos)
    loop = bool(entry.loop)
    step_list = steps(foot_flags, fps, loop, phases) if entry.role in ("cycle", "other") else []
    heading = headings(g_pos, index)
    root = g_pos[:, index["base"]]
    out = {"name": entry.name, "role": entry.role, "tags": list(entry.tags), "loop": loop, "hand": entry.hand,
           "frames": frames, "fps": fps, "duration": motion.duration, "ground": found.ground,
           "leg_length": found.leg_length, "contacts": foot_flags.T.astype(int).tolist(),
           "heel_contacts": phases[:, :, 0].T.astype(int).tolist(), "ball_contacts": phases[:, :, 1].T.astype(int).tolist(),
           "steps": step_list, "notes": []}
    if kind == "locomotion":
        def speed_of(stride):
            d = (root[stride[1]] - root[stride[0]])[[0, 2]]
            return float(np.hypot(*d)) * fps / max(stride[1] - stride[0], 1)

        if cycle is not None:
            (cycle, keys), note = cycle, ""
        else:
            cycle, keys, note = cycle_and_keys(step_list, frames, fps, loop, speed_of if entry.role == "cycle" else None)
        if entry.role == "idle":
            cycle, keys, note = (0, frames - 1), [0.0, motion.duration / 2.0, motion.duration], ""
        if note:
            out["notes"].append(note)
        out.update(cycle=list(cycle), keys=keys, parameters=locomotion_parameters(root, heading, cycle, fps))
    elif kind == "gesture":  # timed by its authored phases; nothing to blend by
        sync = {GESTURE_PHASES[k]: t for k, t in entry.sync.items()}
        out.update(stroke=sync["stroke"], stroke_frame=int(round(sync["stroke"] * fps)), sync=sync, parameters={})
    elif kind == "posture":  # a standing loop, played whole; nothing to blend by
        out.update(stroke=0.0, stroke_frame=0, parameters={})
    else:
        hand = entry.hand
        if hand is None:  # the wrist that travels farther
            travel = {h: np.ptp(g_pos[:, index[f"{h[0]}_wrist"]], axis=0).max() for h in ("left", "right")
                      if f"{h[0]}_wrist" in index}
            hand = max(travel, key=lambda h: travel[h])
        wrist = g_pos[:, index[f"{hand[0]}_wrist"]]
        stroke = stroke_frame(wrist, fps)
        point = body_frame_point(wrist[stroke], root[0], float(heading[0]), found.ground)
        out.update(hand=hand, stroke=stroke / fps, stroke_frame=stroke,
                   parameters={"x": float(point[0]), "y": float(point[1]), "z": float(point[2]),
                               "heading_start": float(heading[0])})
    return out


def coordinates_of(kind: str) -> tuple[str, ...]:
    return LOCOMOTION_COORDINATES if kind == "locomotion" else REACH_COORDINATES


def resolution_of(kind: str) -> tuple[float, ...] | None:
    """The coordinates' resolutions of a pack kind's blend space (see :class:`~.tessellation.Tessellation`)."""
    return LOCOMOTION_RESOLUTION if kind == "locomotion" else None


def blend_groups(kind: str, clips: list[dict]) -> dict[str, list[dict]]:
    """Clips that form each blend space: locomotion cycles and idles in one; reaches per hand."""
    if kind == "locomotion":
        return {"locomotion": [c for c in clips if c["role"] in ("cycle", "idle")]}
    groups: dict[str, list[dict]] = {}
    for c in clips:
        if c["role"] == "reach":
            groups.setdefault(c["hand"], []).append(c)
    return groups
