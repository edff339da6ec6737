"""Lip sync: an :class:`~infuse.speech.Utterance` -> viseme weight tracks for a character, as plain data.

:func:`viseme_curves` gives the channel weights of one viseme set over time, sampled at the
animation frame rate (``K = ceil(duration * fps) + 1`` frames, so the clip covers the audio and
ends less than a frame after it); :func:`lipsync` binds them to a character's own morph targets,
face poses or jaw joint (see :mod:`.channels`). The result (:class:`LipSync`) is data a
controller can play: sample times, weights per target, joint rotations, and a JSON timeline.

Coarticulation is :mod:`.coarticulation`'s dominance blend, smoothing and speed limit. Two holds
come last: bilabials (p, b, m) reach the set's closure pose exactly, on at least one frame, and
pauses of at least ``min_rest_pause_s`` (and the first and last frame) return the mouth to rest.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from infuse.errors import UnusableInputError, UsageError
from infuse.motion import Motion
from infuse.skeleton import Skeleton
from infuse.speech import SILENCE, Utterance

from . import coarticulation as co
from .channels import FaceChannels, viseme_set_binding
from .expressions import Expression, expression_tracks
from .joints import JawRig, PoseFace, face_motion
from .tables import VISEME_SETS, VisemeSet, dominance_arrays, phoneme_viseme, viseme_set


@dataclass(frozen=True)
class LipSyncSettings:
    """Timing settings; seconds, and units (0..1 weight) per second for ``speed_limit``."""

    fps: float = 30.0
    smoothing_s: float = 0.012
    speed_limit: float = 6.0
    closure_ramp_s: float = 0.03
    rest_ramp_s: float = 0.08
    min_rest_pause_s: float = 0.12
    band: int = 4
    jaw_max_angle_deg: float = 12.0

    def __post_init__(self):
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise UsageError(f"fps must be positive, got {self.fps}")
        for name in ("smoothing_s", "closure_ramp_s", "rest_ramp_s", "min_rest_pause_s"):
            if not getattr(self, name) >= 0:
                raise UsageError(f"{name} must be >= 0, got {getattr(self, name)}")


@dataclass
class LipSync:
    """Lip-sync tracks for one utterance.

    - ``times`` (K,) seconds; ``channels`` and ``channel_weights`` (K, C): the viseme set's channels;
    - ``morph_weights``: morph target (or VRM expression) -> (K,) weights 0..1;
    - ``joint_rotations`` / ``joint_translations``: joint name -> (K, 4) local rotations (x, y, z, w) /
      (K, 3) local translations in metres, for joint faces;
    - ``timeline``: the phoneme/viseme timeline as a JSON-able dict.
    """

    viseme_set: str
    times: np.ndarray
    channels: tuple[str, ...]
    channel_weights: np.ndarray
    morph_weights: dict[str, np.ndarray] = field(default_factory=dict)
    joint_rotations: dict[str, np.ndarray] = field(default_factory=dict)
    joint_translations: dict[str, np.ndarray] = field(default_factory=dict)
    timeline: dict = field(default_factory=dict)
    fps: float = 30.0

    def sample(self, t) -> dict[str, np.ndarray]:
        """Channel weights at times ``t`` (seconds, scalar or array), linearly interpolated."""
        t = np.asarray(t, float)
        return {c: np.interp(t, self.times, self.channel_weights[:, i]) for i, c in enumerate(self.channels)}

    def controller(self, name: str = "lipsync"):
        """A runtime ``tracks`` controller (:class:`infuse.runtime.tracks.Tracks`, face layer) that plays these
        morph weights and face-joint rotations as speech; face-joint translations are not carried."""
        from infuse.runtime.tracks import Tracks

        return Tracks(self.times, dict(self.joint_rotations), dict(self.morph_weights), speaks=True, name=name)

    def motion(self, skeleton: Skeleton, name: str = "speech") -> Motion | None:
        """The speech as a clip of ``skeleton`` at ``fps``: its face joints (the clip's animated joints;
        the rest pose elsewhere) and its morph weights; ``None`` when it moves neither."""
        if not self.joint_rotations and not self.morph_weights:
            return None
        rot = {skeleton.index[j]: r for j, r in self.joint_rotations.items()}
        trans = {skeleton.index[j]: t for j, t in self.joint_translations.items()}
        names = tuple(self.morph_weights)
        weights = np.stack([self.morph_weights[n] for n in names], axis=1) if names else np.zeros((len(self.times), 0))
        return face_motion(skeleton, self.fps, len(self.times), rot, trans, name, names, weights)


def _phoneme_rows(utterance: Utterance, vs: VisemeSet):
    starts, ends, names = utterance.phoneme_arrays()
    order = {p: i for i, p in enumerate(vs.phonemes)}
    unknown = sorted({n for n in names if n not in order})
    if unknown:
        raise UsageError(f"phonemes outside the common set: {', '.join(unknown)}")
    return starts, ends, names, np.array([order[n] for n in names], dtype=int)


def _holds(starts, ends, names, duration: float, vs: VisemeSet, s: LipSyncSettings):
    """The closure hold (bilabials, merged when adjacent) and the rest hold (pauses and both ends)."""
    frame = 1.0 / s.fps
    is_closure = np.array([phoneme_viseme(n) == "PP" for n in names], bool)
    spans = _runs(starts, ends, is_closure)
    # the hold starts at the bilabial's start and is complete a ramp later (the blend alone decides
    # when the closure viseme takes over, at the boundary); it ends likewise. A closure too short for
    # that is complete on the frame nearest its middle, so the lips do meet on a frame.
    ramp = np.full(len(spans), s.closure_ramp_s)
    first, last = spans[:, 0] + ramp, spans[:, 1] - ramp
    short = last - first < frame
    nearest_frame = np.round((spans[:, 0] + spans[:, 1]) / 2 * s.fps) / s.fps
    first = np.where(short, nearest_frame, first)
    last = np.where(short, nearest_frame, last)
    closure = co.Hold(first, last, ramp, ramp, vs.closure)

    is_sil = np.array([n == SILENCE for n in names], bool)
    pauses = _runs(starts, ends, is_sil)
    rows = []
    for p0, p1 in pauses:
        if p0 <= 0.0:  # leading silence: rest from the first frame
            r = min(s.rest_ramp_s, p1)
            rows.append((0.0, max(0.0, p1 - r), 0.0, r))
        elif p1 >= duration - 1e-9:  # trailing silence: rest to the last frame
            r = min(s.rest_ramp_s, p1 - p0)
            rows.append((p0 + r, duration + frame, r, 0.0))
        elif p1 - p0 >= s.min_rest_pause_s:
            r = min(s.rest_ramp_s, (p1 - p0) / 2)
            rows.append((p0 + r, p1 - r, r, r))
    if not rows or rows[0][0] > 0.0:  # speech from the first instant: still start at rest
        r = min(s.rest_ramp_s, (ends[0] - starts[0]) / 2) if len(starts) else 0.0
        rows.insert(0, (0.0, 0.0, 0.0, r))
    if rows[-1][1] < duration:
        r = min(s.rest_ramp_s, (ends[-1] - starts[-1]) / 2) if len(starts) else 0.0
        rows.append((duration, duration + frame, r, 0.0))
    a = np.array(rows, float).reshape(-1, 4)
    rest = co.Hold(a[:, 0], a[:, 1], a[:, 2], a[:, 3], vs.rest)
    return closure, rest


def _runs(starts, ends, mask) -> np.ndarray:
    """(R, 2) start/end of the runs of consecutive intervals where ``mask`` holds."""
    if not mask.any():
        return np.zeros((0, 2))
    m = mask.astype(np.int8)
    edges = np.diff(np.concatenate([[0], m, [0]]))
    first = np.flatnonzero(edges == 1)
    last = np.flatnonzero(edges == -1) - 1
    return np.stack([starts[first], ends[last]], axis=1)


def viseme_curves(utterance: Utterance, set_name: str = "oculus", settings: LipSyncSettings | None = None
                  ) -> tuple[np.ndarray, np.ndarray, VisemeSet]:
    """``(times (K,), weights (K, C), viseme set)`` of ``set_name`` for ``utterance`` (see the module doc)."""
    if set_name not in VISEME_SETS:
        raise UsageError(f"unknown viseme set {set_name!r}; known: {', '.join(VISEME_SETS)}")
    s = settings or LipSyncSettings()
    vs = viseme_set(set_name)
    duration = float(utterance.duration_s)
    if not duration > 0:
        raise UnusableInputError(None, "the utterance has no duration")
    times = co.sample_times(duration, s.fps)
    starts, ends, names, rows = _phoneme_rows(utterance, vs)
    _, alpha, theta_before, theta_after = dominance_arrays()
    weights = co.dominance_blend(times, starts, ends, vs.targets[rows], alpha[rows], theta_before[rows], theta_after[rows],
                                 vs.rest, s.band)
    weights = co.smooth(weights, s.smoothing_s, s.fps)
    weights = co.limit_speed(weights, s.speed_limit, s.fps)
    closure, rest = _holds(starts, ends, names, duration, vs, s)
    weights = co.apply_hold(times, weights, rest)
    weights = co.apply_hold(times, weights, closure)
    return times, np.clip(weights, 0.0, 1.0), vs


def timeline(utterance: Utterance, set_name: str, fps: float) -> dict:
    """The phoneme/viseme timeline: phonemes with their viseme class, merged viseme runs, words, marks."""
    doc = utterance.to_dict()
    for entry in doc["phonemes"]:
        entry["viseme"] = phoneme_viseme(entry["phoneme"]) or None
    runs: list[dict] = []
    for entry in doc["phonemes"]:
        v = entry["viseme"]
        if runs and (v is None or v == runs[-1]["viseme"]):
            runs[-1]["end"] = entry["end"]
        else:
            runs.append({"start": entry["start"], "end": entry["end"], "viseme": v or "sil"})
    doc.update(viseme_set=set_name, fps=fps, frames=int(np.ceil(utterance.duration_s * fps - 1e-9)) + 1, visemes=runs)
    return doc


def choose_viseme_set(face: FaceChannels, requested: str | None = None) -> str:
    """The viseme set to drive: ``requested`` if the character offers it, else the best it offers.

    Raises :class:`UnusableInputError` when it offers none (saying what it has), :class:`UsageError`
    when it does not offer ``requested``.
    """
    offered = face.viseme_sets()
    if not offered:
        found = ", ".join(f"{v} ({len(c)} channels)" for v, c in face.vocabularies.items()) or "no known face channels"
        notes = "; ".join(face.notes)
        raise UnusableInputError(None, f"the character has no mouth channels for lip sync (found: {found}"
                                       + (f"; {notes}" if notes else "") + "); declare them in a map file (\"face\")")
    if requested is not None and requested not in offered:
        raise UsageError(f"the character does not offer viseme set {requested!r}; it offers: {', '.join(offered)}")
    return requested or offered[0]


def lipsync(utterance: Utterance, face: FaceChannels | None = None, viseme_set: str | None = None,
            settings: LipSyncSettings | None = None, skeleton: Skeleton | None = None,
            expressions: list[Expression] | tuple = ()) -> LipSync:
    """Lip-sync tracks of ``utterance`` for a character with ``face`` channels.

    ``viseme_set`` picks one of the sets the character offers (default: the best it has). Without
    ``face`` the result carries the set's channel weights only (``viseme_set`` default "oculus").
    Joint faces (set "jaw", or SmartBody face poses) need the character's ``skeleton``.
    ``expressions`` (:class:`~infuse_lipsync.expressions.Expression`) are added on top, on whatever
    channels the character has for them. Raises :class:`UnusableInputError` when the character has
    no face channel for lip sync.
    """
    s = settings or LipSyncSettings()
    if face is None:
        set_name = viseme_set or "oculus"
        times, weights, vs = viseme_curves(utterance, set_name, s)
        return LipSync(set_name, times, vs.channels, weights, timeline=timeline(utterance, set_name, s.fps), fps=s.fps)
    set_name = choose_viseme_set(face, viseme_set)
    times, weights, vs = viseme_curves(utterance, set_name, s)
    binding = viseme_set_binding(face, set_name)
    result = LipSync(set_name, times, vs.channels, weights, timeline=timeline(utterance, set_name, s.fps), fps=s.fps)
    result.timeline["channels"] = {c: [list(b) for b in binds] for c, binds in binding.items()}
    extra = expression_tracks(list(expressions), face, times) if expressions else {}
    pose_extra = {t: w for t, w in extra.items() if t in face.poses}
    jaw_extra = extra.get(face.jaw) if face.jaw else None
    morph_extra = {t: w for t, w in extra.items() if t not in face.poses and t != face.jaw}
    if set_name == "jaw" and face.jaw is not None:  # a face offers the jaw set when it has a jaw joint
        if skeleton is None:
            raise UsageError("a jaw face needs the character's skeleton")
        rig = JawRig.from_skeleton(skeleton, face.jaw)
        opening = weights[:, vs.channels.index("jaw")] + (0.0 if jaw_extra is None else jaw_extra)
        result.joint_rotations[face.jaw] = rig.rotations(np.clip(opening, 0.0, 1.0), np.deg2rad(s.jaw_max_angle_deg))
    elif face.kinds.get(set_name) == "pose":
        if skeleton is None:
            raise UsageError("a face driven by face poses needs the character's skeleton")
        channels = [c for c in vs.channels if c in binding]
        bindings = [binding[c] for c in channels] + [[(pose, 1.0)] for pose in pose_extra]
        columns = [weights[:, vs.channels.index(c)] for c in channels] + list(pose_extra.values())
        pose_face = PoseFace.load(skeleton, face.poses, sorted({p for b in bindings for p, _ in b}))
        rotations, translations = pose_face.blend(np.stack(columns, axis=1), bindings)
        for m, j in enumerate(pose_face.joints):
            name = skeleton.names[j]
            result.joint_rotations[name] = rotations[:, m]
            result.joint_translations[name] = translations[:, m]
    else:
        for c, binds in binding.items():
            column = weights[:, vs.channels.index(c)]
            for target, w in binds:
                result.morph_weights[target] = result.morph_weights.get(target, 0.0) + w * column
    for target, track in morph_extra.items():
        below = result.morph_weights.get(target)
        result.morph_weights[target] = track if below is None else below + track
    result.morph_weights = {t: np.clip(np.broadcast_to(w, times.shape), 0.0, 1.0) for t, w in result.morph_weights.items()}
    return result
