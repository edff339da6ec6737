"""A scene: characters and objects, BML in, animation, audio and feedback out.

::

    from infuse.scene import Scene

    scene = Scene(fps=30)
    scene.add_character("Xbot.glb", name="bob", position=(0, 0, 0), facing="ann")
    scene.add_character("avatar.glb", name="ann", position=(0, 0, 2.5), facing="bob")
    scene.add_object("cup", (0.35, 1.0, 1.9), size=0.08)
    scene.on("warningFeedback", print)
    scene.nod("bob", at=2.0)                       # builder calls write BML, like scene.bml(...)
    scene.say("ann", 'Hello <sync id="tm1"/>Bob!', at=0.5)
    scene.bml("bob", '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">'
                     '<head id="h1" lexeme="NOD" stroke="0.4"/></bml>', at=1.0)
    scene.run()                                    # to the end of everything scheduled (or run(seconds), step())
    scene.export("ann", "ann.glb")                 # ann.glb (mesh, clip, morph tracks) and ann.wav
    scene.render("scene.png", strip=6)             # a preview: characters, objects, lines of sight

Time is global seconds from 0; frame ``i`` is at ``i / fps``. ``bml`` schedules a document's blocks at
``at`` (default: now, the time of the next frame) and realizes their behaviours at once as runtime
activities at their global times (:mod:`infuse.scene.realize`); ``run`` evaluates frames and delivers
the BML feedback (blockProgress, syncPointProgress) up to the last frame evaluated. Warnings
(warningFeedback) are delivered when a block is submitted, and printed to stderr unless ``quiet``.
"""
from __future__ import annotations

import itertools
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from .. import quaternions as quat
from ..asset import Asset, Character
from ..bml import BmlDocument, Scheduler, WarningFeedback, parse_bml, parse_bml_file
from ..bml import builder
from ..bml.builder import BuilderCalls
from ..bml.model import BEHAVIOR_DEGRADED, CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from ..config import held_config
from ..errors import InfuseError, UsageError
from ..runtime import Runtime
from ..runtime.rig import Rig
from .realize import realize
from .speech import SpeechCache, mix, utterance_samples, write_wav
from .stage import SceneStage


@dataclass
class SceneCharacter:
    """A character of a scene: its runtime name, the :class:`~infuse.Character` (asset, mapping and clips), the
    file it came from, its map file (joint and face channels), behaviour packs, voice, the
    :class:`~infuse.packs.Infusion` of its packs, the activities it idles with, and where its last walk ends
    ((x, z) metres)."""

    name: str
    character: Character
    source: Path | None = None
    map_file: Path | None = None
    packs: tuple[str, ...] = ()
    voice: str | None = None
    infusion: object = None
    idle: dict = field(default_factory=dict)
    destination: tuple | None = None


@dataclass(frozen=True)
class SceneObject:
    """A thing in the scene: ``position`` (3,) metres of its centre, ``size`` metres across."""

    name: str
    position: tuple[float, float, float]
    size: float = 0.1


@dataclass
class _Spoken:
    """An utterance a character says: when, cut where (an interruption), and the activity playing it."""

    start_s: float
    stop_s: float | None
    utterance: object
    activity: object


class Scene(BuilderCalls):
    """Characters, objects and BML, realized by the layered runtime (see the module doc).

    - ``fps``: frames per second of the animation.
    - ``tts``: the TTS engine name (``"espeak"``) or an engine object; ``tts_settings`` its settings
      (``voice``, ``rate``...). Speech is timed, lip-synced and heard from the same synthesis.
    - ``idle``: start the idle defaults on every character (the installed controllers that declare
      themselves such, :attr:`~infuse.plugin_types.ControllerFactory.idle`; BML can change them).
    - ``seed``: makes blinks and saccades repeatable (each character draws its own).
    - ``quiet``: do not print warningFeedback to stderr (callbacks still get it).
    - ``pack_cache``: a folder where infused behaviour packs are cached (next loads are instant).
    - ``generators``: BML generators on for every block (``("nonverbal",)``: gestures, nods and looks
      from speech); a block turns one on or off itself with ``infuse:NAME="true"|"false"``. ``seed`` makes
      their choices repeatable too.
    """

    def __init__(self, fps: float = 30.0, *, tts="espeak", tts_settings: dict | None = None, idle: bool = True,
                 seed: int = 0, quiet: bool = False, pack_cache=None, block_frames: int = 150,
                 generators: Iterable[str] = ()):
        self.runtime = Runtime(fps, block_frames=block_frames, report=self._note)
        self.fps = self.runtime.fps
        self.idle = bool(idle)
        self.seed = int(seed)
        self.pack_cache = pack_cache
        self._scheduling: str | None = None
        self.speech = SpeechCache(tts, tts_settings, voice_of=self._voice, warn=self._speech_warning)
        self.scheduler = Scheduler(speech_timer=self.speech, clip_timing=self._clip_timing, locate=self.locate,
                                   generators=tuple(generators), names=self._names, seed=self.seed)
        self.feedback = self.scheduler.feedback
        self.characters: dict[str, SceneCharacter] = {}
        self.objects: dict[str, SceneObject] = {}
        self.targets: set[str] = set()
        self.activities: dict[tuple[str, str], object] = {}
        self._spoken: dict[str, list[_Spoken]] = {}
        self._interrupted: set[tuple[str, str]] = set()
        self.stage = SceneStage(self)
        self._recorder = None
        self._realizing = None
        self._realize_notes: list[str] = []
        self._ids = itertools.count(1)
        self._points = itertools.count(1)
        self._made_points: set[str] = set()  # the point targets the builder named
        self._free_points: list[str] = []  # those of them nothing refers to any more, to reuse
        self._facing_later: dict[str, tuple] = {}  # character -> (name it faces, character, mapping, position)
        if not quiet:
            self.feedback.subscribe(_print_warning, kinds=["warningFeedback"])

    # -- the cast -------------------------------------------------------------------------------------
    def add_character(self, source, name: str | None = None, *, position=(0.0, 0.0, 0.0), facing=None,
                      packs: Iterable[str] = (), map=None, mapper: str | None = None, voice: str | None = None,
                      idle: bool | None = None, format: str | None = None, units: str | None = None,
                      up_axis: str | None = None) -> str:
        """Add a character and return its name.

        ``source``: a file (any installed reader), an :class:`~infuse.Asset` or an :class:`~infuse.Character`.
        It is mapped to the canonical joints (``mapper``, default the heuristic one; ``map``: a map file
        whose entries win, and whose ``"face"`` entry declares face channels) and infused with ``packs``
        (behaviour packs, when installed). ``position`` (metres) is where it stands; ``facing`` which way
        its front looks: degrees about +Y (0 = +Z, 90 = +X), a point (x, z) or (x, y, z), or the name of
        a character or object (default: as in its file). ``voice``: its TTS voice. ``idle``: its idle defaults
        (default: the scene's ``idle``). ``format``, ``units``, ``up_axis``: reader options.
        """
        from .. import fileio
        from ..mapping import map_skeleton

        path = None
        if isinstance(source, Character):
            character = source
            asset = source.asset
        elif isinstance(source, Asset):
            asset, character = source, None
        else:
            path = Path(source)
            options = {k: v for k, v in (("units", units), ("up_axis", up_axis)) if v is not None}
            asset = fileio.load(path, format=format, **options)
            character = None
        name = name or (character.name if character is not None else (asset.path.stem if asset.path else "character"))
        self._check_new_name(name)
        map_file = Path(map) if map is not None else None
        if character is None or character.mapping is None or map is not None or mapper is not None:
            mapping = map_skeleton(asset, mapper=mapper, saved_map=map_file)
        else:
            mapping = character.mapping
        character = Character(name, asset, mapping, dict(character.clips) if character is not None else {})
        packs = (packs,) if isinstance(packs, str) else tuple(packs)
        infusion = self._infuse(character, packs) if packs else None
        position = _point(position, "position")
        heading = self._heading(character, mapping, position, facing, waiting=name)
        self.runtime.add_character(character, name, mapping, position, heading)
        entry = SceneCharacter(name, character, path or asset.path, map_file, packs, voice, infusion)
        self.characters[name] = entry
        self._start_base(name)
        if self.idle if idle is None else idle:
            self._start_idle(entry, len(self.characters) - 1)
        self._record_objects()
        self._face_waiting()
        return name

    def add_object(self, name: str, position, size: float = 0.1) -> str:
        """Add an object (something to look at, walk to or take) at ``position`` (x, y, z) metres, ``size``
        metres across; returns its name."""
        self._check_new_name(name)
        if not (np.isfinite(size) and size > 0):
            raise UsageError(f"object {name!r}: size must be a positive number of metres")
        point = _point(position, f"object {name!r} position")
        self.objects[name] = SceneObject(name, tuple(float(v) for v in point), float(size))
        self.runtime.add_target(name, point)
        self._record_objects()
        self._face_waiting()
        return name

    def _record_objects(self) -> None:
        """Start recording where the objects are (they move when characters carry them), once there are
        objects and a character to run the recorder on."""
        if self._recorder is None and self.objects and self.characters:
            from .objects import ObjectRecorder, ObjectsBefore

            self._recorder = ObjectRecorder(self)
            first = next(iter(self.characters))
            self.runtime.activate(first, ObjectsBefore(self._recorder), self.time)
            self.runtime.activate(first, self._recorder, self.time)

    def note_object_move(self, name: str, at_s: float) -> None:
        """Object ``name`` is picked up or put down at ``at_s`` seconds (for :meth:`object_track`)."""
        if self._recorder is not None:
            self._recorder.switch(name, at_s)

    def object_track(self, name: str):
        """(F, 3) positions of object ``name`` at every frame evaluated so far, metres."""
        if name not in self.objects:
            raise UsageError(f"no object {name!r} in the scene; objects: {', '.join(self.objects) or 'none'}")
        if self._recorder is None:
            return np.broadcast_to(np.asarray(self.objects[name].position), (self.runtime.frame, 3)).copy()
        return self._recorder.track(name, self.runtime.frame)

    def add_target(self, name: str, target) -> str:
        """Name a target that is not an object: a moving point (an (F, 3) track at the scene's frame rate, a
        function of time) or ``"character:joint"``; BML and the builder can then refer to it by name."""
        self._check_new_name(name)
        self.runtime.add_target(name, target)
        self.targets.add(name)
        return name

    def character(self, name: str) -> SceneCharacter:
        """A character of the scene by name (:class:`UsageError` when there is none)."""
        if name not in self.characters:
            raise UsageError(f"no character {name!r} in the scene; characters: {', '.join(self.characters) or 'none'}")
        return self.characters[name]

    def _check_new_name(self, name: str) -> None:
        if not isinstance(name, str) or not name or ":" in name or name != name.strip():
            raise UsageError(f"{name!r} cannot name a scene character or object (non-empty, no ':' or outer spaces)")
        if name in self.characters or name in self.objects or name in self.targets:
            raise UsageError(f"the scene already has something named {name!r}")

    def _heading(self, character: Character, mapping, position: np.ndarray, facing, waiting: str | None = None) -> float:
        """Degrees to turn the character about +Y so its front looks toward ``facing``. A name not in the
        scene yet, before the first frame, makes character ``waiting`` turn when that name is added."""
        if facing is None:
            return 0.0
        if isinstance(facing, str):
            there = self.locate(self.resolve_name(facing))
            if there is None and waiting is not None and self.runtime.frame == 0:
                self._facing_later[waiting] = (facing, character, mapping, position)
                return 0.0
            if there is None:
                raise UsageError(f"facing {facing!r}: no character or object of that name")
            direction = np.asarray(there) - position
        elif np.ndim(facing) == 0:
            yaw = math.radians(float(facing))
            direction = np.array([math.sin(yaw), 0.0, math.cos(yaw)])
        else:
            point = np.asarray(facing, dtype=np.float64).reshape(-1)
            if point.shape not in ((2,), (3,)) or not np.all(np.isfinite(point)):
                raise UsageError(f"facing {facing!r}: expected degrees, a point (x, z) or (x, y, z), or a name")
            point = np.array([point[0], 0.0, point[-1]])
            direction = point - position
        if math.hypot(direction[0], direction[2]) < 1e-9:
            raise UsageError(f"facing {facing!r}: the character stands there; cannot tell which way to face")
        forward = quat.rotate(Rig("probe", character, mapping).body, np.array([0.0, 0.0, 1.0]))
        turn = math.atan2(direction[0], direction[2]) - math.atan2(forward[0], forward[2])
        return math.degrees((turn + math.pi) % (2 * math.pi) - math.pi)

    def _face_waiting(self) -> None:
        """Turn the characters whose facing names something now in the scene."""
        for name, (facing, character, mapping, position) in list(self._facing_later.items()):
            if self.locate(self.resolve_name(facing)) is not None:
                del self._facing_later[name]
                heading = self._heading(character, mapping, position, facing)
                self.runtime.rig(name).rotation = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), math.radians(heading))

    def _check_facing(self) -> None:
        """Before the first frame: every facing names something in the scene."""
        if self._facing_later:
            name, (facing, *_) = next(iter(self._facing_later.items()))
            raise UsageError(f"character {name!r} facing {facing!r}: no character or object of that name")

    def _infuse(self, character: Character, packs: tuple[str, ...]):
        """Infuse ``character`` with behaviour packs: their clips join the character's (``clip`` and
        ``pack/clip``), their blend spaces drive the pack controllers."""
        from ..packs import infuse_character

        infusion = infuse_character(character, list(packs), mapping=character.mapping, cache=self.pack_cache)
        for space in infusion.spaces.values():
            for clip in space.clips.values():
                character.clips.setdefault(clip.name, clip.motion)
                character.clips[f"{space.pack}/{clip.name}"] = clip.motion
        return infusion

    def _start_base(self, name: str) -> None:
        """The base layer under everything: the idle clip of a behaviour pack, looping; else, for a character
        whose rest pose does not stand (every bone along one axis), the first frame of its clip, the pose its
        axes were read from; else the rest pose."""
        from ..runtime import Clip

        rig = self.runtime.rig(name)
        idle = self.find_clip(name, "idle")
        if idle is not None:
            self.characters[name].idle["base"] = self.runtime.activate(name, Clip(idle, loop=True), 0.0)
            return
        if rig.reference == "rest":
            return
        clip = next(m for m in rig.character.asset.motions.values() if m.num_frames and m.skeleton.names == rig.skeleton.names)
        jt = None if clip.joint_translations is None else clip.joint_translations[:1]
        first = clip.replace(local_rotations=clip.local_rotations[:1], root_translations=clip.root_translations[:1],
                             joint_translations=jt, name="reference pose")
        self.runtime.activate(name, Clip(first), 0.0)

    def _start_idle(self, entry: SceneCharacter, index: int) -> None:
        """Start the idle defaults, the installed controllers that declare themselves such
        (:attr:`~infuse.plugin_types.ControllerFactory.idle`), on the ``index``-th character."""
        from .. import registry

        for kind, descriptor in registry.table("controller").items():
            if descriptor.idle is not None:
                settings = descriptor.idle(index, self.seed)
                entry.idle[kind] = self.runtime.activate(entry.name, descriptor.factory(**settings), 0.0)

    def stop_postures(self, name: str, at_s: float) -> None:
        """Stop a character's lasting posture clips at ``at_s`` (a new posture replaces them)."""
        for activity in self.activities.values():
            source = activity.source
            if activity.rig.name == name and source is not None and source.controller in ("posture", "blend") \
                    and activity.end_s is None and activity.start_s < at_s:
                self.runtime.stop(activity, at_s)

    # -- where things are -----------------------------------------------------------------------------
    def resolve_name(self, name: str) -> str:
        """``name`` as the scene spells it (characters and objects match without regard to case; so does the
        character of ``"character:joint"``); unknown names are returned as they are."""
        head, sep, tail = name.partition(":")
        known = {n.lower(): n for n in itertools.chain(self.characters, self.objects, self.targets)}
        return known.get(head.lower(), head) + sep + tail

    def _names(self) -> dict:
        """Name -> ``"character"`` or ``"object"``, for BML generators."""
        return {**{name: "object" for name in self.objects}, **{name: "character" for name in self.characters}}

    def locate(self, name: str):
        """(x, y, z) metres of an object, or where a character stands; None for an unknown name."""
        if name in self.objects:
            return self.objects[name].position
        if name in self.characters:
            entry = self.characters[name]
            if entry.destination is not None:  # where its last walk takes it
                return (entry.destination[0], 0.0, entry.destination[1])
            return tuple(float(v) for v in self.runtime.rig(name).position)
        return None

    def pack_space(self, name: str, kind: str):
        """The :class:`~infuse.packs.BlendSpace` of pack kind ``kind`` the character was
        infused with (the first of its packs), or None."""
        infusion = self.character(name).infusion
        spaces = infusion.spaces.values() if infusion is not None else ()
        return next((s for s in spaces if s.kind == kind), None)

    def find_clip(self, name: str, clip: str):
        """The character's clip called ``clip`` (from its behaviour packs, else its own file; case and a
        ``character@`` prefix ignored), or None."""
        entry = self.character(name)
        pools = [entry.character.clips, entry.character.asset.motions]
        key = clip.lower()
        for pool in pools:
            for label, motion in pool.items():
                if label.lower() == key or label.lower().rsplit("@", 1)[-1] == key.rsplit("@", 1)[-1]:
                    if motion.num_frames and motion.skeleton.names == entry.character.skeleton.names:
                        return motion
        return None

    def _clip_timing(self, clip: str):
        if self._scheduling is None or self._scheduling not in self.characters:
            return None
        motion = self.find_clip(self._scheduling, clip)
        if motion is None:
            return None
        points = {k: float(v) for k, v in motion.sync_points.items() if 0.0 <= float(v) <= motion.duration}
        points.update(start=0.0, end=motion.duration)
        return points

    def _voice(self) -> str | None:
        entry = self.characters.get(self._scheduling) if self._scheduling else None
        return entry.voice if entry is not None else None

    # -- BML ------------------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Seconds evaluated so far: the time of the next frame."""
        return self.runtime.time

    def bml(self, character: str | None, bml, at: float | None = None, *, generated: bool = False):
        """Schedule and realize BML (XML text or bytes, a :class:`~pathlib.Path` to a file, or a parsed document).

        Its blocks play on ``character`` (None: the character each block names) from ``at`` seconds (default:
        now). Returns the block id, or a list of ids for a document with several blocks. Malformed XML raises
        :class:`~infuse.errors.InputError`; everything else it holds becomes warningFeedback. ``generated``:
        the blocks have been through the BML generators already (:meth:`~infuse.bml.Scheduler.generate`, as
        a live scene does ahead, so that their speech is synthesized once); they do not run again.
        """
        if isinstance(bml, Path):
            document = parse_bml_file(bml)
        elif isinstance(bml, (str, bytes)):
            document = parse_bml(bml)
        elif isinstance(bml, BmlDocument):
            document = bml
        else:
            raise UsageError(f"bml() takes XML text, a Path or a parsed document, not {type(bml).__name__}")
        at = self.time if at is None else float(at)
        if not math.isfinite(at):
            raise UsageError("a block's start time must be finite")
        blocks = []
        for block in document.blocks:
            name = character if character is not None else block.character_id
            if name is None:
                raise UsageError(f"block {block.id!r} names no character; pass the character to bml()")
            name = self.resolve_name(name)
            self.character(name)
            blocks.append(block if block.character_id == name else replace(block, character_id=name))
        ids = [block.id for block in blocks]
        with held_config():  # one look at the configuration file for all the block's plugin lookups
            for block in (blocks if generated else [g for b in blocks for g in self.scheduler.generate(b)]):
                self._scheduling = block.character_id
                try:
                    record = self.scheduler.schedule_block(block, at)
                finally:
                    self._scheduling = None
                if at < self.time - 0.5 / self.fps:
                    self.feedback.emit(WarningFeedback(block.id, "IMPOSSIBLE_TO_SCHEDULE",
                                                       f"the block starts at {at:g} s, before the scene's current time "
                                                       f"({self.time:g} s): what falls before now is not shown",
                                                       block.character_id))
                for activation in record.activations:
                    self._realize(activation)
                self._apply_interruptions()
        return ids[0] if len(ids) == 1 else ids

    def _realize(self, activation) -> None:
        self._realizing, self._realize_notes = activation, []
        try:
            activity = realize(self, activation)
        except InfuseError as exc:
            activity = None
            self._realize_notes.append(str(exc))
        finally:
            self._realizing = None
        if activity is not None:
            self.activities[(activation.block, activation.behaviour)] = activity
        for message in self._realize_notes:
            kind = NO_SUCH_TARGET if ("no target or character named" in message or "has no joint" in message) \
                else CANNOT_CREATE_BEHAVIOR if activity is None else BEHAVIOR_DEGRADED
            self.warn(activation, kind, message)

    def _apply_interruptions(self) -> None:
        """Stop the activities of behaviours a later block interrupted (REPLACE, ``bmla:interrupt``)."""
        for record in self.scheduler.take_interrupted():
            for activation in record.activations:
                key = (activation.block, activation.behaviour)
                if activation.stop_s is None or key in self._interrupted:
                    continue
                self._interrupted.add(key)
                activity = self.activities.get(key)
                if activity is not None:
                    self.runtime.stop(activity, activation.stop_s)
                for spoken in self._spoken.get(activation.character, ()):
                    if spoken.activity is activity and activity is not None:
                        spoken.stop_s = activation.stop_s

    @property
    def stagehands(self) -> dict:
        """The helpers the realizing plugins keep in this scene, by key (:meth:`infuse.stage.Stage.stagehand`)."""
        return self.stage.stagehands

    def activate(self, activation, controller_, end_s, **options):
        """Start ``controller_`` for ``activation`` on its character at the activation's start, until ``end_s``."""
        return self.runtime.activate(activation.character, controller_, activation.start, end_s, source=activation,
                                     **options)

    def keep_audio(self, name: str, activation, utterance, activity) -> None:
        """Remember an utterance ``name`` says from the activation's start, for its WAV."""
        self._spoken.setdefault(name, []).append(_Spoken(activation.start, activation.stop_s, utterance, activity))

    def warn(self, activation, kind: str, message: str) -> None:
        """warningFeedback about one behaviour (``block:behaviour``)."""
        self.feedback.emit(WarningFeedback(f"{activation.block}:{activation.behaviour}", kind, message,
                                           activation.character))

    def _note(self, character: str, message: str) -> None:
        if self._realizing is not None:
            self._realize_notes.append(message)
        else:
            self.feedback.emit(WarningFeedback(character, BEHAVIOR_DEGRADED, message, character))

    def _speech_warning(self, message: str) -> None:
        self.feedback.emit(WarningFeedback(self._scheduling or "scene", CANNOT_CREATE_BEHAVIOR, message, self._scheduling))

    def on(self, kinds: str | Iterable[str] | None, callback: Callable) -> Callable[[], None]:
        """Call ``callback(event)`` for feedback of ``kinds`` (``"blockProgress"``, ``"syncPointProgress"``,
        ``"warningFeedback"``, ``"blockPrediction"``; None: all); returns a function that unsubscribes."""
        return self.feedback.subscribe(callback, kinds=[kinds] if isinstance(kinds, str) else kinds)

    # -- the builder (its calls: :class:`~infuse.bml.builder.BuilderCalls`) ----------------------------
    def block_id(self, what: str) -> str:
        """A new block id for the builder: ``what`` and a number no block scheduled so far uses (ids taken
        from several threads differ)."""
        while True:
            block_id = f"{what}{next(self._ids)}"
            if block_id not in self.scheduler.blocks:
                return block_id

    def _submit(self, character: str, what: str, behaviour: str, at, composition: str = "MERGE") -> str:
        character = self.resolve_name(character)
        self.character(character)
        block_id = self.block_id(what)
        return self.bml(character, builder.block(block_id, character, behaviour, composition), at)

    def _target_name(self, target) -> str:
        """A BML target for ``target``: a name (kept), or a point, which becomes a named scene target."""
        if isinstance(target, str):
            return self.resolve_name(target)
        point = _point(target, "target")
        if self._free_points:  # one that no behaviour refers to any more (see :meth:`forget`): it moves here
            name = self._free_points.pop()
            self.runtime.add_target(name, point)
            return name
        name = f"point{next(self._points)}"
        while name in self.characters or name in self.objects or name in self.targets:
            name = f"point{next(self._points)}"
        self._made_points.add(name)
        return self.add_target(name, point)

    def _free_point_targets(self) -> None:
        """Offer the point targets the builder named for reuse once no activity the runtime keeps and no BML
        block the scheduler keeps refers to them."""
        named: set[str] = set()
        sources = itertools.chain((a.source for a in self.runtime.activities),
                                  (a for record in self.scheduler.blocks.values() for a in record.activations))
        for source in sources:
            _strings_in(getattr(source, "parameters", None), named)
        self._free_points = sorted(self._made_points - named, reverse=True)

    # -- evaluation -----------------------------------------------------------------------------------
    @property
    def end_time(self) -> float:
        """When everything scheduled has ended and every stagehand is done, e.g. every walk standing at its target
        (seconds; 0 for an empty scene)."""
        return max([0.0, self.stage.end_s()] + [r.end_s if r.interrupted_at is None else r.interrupted_at
                                                for r in self.scheduler.blocks.values() if not r.failed])

    def run(self, seconds: float | None = None, progress=None) -> None:
        """Evaluate the next ``seconds`` (default: up to the first frame at or after :attr:`end_time`) and
        deliver the feedback up to the last frame; ``progress(frames_done, frames_total)`` is called per
        evaluated block."""
        if seconds is None:
            frames = max(math.ceil(self.end_time * self.fps - 1e-6) + 1 - self.runtime.frame, 0)
        else:
            frames = int(round(float(seconds) * self.fps))
        if frames < 0:
            raise UsageError("run() takes a duration >= 0 seconds")
        self._check_facing()
        done = 0
        while done < frames:
            self.stage.before_block()
            n = self.stage.frames_ahead(min(self.runtime.block_frames, frames - done))
            self.runtime.step(n)
            done += n
            self._deliver()
            if progress is not None:
                progress(done, frames)

    def step(self, frames: int = 1) -> None:
        """Evaluate the next ``frames`` frames and deliver their feedback."""
        frames = int(frames)
        self._check_facing()
        while frames > 0:
            self.stage.before_block()
            n = self.stage.frames_ahead(frames)
            self.runtime.step(n)
            frames -= n
        self._deliver()

    def _deliver(self) -> None:
        last = (self.runtime.frame - 1) / self.fps
        self.scheduler.advance(last + 1e-9)

    def forget(self, keep_s: float) -> None:
        """Keep memory bounded in a scene that runs for hours (a live one): drop the frames evaluated more
        than ``keep_s`` seconds ago (:meth:`motion` and :meth:`audio` then start later), the activities,
        utterances and BML blocks that ended before then (:meth:`~infuse.bml.Scheduler.forget`), and all
        but the last 1,000 feedback events of the log. The point targets the builder named for points given
        as targets, once nothing kept refers to them, are reused for the next such points."""
        before = self.time - float(keep_s)
        self.runtime.forget(keep_s)
        self.scheduler.forget(before)
        self._interrupted = {key for key in self._interrupted if key[0] in self.scheduler.blocks}
        for key, activity in list(self.activities.items()):
            if activity.end_s is not None and activity.end_s < before:
                del self.activities[key]
        self._free_point_targets()
        for name, spoken in self._spoken.items():
            self._spoken[name] = [s for s in spoken if s.start_s + s.utterance.duration_s >= before
                                  and (s.stop_s is None or s.stop_s >= before)]
        del self.feedback.log[:-1000]

    # -- results --------------------------------------------------------------------------------------
    def motion(self, character: str, clip: str = "scene"):
        """The character's animation so far, a :class:`~infuse.Motion` on its own skeleton (placed in the scene)."""
        return self.runtime.motion(self.character(character).name, clip)

    def audio(self, character: str) -> tuple[np.ndarray, int] | None:
        """The character's speech as one mono int16 track as long as its animation so far, and its rate;
        None when it has said nothing."""
        pieces = []
        for spoken in self._spoken.get(self.character(character).name, ()):
            samples, rate = utterance_samples(spoken.utterance)
            pieces.append((spoken.start_s, spoken.stop_s, samples, rate))
        if not pieces:
            return None
        return mix(pieces, self.runtime.frame / self.fps)

    def export(self, character: str, path, clip: str = "scene", audio: bool = True, **options) -> list[Path]:
        """Write the character with its animation so far as one clip (``path``: .glb keeps its mesh and
        carries the morph-weight tracks; .bvh and any other installed writer work too), and its speech
        beside it as ``<stem>.wav`` (the WAV the viewer plays with the clip). Returns the files written."""
        from .. import fileio

        entry = self.character(character)
        path = Path(path)
        written = [fileio.save(self.runtime.export(entry.name, clip), path, **options)]
        track = self.audio(entry.name) if audio else None
        if track is not None:
            written.append(write_wav(path.with_suffix(".wav"), *track))
        return written

    def render(self, path, **options) -> Path:
        """A preview of the scene so far (see :func:`infuse.scene.preview.render_scene`)."""
        from .preview import render_scene

        return render_scene(self, path, **options)


def _strings_in(value, found: set[str]) -> None:
    """Add the strings in ``value`` (BML parameters: plain data, nested in dicts, lists and tuples) to ``found``."""
    if isinstance(value, str):
        found.add(value)
    elif isinstance(value, dict):
        for item in value.values():
            _strings_in(item, found)
    elif isinstance(value, (list, tuple)):
        for item in value:
            _strings_in(item, found)


def _point(value, what: str) -> np.ndarray:
    point = np.asarray(value, dtype=np.float64).reshape(-1)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        raise UsageError(f"{what} must be three finite numbers (x, y, z) in metres, got {value!r}")
    return point


def _print_warning(event) -> None:
    print(f"infuse: warning: {event.id}: {event.description}", file=sys.stderr)
