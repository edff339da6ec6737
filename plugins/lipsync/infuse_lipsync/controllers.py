"""Runtime controllers for the face: ``speech`` (an utterance's lip sync) and ``face`` (an expression held
over an activity), with the builders that realize BML ``<speech>``, ``<faceLexeme>``, ``<faceFacs>`` and
``<face>`` activations.

- :class:`Speech` plays the lip sync of an :class:`~infuse.speech.Utterance` on whatever mouth the
  character has (morph targets, SmartBody face poses or a jaw joint; :mod:`.channels`). It is marked as
  speaking, so saccades pause. A character without mouth channels is reported once and still speaks
  (its audio is kept), without moving its mouth.
- :class:`FaceExpression` holds a lexeme (``smile``, BML ``RAISE_BROWS``...) or a FACS action unit, on one
  side or both, at an intensity, as an additive offset on the face layer: morph weights are added,
  face-pose and jaw rotations are post-multiplied. It blends in over ``blend_in_s`` (BML: start to
  attackPeak) and out over ``blend_out_s`` (relax to end).
"""
from __future__ import annotations

import json
import re
import threading
from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.errors import InfuseError, UnusableInputError, UsageError
from infuse.runtime import Layer, Mode
from infuse.runtime.tracks import Tracks, TracksBinding
from infuse.runtime.controller import Controller
from infuse.speech import Utterance

from .channels import detect_face
from .expressions import expression_targets
from .tables import expressions_table
from .joints import JawRig, PoseFace
from .lipsync import LipSyncSettings, lipsync

#: BML 1.0 facial lexemes (and a few other realizers' names) -> a lexeme of ``expressions.toml`` or action
#: units, and the side they act on.
BML_LEXEMES = {
    "OBLIQUE_BROWS": ("oblique_brows", "BOTH"),
    "RAISE_BROWS": ("raised_brows", "BOTH"), "RAISE_LEFT_BROW": ("raised_brows", "LEFT"),
    "RAISE_RIGHT_BROW": ("raised_brows", "RIGHT"),
    "LOWER_BROWS": ("AU4", "BOTH"), "LOWER_LEFT_BROW": ("AU4", "LEFT"), "LOWER_RIGHT_BROW": ("AU4", "RIGHT"),
    "LOWER_MOUTH_CORNERS": ("AU15", "BOTH"), "LOWER_LEFT_MOUTH_CORNER": ("AU15", "LEFT"),
    "LOWER_RIGHT_MOUTH_CORNER": ("AU15", "RIGHT"),
    "RAISE_MOUTH_CORNERS": ("AU12", "BOTH"), "RAISE_LEFT_MOUTH_CORNER": ("AU12", "LEFT"),
    "RAISE_RIGHT_MOUTH_CORNER": ("AU12", "RIGHT"),
    "OPEN_MOUTH": ("AU26", "BOTH"), "OPEN_LIPS": ("AU25", "BOTH"), "WIDEN_EYES": ("AU5", "BOTH"),
    "CLOSE_EYES": ("AU43", "BOTH"), "WINK": ("AU46L", "LEFT"), "BARE_TEETH": ("bare_teeth", "BOTH"),
    "SMILE": ("smile", "BOTH"), "FROWN": ("frown", "BOTH"),
}
# Words in other lexicons' names (Greta's Eyebrows_Raise, Smile_Small_Open, joy...) -> a lexeme.
_LEXEME_WORDS = (
    (("smile", "joy", "happy", "happiness"), "smile"), (("frown",), "frown"), (("surprise", "surprised"), "surprise"),
    (("sad", "sadness"), "sad"), (("angry", "anger"), "angry"), (("blink",), "blink"),
    (("fear", "afraid", "scared", "fearful"), "fear"), (("disgust", "disgusted"), "disgust"),
    (("contempt", "sneer"), "contempt"),
)
_SIDE_SUFFIX = re.compile(r"(left|right|lf|rt|_l|_r|\.l|\.r)$")


def expression_for(lexeme: str) -> tuple[str | dict, str]:
    """(expression, side) for a lexeme name: a BML 1.0 lexeme, a lexeme of ``expressions.toml``, an action unit
    (``AU12``), or a name whose words say it (``Eyebrows_Raise``, ``Smile_Small_Open``). Raises
    :class:`UsageError` when nothing matches."""
    key = lexeme.strip().upper().replace("-", "_").replace(" ", "_")
    if key in BML_LEXEMES:
        return BML_LEXEMES[key]
    words = set(key.lower().split("_"))
    side = "LEFT" if "left" in words else "RIGHT" if "right" in words else "BOTH"
    if re.fullmatch(r"AU?\d+[LR]?", key):
        return (key if key.startswith("AU") else f"AU{key[1:]}"), side
    if "brow" in key.lower() or "eyebrow" in key.lower() or "eyebrows" in words:
        if words & {"raise", "raised", "up", "raising"}:
            return "raised_brows", side
        if words & {"frown", "down", "lower", "lowered"}:
            return "AU4", side
    if "wink" in words:
        return ("AU46R" if side == "RIGHT" else "AU46L"), side
    for names, name in _LEXEME_WORDS:
        if words & set(names) or key.lower() == name:
            return name, side
    if key.lower() in ("raised_brows", "questioning"):
        return "raised_brows", side
    raise UsageError(f"facial lexeme {lexeme!r} is unknown; known: {', '.join(known_lexemes())}, action units "
                     "(AU12, 12_left) and names containing one of these words")


def known_lexemes() -> list[str]:
    """The facial lexemes :func:`expression_for` knows by name: BML 1.0's, then the expressions of
    ``expressions.toml`` and their other words (``happy``, ``afraid``...)."""
    words = [w for names, _ in _LEXEME_WORDS for w in names]
    return list(dict.fromkeys([*BML_LEXEMES, *expressions_table()["lexemes"], *words]))


def target_side(name: str) -> str | None:
    """``"LEFT"``, ``"RIGHT"`` or None (both or unsided) from a morph target or face pose name."""
    key = name.rsplit(".", 1)[-1].replace("-", "_").lower()
    m = _SIDE_SUFFIX.search(key)
    if m is None:
        return None
    return "LEFT" if m.group(1) in ("left", "lf", "_l", ".l") else "RIGHT"


class FaceChannelsByMap(dict):
    """The face channels of one runtime character, detected once per map file: a key of the map file
    (:func:`map_key`) -> its :class:`~.channels.FaceChannels`. Kept in the character's rig
    (:meth:`~infuse.runtime.rig.Rig.state_of`), so it goes with its runtime."""


def map_key(map_file) -> tuple[str, str] | None:
    """What tells map files apart: a path as written, a parsed document by its content (two equal
    documents declare the same channels), None for none."""
    if map_file is None:
        return None
    if isinstance(map_file, dict):
        return "document", json.dumps(map_file, sort_keys=True, default=str)
    return "path", str(map_file)


def face_channels(rig, map_file=None):
    """The :class:`~.channels.FaceChannels` of a runtime character, detected once per map file."""
    channels = rig.state_of(FaceChannelsByMap)
    key = map_key(map_file)
    if key not in channels:
        channels[key] = detect_face(rig.character.asset, map_file)
    return channels[key]


class Speech(Tracks):
    """Lip sync of ``utterance`` (an :class:`~infuse.speech.Utterance`, times from its start) at ``fps``.

    ``map_file`` declares face channels (see :mod:`.channels`); ``viseme_set`` picks one of the
    character's sets. The activity lasts as long as the audio.
    """

    kind = "speech"
    blend_in_s = 0.0  # the lip sync starts and ends at rest
    blend_out_s = 0.0

    def __init__(self, utterance: Utterance, fps: float = 30.0, map_file=None, viseme_set: str | None = None,
                 name: str = "speech"):
        if not isinstance(utterance, Utterance):
            raise UsageError(f"speech needs an infuse.speech.Utterance, not {type(utterance).__name__}")
        if not utterance.duration_s > 0:
            raise UsageError("the utterance has no duration")
        super().__init__([0.0, float(utterance.duration_s)], speaks=True, name=name)
        self.utterance = utterance
        self.settings = LipSyncSettings(fps=fps)
        self.map_file = map_file
        self.viseme_set = viseme_set

    def describe(self) -> str:
        return f"speech {self.utterance.text[:40]!r}"

    def bind(self, rig, report) -> TracksBinding:
        """The lip sync on this character's face channels, as keyed tracks (their own per character); none
        when the face has no usable channels (it speaks without moving its mouth). Taken from
        :meth:`prepare` when it worked it out from the very same inputs."""
        inputs = self._inputs(rig)
        with _PREPARED_LOCK:
            kept = rig.state_of(PreparedLipSync).pop(id(self.utterance), None)
        if kept is not None and _same(kept[0], inputs):
            binding, notes = kept[1]
        else:
            binding, notes = self._bound(rig, inputs[1])
        for note in notes:
            report(note)
        return binding

    def prepare(self, rig) -> None:
        """Work out :meth:`bind` for ``rig`` ahead, on another thread, and keep it in the rig for
        :meth:`bind` (the latest :data:`MAX_PREPARED` of a character)."""
        inputs = self._inputs(rig)
        bound = self._bound(rig, inputs[1])
        with _PREPARED_LOCK:
            kept = rig.state_of(PreparedLipSync)
            kept[id(self.utterance)] = (inputs, bound)
            while len(kept) > MAX_PREPARED:
                del kept[next(iter(kept))]

    def _inputs(self, rig) -> tuple:
        """What :meth:`bind` depends on: the utterance, the face channels and the character (the same
        objects), the viseme set, the settings and the name."""
        return self.utterance, face_channels(rig, self.map_file), rig.character, self.viseme_set, self.settings, self.name

    def _bound(self, rig, face) -> tuple[TracksBinding, list[str]]:
        """The binding and what to report about it, in order."""
        notes: list[str] = []
        try:
            result = lipsync(self.utterance, face, self.viseme_set, self.settings, rig.skeleton)
        except UnusableInputError as exc:
            notes.append(f"{exc.problem}; it speaks without moving its mouth")
            return super().bind(rig, notes.append), notes  # no tracks: the speech's span alone
        tracks = Tracks(result.times, dict(result.joint_rotations), dict(result.morph_weights), speaks=True, name=self.name)
        return tracks.bind(rig, notes.append), notes


class PreparedLipSync(dict):
    """The lip syncs :meth:`Speech.prepare` worked out ahead for one runtime character, by the utterance's
    id: (:meth:`Speech._inputs`, (binding, notes)). Kept in the character's rig, the oldest dropped first."""


#: Lip syncs kept ahead per character.
MAX_PREPARED = 16
_PREPARED_LOCK = threading.Lock()


def _same(kept: tuple, inputs: tuple) -> bool:
    """Whether two :meth:`Speech._inputs` are the very same: objects by identity, settings by value."""
    return all(a is b for a, b in zip(kept[:3], inputs[:3])) and kept[3:] == inputs[3:]


@dataclass(frozen=True, eq=False)
class FaceBinding:
    """A face expression bound to one character: morph targets ``columns`` (M,) at weights ``values``
    (M,); face joints ``joints`` (K,) turned by local offsets ``offsets`` (K, 4) from rest; joints
    ``moved`` (T,) shifted by ``shifts`` (T, 3) metres from rest."""

    columns: np.ndarray
    values: np.ndarray
    joints: np.ndarray
    offsets: np.ndarray
    moved: np.ndarray
    shifts: np.ndarray


class FaceExpression(Controller):
    """Hold ``expression`` (a lexeme, an action unit such as ``"AU12"`` or ``{AU: weight}``) at ``amount``
    (0..1) on ``side`` (``"LEFT"``, ``"RIGHT"`` or ``"BOTH"``; default both). ``lexeme`` names it the way
    BML and other realizers do instead (``RAISE_LEFT_BROW``, ``Smile_Small_Open``; see :func:`expression_for`).
    Additive on the face layer, after the lip sync (priority 5)."""

    kind = "face"
    layer = Layer.FACE
    mode = Mode.ADDITIVE
    priority = 5
    blend_in_s = 0.3
    blend_out_s = 0.3

    def __init__(self, expression=None, amount: float = 1.0, side: str | None = None, map_file=None,
                 duration_s: float | None = None, lexeme: str | None = None):
        if not np.isfinite(amount):
            raise UsageError("an expression's amount must be finite")
        if lexeme is not None:  # a BML or other realizer's lexeme name: its expression and side
            expression, lexeme_side = expression_for(lexeme)
            side = side or lexeme_side
        if expression is None:
            raise UsageError("a face expression needs an expression or a lexeme")
        side = str(side or "BOTH").upper()
        if side not in ("LEFT", "RIGHT", "BOTH"):
            raise UsageError(f"side must be LEFT, RIGHT or BOTH, not {side!r}")
        self.expression = expression
        self.amount = float(amount)
        self.side = side
        self.map_file = map_file
        self.duration_s = duration_s

    def describe(self) -> str:
        return f"face {self.expression!r}"

    def bind(self, rig, report) -> FaceBinding | None:
        face = face_channels(rig, self.map_file)
        if self.amount < 0:
            report(f"face {self.expression!r}: a negative amount ({self.amount:g}) is not shown; its size is used")
        try:
            targets = expression_targets(self.expression, face, min(abs(self.amount), 1.0), direct=self.side == "BOTH")
        except UsageError as exc:
            report(f"face: {exc}; not shown")
            return None
        if self.side != "BOTH":
            targets = {t: w for t, w in targets.items() if target_side(t) in (None, self.side)}
        targets = {t: w for t, w in targets.items() if w > 0.0}
        columns = [(rig.morph_index[t], w) for t, w in targets.items() if t in rig.morph_index]
        joint_offsets, shifts = self._joint_offsets(rig, face, targets, report)
        if not columns and not joint_offsets:
            report(f"face {self.expression!r}: the character has no face channel for it; not shown")
            return None
        joints = sorted(joint_offsets)
        moved = sorted(shifts)
        return FaceBinding(columns=np.array([c for c, _ in columns], dtype=np.int64), values=np.array([w for _, w in columns]),
                           joints=np.array(joints, dtype=np.int64),
                           offsets=np.array([joint_offsets[j] for j in joints]).reshape(len(joints), 4),
                           moved=np.array(moved, dtype=np.int64), shifts=np.array([shifts[j] for j in moved]).reshape(len(moved), 3))

    @staticmethod
    def _joint_offsets(rig, face, targets: dict, report) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
        """Joint index -> local rotation offset (x, y, z, w) from rest, and joint index -> local translation
        offset (3,) metres from rest, for face poses (SmartBody's move brows and lips by both) and the jaw among
        ``targets``."""
        sk = rig.skeleton
        offsets: dict[int, np.ndarray] = {}
        shifts: dict[int, np.ndarray] = {}
        poses = [t for t in targets if t in face.poses]
        if poses:
            try:
                pose_face = PoseFace.load(sk, face.poses, poses)
            except InfuseError as exc:
                report(f"face poses cannot be read ({exc}); not shown")
                pose_face = None
            if pose_face is not None and len(pose_face.joints):
                rotations, translations = pose_face.blend(np.array([[targets[p] for p in poses]]), [[(p, 1.0)] for p in poses])
                for m, j in enumerate(pose_face.joints):
                    offsets[int(j)] = quat.multiply(quat.conjugate(sk.rest_rotations[j]), rotations[0, m])
                    shift = translations[0, m] - sk.rest_translations[j]
                    if np.abs(shift).max() > 1e-7:
                        shifts[int(j)] = shift
        if face.jaw is not None and face.jaw in targets:
            rig_jaw = JawRig.from_skeleton(sk, face.jaw)
            rotation = rig_jaw.rotations(np.array([targets[face.jaw]]), np.radians(LipSyncSettings().jaw_max_angle_deg))[0]
            j = sk.index[face.jaw]
            offsets[j] = quat.multiply(offsets.get(j, quat.identity()), quat.multiply(quat.conjugate(sk.rest_rotations[j]), rotation))
        return offsets, shifts

    def evaluate_one(self, job, block) -> None:
        b: FaceBinding | None = job.binding
        if b is None:
            return
        n = len(job.local_times)
        if b.columns.size:
            job.pose.set_morphs(b.columns, np.broadcast_to(b.values, (n, len(b.values))), job.weight, job.mode)
        if b.joints.size:
            job.pose.set_rotations(b.joints, np.broadcast_to(b.offsets, (n,) + b.offsets.shape), job.weight, job.mode)
        if b.moved.size:
            job.pose.set_translations(b.moved, np.broadcast_to(b.shifts, (n,) + b.shifts.shape), job.weight, job.mode)


def speech_from_bml(parameters: dict, runtime, character: str, activation=None) -> Speech | None:
    """A :class:`Speech` from a BML ``<speech>`` activation played on a runtime alone. When the scheduler
    timed it with a TTS engine its phonemes come with the activation (``parameters["tts"]``); otherwise
    the text is synthesized with the default engine. Empty speech plays nothing."""
    text = (parameters.get("text") or "").strip()
    if not text:
        return None
    details = parameters.get("tts") or {}
    if details.get("phonemes"):
        utterance = Utterance(text, float(parameters["duration_s"]), [tuple(p) for p in details["phonemes"]],
                              [tuple(w) for w in details.get("words", ())], dict(parameters.get("marks_s") or {}))
    else:
        from infuse.speech import tts_engine

        voice = parameters.get("voice")
        utterance = tts_engine(None, **({"voice": voice} if voice else {})).synthesize(text)
    return Speech(utterance, fps=runtime.fps)


def face_from_bml(parameters: dict, runtime, character: str, activation=None, map_file=None) -> FaceExpression:
    """A :class:`FaceExpression` from a BML face activation (``kind`` ``"lexeme"`` or ``"facs"``) on the face
    channels ``map_file`` declares; it blends in from start to attackPeak and out from relax to end."""
    amount = float(parameters.get("amount", 0.5))
    if parameters.get("kind") == "facs":
        controller = FaceExpression(f"AU{int(parameters['au'])}", amount, parameters.get("side"), map_file=map_file)
    else:
        controller = FaceExpression(amount=amount, lexeme=str(parameters.get("lexeme") or ""), map_file=map_file)
    if activation is not None:
        peak, relax = activation.time("attackPeak"), activation.time("relax")
        if peak is not None:
            controller.blend_in_s = max(peak - activation.start, 0.0)
        if relax is not None and not activation.persistent:
            controller.blend_out_s = max(activation.end - relax, 0.0)
    return controller
