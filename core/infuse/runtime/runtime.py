"""The runtime: characters, the controllers active on them, and evaluation frame block by frame block.

::

    rt = Runtime(fps=30)
    rt.add_character(character)                      # an infuse.Character (mapped on the way if needed)
    rt.activate(character, Clip(walk), 0.0)           # a base layer
    rt.activate(character, nod, 1.0, end_s=4.0, blend_in_s=0.3)
    rt.run(5.0)                                       # or rt.step() for one frame
    motion = rt.motion(character)                     # a Motion on the character's own skeleton, with
                                                      # the morph weights any controller wrote

Frame ``i`` is at ``i / fps`` seconds. Evaluation runs block by block (up to ``block_frames`` frames
at once): each character's pose starts at its rest pose, then activities apply in order of layer,
priority and activation, each controller class batched over all characters (see
:mod:`infuse.runtime.controller`).
"""
from __future__ import annotations

import sys
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from typing import Any, Callable, ClassVar

import numpy as np

from .. import quaternions as quat
from ..asset import Asset, Character
from ..errors import UsageError
from ..grounding import on_ground
from ..motion import Motion
from .controller import Block, Controller, Job, Jobs
from .layers import Layer, Mode, blend_weights, blend_weights_of
from .pose import PoseTable, TableLayout
from .rig import Rig, State


@dataclass(eq=False)
class Activity:
    """A controller active on one character.

    ``start_s`` / ``end_s``: global seconds (``end_s`` None: until stopped); the weight ramps up over
    ``blend_in_s`` from the start and down over ``blend_out_s`` to 0 at the end. ``binding`` is
    what the controller prepared for the character; ``state`` persists between blocks.
    ``source`` is what it was made from (a BML activation, if any). A controller keeps its own typed
    state there through :meth:`state_of`. ``settle_s``: how long after its end it is still evaluated
    (None: its controller's ``settle_s``; 0 once :meth:`Runtime.end` ended it).
    """

    id: int
    runtime: Any
    rig: Rig
    controller: Controller
    start_s: float
    end_s: float | None
    blend_in_s: float
    blend_out_s: float
    priority: int
    mode: Mode
    binding: Any = None
    state: dict = field(default_factory=dict)
    source: Any = None
    settle_s: float | None = None

    #: Counts the assignments to any activity's fields the runtime schedules by (:data:`_SCHEDULE`):
    #: the runtime works out which activities play, their groups and their weights' shape again only
    #: when it (or the list of activities) has changed.
    changes: ClassVar[int] = 0

    def __setattr__(self, name: str, value) -> None:
        object.__setattr__(self, name, value)
        if name in _SCHEDULE:
            Activity.changes += 1

    @property
    def character(self) -> str:
        return self.rig.name

    def state_of(self, kind: type[State]) -> State:
        """The activity's state of class ``kind`` (made by ``kind()`` the first time it is asked for, kept in
        ``state`` under the class): what its controller carries from one block to the next."""
        value = self.state.get(kind)
        if value is None:
            value = self.state[kind] = kind()
        return value

    @property
    def layer(self) -> Layer:
        return self.controller.layer

    def weights(self, times) -> np.ndarray:
        """(F,) blend weights at ``times`` seconds."""
        return blend_weights(times, self.start_s, self.end_s, self.blend_in_s, self.blend_out_s)

    @property
    def settled_s(self) -> float:
        """Global seconds after which it is no longer evaluated: its end and its settle (inf: no end yet)."""
        if self.end_s is None:
            return np.inf
        return self.end_s + (self.controller.settle_s if self.settle_s is None else self.settle_s)

    def active_between(self, t0: float, t1: float) -> bool:
        """Whether frames between ``t0`` and ``t1`` (seconds) need this activity."""
        if self.start_s > t1 + 1e-9:
            return False
        return self.settled_s >= t0 - 1e-9


#: The fields of an :class:`Activity` that say when and where among the others it plays.
_SCHEDULE = frozenset(("rig", "controller", "start_s", "end_s", "blend_in_s", "blend_out_s", "priority", "settle_s"))


class _Schedule:
    """The runtime's activities as arrays, for finding those a block needs and their weights with a few
    numpy calls: ``starts``, ``settled`` (:attr:`Activity.settled_s`) and (N, 4) ``timing`` (start, end
    (inf: none), blend in, blend out) seconds; ``on_from`` / ``on_until``: the span of times whose
    weight is certainly exactly 1 (past the blend-in, before the blend-out, with a margin over
    rounding); per set of active activities (their indices), their groups (:meth:`groups`)."""

    def __init__(self, activities: list[Activity]):
        self.activities = activities
        self.key = (Activity.changes, len(activities))
        timing = np.array([value for a in activities for value in (a.start_s, np.inf if a.end_s is None else a.end_s,
                                                                   a.blend_in_s, a.blend_out_s)], dtype=np.float64).reshape(-1, 4)
        self.timing = timing
        self.starts = timing[:, 0]
        start, end, blend_in, blend_out = timing.T
        # Activity.settled_s of each: inf without an end, which its settle leaves as it is
        self.settled = end + np.array([a.controller.settle_s if a.settle_s is None else a.settle_s for a in activities],
                                      dtype=np.float64)
        self.on_from = np.where(blend_in > 0, start + blend_in, start) + 1e-9
        self.on_until = np.where(blend_out > 0, end - blend_out, end) - 2e-9
        self._groups: dict[bytes, list[tuple[tuple, list[tuple[Activity, str]], np.ndarray, tuple]]] = {}
        self._members: list[tuple[tuple, tuple[Activity, str]]] | None = None  # per activity: its group, itself and its character

    def current(self, activities: list[Activity]) -> bool:
        """Whether these arrays still describe ``activities`` (the runtime's list)."""
        return activities is self.activities and self.key == (Activity.changes, len(activities))

    def groups(self, active: np.ndarray) -> list[tuple[tuple, list[tuple[Activity, str]], np.ndarray, tuple]]:
        """The groups of the activities of indices ``active`` in evaluation order (by layer, priority and
        first activation): (layer, priority, controller class) keys with their activities and
        characters' names, their rows among ``active`` and their ids. Between two classes that may read
        any character (:attr:`Controller.own_characters_only` False), the groups of the others are
        evaluated as :func:`_calls` joins them."""
        key = active.tobytes()
        found = self._groups.get(key)
        if found is None:
            if self._members is None:
                self._members = [((int(a.layer), a.priority, type(a.controller)), (a, a.rig.name)) for a in self.activities]
            chosen = [self._members[k] for k in active.tolist()]
            groups: dict[tuple, list[int]] = {}
            for row, (group, _) in enumerate(chosen):
                groups.setdefault(group, []).append(row)
            order = sorted(groups, key=lambda g: (g[0], g[1], chosen[groups[g][0]][1][0].id))
            calls: list[tuple[tuple, list[int]]] = []
            start = 0
            for end in range(len(order) + 1):
                if end == len(order) or not order[end][2].own_characters_only:
                    calls += _calls([(g, groups[g]) for g in order[start:end]], [name for _, (_, name) in chosen])
                    if end < len(order):
                        calls.append((order[end], groups[order[end]]))
                    start = end + 1
            seen: dict[tuple, int] = {}
            found = self._groups[key] = []
            for g, rows in calls:  # a class called twice for one priority keeps a memo per call
                seen[g] = seen.get(g, -1) + 1
                found.append((g if not seen[g] else g + (seen[g],), [chosen[row][1] for row in rows], np.array(rows),
                              tuple(chosen[row][1][0].id for row in rows)))
        return found


def _calls(groups: list[tuple[tuple, list[int]]], names: list[str]) -> list[tuple[tuple, list[int]]]:
    """The calls evaluating ``groups`` (in evaluation order, keys and rows; ``names``: each row's
    character) of classes touching only their own characters: each call one class and layer, for the
    next activities of as many characters as can go together, each character's activities in their
    order. The class called next is one whose waiting activities are all next for their characters,
    else the one whose call costs least (:attr:`Controller.call_ms`), so that the costlier wait for more
    to join them; the earliest first among equals. A walk of priority 4 of one character, over its idle
    clip of priority 3, goes with another character's walk of priority 2 whose settled idle clip of
    priority 3 is over it: the clips in two calls, the walks in one."""
    chains: dict[str, list[tuple[int, list[int]]]] = {}  # per character, its rows of each group in order
    for n, (_, rows) in enumerate(groups):
        for row in rows:
            chain = chains.setdefault(names[row], [])
            if chain and chain[-1][0] == n:
                chain[-1][1].append(row)
            else:
                chain.append((n, [row]))
    kind = [(key[0], key[2]) for key, _ in groups]
    waiting = Counter(kind[n] for chain in chains.values() for n, _ in chain)
    calls = []
    while chains:
        heads: dict[tuple, list[tuple[int, list[int], str]]] = {}
        for name, chain in chains.items():
            n, rows = chain[0]
            heads.setdefault(kind[n], []).append((n, rows, name))
        chosen = max(heads, key=lambda k: (len(heads[k]) == waiting[k], -k[1].call_ms, -min(h[0] for h in heads[k])))
        taken = sorted(heads[chosen])
        calls.append((groups[taken[0][0]][0], [row for _, rows, _ in taken for row in rows]))
        waiting[chosen] -= len(taken)
        for _, _, name in taken:
            chains[name].pop(0)
            if not chains[name]:
                del chains[name]
    return calls


@dataclass(frozen=True, slots=True)
class _Evaluated:
    """One evaluated block's arrays, every character side by side, as its :class:`PoseTable` held them:
    ``local_rotations`` (F, N, 4), ``root_translations`` (F, C, 3), ``morph_weights`` (F, M) on ``layout``.
    Kept without the table's per-character :class:`~infuse.runtime.pose.PoseBlock` objects: the fewer
    objects a runtime keeps block after block, the shorter the garbage collector's passes over them."""

    layout: TableLayout
    frames: int
    local_rotations: np.ndarray
    root_translations: np.ndarray
    morph_weights: np.ndarray


@dataclass
class _Track:
    """One character's output so far: per-block arrays."""

    rig: Rig
    rotations: list = field(default_factory=list)
    roots: list = field(default_factory=list)
    translations: list = field(default_factory=list)
    morphs: list = field(default_factory=list)
    morph_written: np.ndarray | None = None


class Runtime:
    """Evaluates the controllers of many characters at ``fps`` frames per second.

    ``block_frames``: most frames evaluated at once by :meth:`run`; ``report``: called as
    ``report(character, message)`` for what a character lacks (default: one stderr line per message).
    """

    def __init__(self, fps: float = 30.0, block_frames: int = 150, report: Callable[[str, str], None] | None = None):
        if not (np.isfinite(fps) and fps > 0):
            raise UsageError(f"fps must be positive, got {fps}")
        self.fps = float(fps)
        self.block_frames = max(1, int(block_frames))
        self.frame = 0
        self.activities: list[Activity] = []
        self.notes: list[tuple[str, str]] = []
        self._report = report
        self._tracks: dict[str, _Track] = {}
        self._speech: dict[str, list[tuple[float, float]]] = {}
        self._targets: dict = {}
        self._next_id = 0
        self._layout: TableLayout | None = None  # where each character sits in a block's PoseTable
        self._tables: list[_Evaluated] = []  # the blocks' arrays, oldest first (as the tracks' arrays, up to forget)
        self._memos: dict[tuple, list] = {}  # per group of jobs: what its controller class memoized
        self._schedule: _Schedule | None = None  # the activities as arrays, while they stay as they are
        self._placed: tuple[TableLayout, list, tuple] | None = None  # what cast_poses places, while it stays
        self._speakers: list[Activity] = []  # the activities whose controller speaks
        self._resolved: dict[str, Any] = {}  # target names resolved since the last target or character added
        #: Counts the targets and characters added: what :meth:`target` resolves a name to changes only with it.
        self.targets_version = 0
        #: The characters some evaluated frame of which places joints by translation (what
        #: :meth:`last_translations` can return frames of; for the others it returns None).
        self.translated: set[str] = set()
        #: Seconds of the evaluating thread's CPU time spent in the controllers (their jobs handed over
        #: included), over every block so far: what evaluation costs beside the runtime's own bookkeeping.
        self.controllers_cpu_s = 0.0

    # -- characters ------------------------------------------------------------------------------------
    def add_character(self, character, name: str | None = None, mapping=None, position=(0.0, 0.0, 0.0),
                      heading_deg: float = 0.0) -> str:
        """Add a character (an :class:`~infuse.Character` or an :class:`~infuse.Asset`); returns its name.

        The mapping is ``mapping``, else the character's own, else the default mapper's. The character
        stands at ``position`` (metres), turned by ``heading_deg`` about +Y (positive: its front turns
        toward +X); its clips and controllers move it from there.
        """
        if isinstance(character, Asset):
            stem = character.path.stem if character.path is not None else "character"
            character = Character(stem, character)
        if not isinstance(character, Character):
            raise UsageError(f"add_character takes an infuse.Character or Asset, not {type(character).__name__}")
        name = name or character.name
        if name in self._tracks:
            raise UsageError(f"a character named {name!r} is already in the runtime")
        if mapping is None:
            mapping = character.mapping
        if mapping is None:
            from ..mapping import map_skeleton

            mapping = map_skeleton(character.asset)
        position = np.asarray(position, dtype=np.float64).reshape(3)
        if not (np.all(np.isfinite(position)) and np.isfinite(heading_deg)):
            raise UsageError("a character's position and heading must be finite")
        rotation = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.radians(heading_deg))
        rig = Rig(name, character, mapping, position, rotation)
        self._tracks[name] = _Track(rig)
        self._resolved.clear()
        self.targets_version += 1
        for note in rig.notes:
            self.report(name, note)
        return name

    @property
    def characters(self) -> tuple[str, ...]:
        return tuple(self._tracks)

    def rig(self, character) -> Rig:
        """The :class:`Rig` of a character (its name, or the Character added)."""
        return self._track(character).rig

    def _track(self, character) -> _Track:
        name = character if isinstance(character, str) else getattr(character, "name", None)
        if name not in self._tracks:
            raise UsageError(f"no character {name!r} in the runtime; added: {', '.join(self._tracks) or 'none'}")
        return self._tracks[name]

    def report(self, character: str, message: str) -> None:
        """Report something about a character once: kept in :attr:`notes` and printed (or passed to ``report``)."""
        if (character, message) in self.notes:
            return
        self.notes.append((character, message))
        if self._report is not None:
            self._report(character, message)
        else:
            print(f"infuse: warning: {character}: {message}", file=sys.stderr)

    # -- activities ------------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Seconds evaluated so far (the time of the next frame)."""
        return self.frame / self.fps

    def activate(self, character, controller: Controller, start_s: float | None = None, end_s: float | None = None, *,
                 duration_s: float | None = None, blend_in_s: float | None = None, blend_out_s: float | None = None,
                 priority: int | None = None, mode: Mode | str | None = None, source: Any = None) -> Activity:
        """Play ``controller`` on ``character`` from ``start_s`` (default: now) to ``end_s`` (or for
        ``duration_s``; neither: for the controller's own ``duration_s``, or until :meth:`stop`).
        Unset options take the controller's defaults."""
        if not isinstance(controller, Controller):
            raise UsageError(f"activate takes a runtime Controller, not {type(controller).__name__}")
        track = self._track(character)
        start = self.time if start_s is None else float(start_s)
        if duration_s is not None:
            if end_s is not None:
                raise UsageError("give end_s or duration_s, not both")
            end_s = start + float(duration_s)
        elif end_s is None and controller.duration_s is not None:
            end_s = start + float(controller.duration_s)
        if end_s is not None and end_s < start:
            raise UsageError(f"activity ends ({end_s:g} s) before it starts ({start:g} s)")
        blend_in = controller.blend_in_s if blend_in_s is None else float(blend_in_s)
        blend_out = controller.blend_out_s if blend_out_s is None else float(blend_out_s)
        if blend_in < 0 or blend_out < 0:
            raise UsageError("blend times must be >= 0 seconds")
        rig = track.rig
        binding = controller.bind(rig, lambda message: self.report(rig.name, message))
        activity = Activity(self._next_id, self, rig, controller, start, None if end_s is None else float(end_s),
                            blend_in, blend_out, controller.priority if priority is None else int(priority),
                            Mode(mode) if mode is not None else controller.mode, binding, source=source)
        self._next_id += 1
        self.activities.append(activity)
        if controller.speaks:
            self._speakers.append(activity)
        return activity

    def stop(self, activity: Activity, at_s: float | None = None, blend_out_s: float | None = None) -> None:
        """Stop an activity: it blends out from ``at_s`` (default: now) over ``blend_out_s``."""
        at = self.time if at_s is None else float(at_s)
        if blend_out_s is not None:
            activity.blend_out_s = float(blend_out_s)
        end = max(at, activity.start_s) + activity.blend_out_s
        activity.end_s = end if activity.end_s is None else min(activity.end_s, end)

    def end(self, activity: Activity, at_s: float | None = None) -> None:
        """End an activity at ``at_s`` (default: now; an earlier end stays) at once, with no blend-out and
        no settle: no frame after it evaluates it. For an activity whose weight is 0 from then on anyway
        and that keeps nothing going that later frames need (one that another of its kind has taken over
        from); a blend-out is :meth:`stop`."""
        at = max(self.time if at_s is None else float(at_s), activity.start_s)
        if activity.end_s is None or activity.end_s > at:
            activity.end_s, activity.blend_out_s = at, 0.0
        activity.settle_s = 0.0

    def add_target(self, name: str, target) -> None:
        """Name a target (a scene object: a point, a track, a function of time...) for gazes and BML."""
        from .targets import as_target

        self._targets[str(name)] = as_target(target)
        self._resolved.clear()
        self.targets_version += 1

    def target(self, name: str):
        """The target called ``name``: one added with :meth:`add_target`, ``"character:joint"``, or a
        character (its face); :class:`UsageError` otherwise."""
        from .targets import JointTarget, as_target

        found = self._resolved.get(name)
        if found is not None:
            return found
        if name in self._targets:
            found = self._targets[name]
        elif ":" in name:
            found = as_target(name)
        elif name in self._tracks:
            found = JointTarget(name)
        if found is not None:
            self._resolved[name] = found
            return found
        known = sorted(set(self._targets) | set(self._tracks))
        raise UsageError(f"no target or character named {name!r}; known: {', '.join(known) or 'none'}")

    def add_speech(self, character, start_s: float, end_s: float) -> None:
        """Tell the runtime the character speaks from ``start_s`` to ``end_s`` seconds (saccades pause)."""
        self._speech.setdefault(self._track(character).rig.name, []).append((float(start_s), float(end_s)))

    def speech_intervals(self, character) -> list[tuple[float, float]]:
        """(start, end) seconds when the character speaks: :meth:`add_speech` and speaking controllers."""
        return self.speaking().get(self._track(character).rig.name, [])

    def speaking(self) -> dict[str, list[tuple[float, float]]]:
        """:meth:`speech_intervals` of every character that speaks, by name, in one pass."""
        spans = {name: list(told) for name, told in self._speech.items()}
        for a in self._speakers:
            spans.setdefault(a.rig.name, []).append((a.start_s, a.end_s if a.end_s is not None else np.inf))
        return {name: sorted(told) for name, told in spans.items()}

    def realize(self, activation, character=None, *, component=None) -> Activity | None:
        """Play a scheduled BML :class:`~infuse.bml.Activation` through the installed controller that
        realizes its kind (:func:`infuse.registry.realizer`).

        The controller's ``from_bml(parameters, runtime, character, activation)`` (its
        :class:`~infuse.plugin_types.ControllerFactory`) builds
        the controller (else its factory is called with the parameters). It may return None when the
        activation asks for nothing to play, and may stop activities itself (finishing saccades).
        Returns None, and reports why, when no installed controller realizes that kind. The activity
        runs from the activation's start to its end (persistent ones: until stopped), cut at ``stop_s``.
        ``component``: that controller's factory when the caller looked it up already.
        """
        from .. import registry

        name = character if character is not None else activation.character
        rig = self.rig(name)
        if activation.stop_s is not None and activation.stop_s <= activation.start:
            return None  # interrupted before it started
        if component is None:
            component = registry.realizer(activation.controller)
        if component is None:
            self.report(rig.name, f"no installed controller realizes <{activation.element}> ({activation.controller!r}); skipped")
            return None
        build = component.from_bml
        try:
            controller = build(dict(activation.parameters), self, rig.name, activation) if build \
                else component.factory(**activation.parameters)
        except (UsageError, ValueError, TypeError) as exc:
            self.report(rig.name, f"<{activation.element}> {activation.behaviour!r} cannot be realized: {exc}")
            return None
        if controller is None:
            return None
        end = None if activation.persistent else activation.end
        if activation.stop_s is not None:
            end = activation.stop_s if end is None else min(end, activation.stop_s)
        fade_in, fade_out = (activation.parameters.get(key) for key in ("fade_in_s", "fade_out_s"))
        return self.activate(rig.name, controller, activation.start, end, source=activation,
                             blend_in_s=None if fade_in is None else float(fade_in),
                             blend_out_s=None if fade_out is None else float(fade_out))

    # -- evaluation ------------------------------------------------------------------------------------
    def run(self, seconds: float) -> None:
        """Evaluate the next ``seconds`` of every character (rounded to whole frames)."""
        frames = int(round(float(seconds) * self.fps))
        if frames < 0:
            raise UsageError("run() takes a duration >= 0 seconds")
        while frames > 0:
            n = min(frames, self.block_frames)
            self._evaluate(n)
            frames -= n

    def step(self, frames: int = 1) -> None:
        """Evaluate the next ``frames`` frames as one block."""
        if frames > 0:
            self._evaluate(int(frames))

    def _evaluate(self, n: int) -> None:
        frames = self.frame + np.arange(n)
        times = frames / self.fps
        if self._layout is None or len(self._layout.rigs) != len(self._tracks):
            self._layout = TableLayout(track.rig for track in self._tracks.values())
        table = PoseTable(self._layout, n)
        poses = table.poses
        block = Block(self, frames, times, self.fps, poses, table)
        first, last = float(times[0]), float(times[-1])
        schedule = self._schedule
        if schedule is None or not schedule.current(self.activities):
            schedule = self._schedule = _Schedule(self.activities)
        playing = np.flatnonzero((schedule.starts <= last + 1e-9) & (schedule.settled >= first - 1e-9))  # active_between
        groups = schedule.groups(playing)
        # Every active activity's weights in one step (exactly 1 where certainly past its ramps), each
        # group's jobs then rows of them.
        if ((schedule.on_from[playing] <= first) & (schedule.on_until[playing] >= last)).all():
            weights = np.ones((len(playing), n))
        else:
            weights = blend_weights_of(times, *schedule.timing[playing].T)
        local_times = times[None] - schedule.starts[playing, None]
        started = time.thread_time()
        for key, members, rows, ids in groups:
            group_weights, group_times = weights[rows], local_times[rows]
            jobs = Jobs([Job(a, poses[name], w, t) for (a, name), w, t in zip(members, group_weights, group_times)],
                        group_weights, group_times, table, self._memos.setdefault(key, [None, None]), ids)
            key[2].evaluate(jobs, block)
        self.controllers_cpu_s += time.thread_time() - started
        for name, track in self._tracks.items():
            pose = poses[name]
            pose.carry_ends()
            track.rotations.append(pose.local_rotations)
            track.roots.append(pose.root_translations)
            track.translations.append(pose.joint_translations)
            if pose.joint_translations is not None:
                self.translated.add(name)
            track.morphs.append(pose.morph_weights)
            written = pose.morph_written
            track.morph_written = written if track.morph_written is None else track.morph_written | written
        self._tables.append(_Evaluated(table.layout, n, table.local_rotations, table.root_translations, table.morph_weights))
        self.frame += n

    # -- results ---------------------------------------------------------------------------------------
    def motion(self, character, name: str = "runtime") -> Motion:
        """Every frame evaluated so far, as a :class:`~infuse.Motion` on the character's skeleton; its
        morph weights are those of the morph targets any controller wrote."""
        track = self._track(character)
        rig = track.rig
        sk = rig.skeleton
        if not track.rotations:
            return Motion(sk, self.fps, np.zeros((0, sk.num_joints, 4)), np.zeros((0, 3)), name=name)
        written = np.zeros(len(rig.morph_targets), dtype=bool) if track.morph_written is None else track.morph_written
        columns = np.nonzero(written)[0]
        rotations = np.concatenate(track.rotations)
        roots = np.concatenate(track.roots)
        if rig.placed:  # the placement goes into the root joint (other roots, if any, stay where they are)
            rotations[:, 0], roots = rig.place(rotations[:, 0], roots)
        translations = None
        if any(t is not None for t in track.translations):
            rest = sk.rest_translations
            translations = np.concatenate([np.repeat(rest[None], len(r), axis=0) if t is None else t
                                           for t, r in zip(track.translations, track.roots)])
        return Motion(sk, self.fps, rotations, roots, translations, name=name,
                      morph_names=tuple(rig.morph_targets[i] for i in columns), morph_weights=self.morph_weights(character)[:, columns])

    def last_frames(self, character, count: int) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (n, J, 4) and root translations (n, 3) of the last ``count`` frames evaluated
        (n = fewer when fewer were), in the character's own frame: its placement is not applied."""
        track = self._track(character)
        rotations, roots, n = [], [], 0
        for rot, root in zip(reversed(track.rotations), reversed(track.roots)):
            if n >= count:
                break
            rotations.append(rot[-(count - n):])
            roots.append(root[-(count - n):])
            n += len(rotations[-1])
        sk = track.rig.skeleton
        if not rotations:
            return np.zeros((0, sk.num_joints, 4)), np.zeros((0, 3))
        return np.concatenate(rotations[::-1]), np.concatenate(roots[::-1])

    def last_poses(self, character, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The last ``count`` frames evaluated (n = fewer when fewer were), placed in the world as
        :meth:`motion` places them: local rotations (n, J, 4) (the root joint's with the placement), root
        translations (n, 3) metres and morph weights (n, M)."""
        track = self._track(character)
        rotations, roots, morphs, n = [], [], [], 0
        for rot, root, morph in zip(reversed(track.rotations), reversed(track.roots), reversed(track.morphs)):
            if n >= count:
                break
            take = min(count - n, len(rot))
            rotations.append(rot[len(rot) - take:])
            roots.append(root[len(root) - take:])
            morphs.append(morph[len(morph) - take:])
            n += take
        rig = track.rig
        if not rotations:
            return (np.zeros((0, rig.skeleton.num_joints, 4)), np.zeros((0, 3)), np.zeros((0, len(rig.morph_targets))))
        local = np.concatenate(rotations[::-1])
        root = np.concatenate(roots[::-1])
        if rig.placed:
            local[:, 0], root = rig.place(local[:, 0], root)
        return local, root, np.concatenate(morphs[::-1])

    def cast_poses(self, count: int) -> tuple[TableLayout, np.ndarray, np.ndarray, np.ndarray] | None:
        """Every character's last ``count`` frames evaluated (n = fewer when fewer were) side by side, placed
        in the world as :meth:`last_poses` places each: the :class:`~infuse.runtime.pose.TableLayout` of the
        columns, local rotations (n, N, 4) (each character's root joint with its placement), root
        translations (n, C, 3) metres and morph weights (n, M), new arrays. None when a character joined
        within those frames (the blocks' layouts differ: :meth:`last_poses` per character then)."""
        tables, n = [], 0
        for table in reversed(self._tables):
            if n >= count:
                break
            take = min(count - n, table.frames)
            tables.append((table, table.frames - take))
            n += take
        if not tables or any(table.layout is not tables[0][0].layout for table, _ in tables):
            return None
        layout = tables[0][0].layout
        tables.reverse()
        rotations, roots, morphs = (np.concatenate([getattr(table, key)[start:] for table, start in tables])
                                    for key in ("local_rotations", "root_translations", "morph_weights"))
        placed, columns, turns, positions = self._placements(layout)
        if placed.size:  # Rig.place on every placed character at once
            rotations[:, columns] = quat.multiply(turns, rotations[:, columns])
            roots[:, placed] = quat.rotate(turns, roots[:, placed]) + positions
        return layout, rotations, roots, morphs

    def _placements(self, layout: TableLayout) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The characters of ``layout`` placed in the world (:attr:`Rig.placed`): their indices (n,), their
        root joints' table columns (n,), rotations (n, 4) and positions (n, 3); kept while each rig holds
        the same placement arrays (a scene turning a character gives its rig a new rotation)."""
        kept = self._placed
        if kept is None or kept[0] is not layout or any(rig.rotation is not rotation or rig.position is not position
                                                        for rig, (rotation, position) in zip(layout.rigs, kept[1])):
            turns = np.stack([rig.rotation for rig in layout.rigs])  # (C, 4)
            positions = np.stack([rig.position for rig in layout.rigs])  # (C, 3)
            placed = np.flatnonzero((positions != 0.0).any(axis=1) | (turns != quat.IDENTITY).any(axis=1))
            columns = np.array([span[0] for span in layout.joint_spans], dtype=np.int64)[placed]
            kept = self._placed = (layout, [(rig.rotation, rig.position) for rig in layout.rigs],
                                   (placed, columns, turns[placed], positions[placed]))
        return kept[2]

    def last_translations(self, character, count: int) -> np.ndarray | None:
        """Local joint translations (n, J, 3) metres of the frames :meth:`last_poses` returns (joint 0's:
        the rest offset, its root translation being :meth:`last_poses`'), for a character whose controllers
        place joints by translation (a foot carried on its shin's end, a clip's translation channels);
        None when none of those frames has any (an ordinary rig, at no cost)."""
        track = self._track(character)
        parts, n = [], 0
        for translations, root in zip(reversed(track.translations), reversed(track.roots)):
            if n >= count:
                break
            take = min(count - n, len(root))
            parts.append((translations, len(root) - take, take))
            n += take
        if all(t is None for t, _, _ in parts):
            return None
        rest = track.rig.skeleton.rest_translations
        return np.concatenate([np.repeat(rest[None], take, axis=0) if t is None else t[start:start + take]
                               for t, start, take in parts[::-1]])

    def forget(self, keep_s: float) -> None:
        """Drop the evaluated frames older than ``keep_s`` seconds (whole blocks; :meth:`motion` then starts
        later than frame 0), and the activities and the speech (:meth:`add_speech`) that ended before then,
        so that a runtime that runs for hours keeps bounded memory. Frames still needed by :meth:`last_frames` up to ``keep_s`` stay."""
        keep = max(int(round(float(keep_s) * self.fps)), 1)
        for track in self._tracks.values():
            lengths = [len(r) for r in track.rotations]
            held, cut = sum(lengths), 0
            while cut < len(lengths) - 1 and held - lengths[cut] >= keep:
                held -= lengths[cut]
                cut += 1
            for parts in (track.rotations, track.roots, track.translations, track.morphs):
                del parts[:cut]
        held = 0
        for cut in range(len(self._tables) - 1, -1, -1):
            held += self._tables[cut].frames
            if held >= keep:
                del self._tables[:cut]
                break
        before = self.time - float(keep_s)
        self.activities = [a for a in self.activities if a.settled_s >= before]
        self._speakers = [a for a in self._speakers if a.settled_s >= before]
        self._speech = {name: [(s, e) for s, e in spans if e >= before] for name, spans in self._speech.items()}

    def morph_weights(self, character) -> np.ndarray:
        """(F, M) morph weights of every frame evaluated so far (columns: the character's morph targets)."""
        track = self._track(character)
        if not track.morphs:
            return np.zeros((0, len(track.rig.morph_targets)))
        return np.concatenate(track.morphs)

    def export(self, character, clip: str = "runtime", ground: bool = True) -> Asset:
        """The character's asset with the evaluated frames as its only clip (morph weights included),
        ready for :func:`infuse.save`. With ``ground`` the clip is moved up or down so that the
        feet's lowest point, soles included, is at the height the character stands at (a rig that
        puts its hips at the origin would otherwise stand a leg's length below the ground)."""
        track = self._track(character)
        rig = track.rig
        asset = rig.character.asset
        motion = self.motion(character, clip)
        if ground and motion.num_frames:
            motion = on_ground(asset, rig.mapping, motion, float(rig.position[1]))
        return replace(asset, motions={clip: motion})
