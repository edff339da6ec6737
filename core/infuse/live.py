"""Live characters: a :class:`~infuse.scene.Scene` run against the wall clock, frame by frame.

::

    from infuse.live import LiveScene
    from infuse.scene import Scene

    scene = Scene(fps=60)
    scene.add_character("avatar.glb", name="ann", packs=["locomotion-female"])
    with LiveScene(scene) as live:                  # threads evaluate and show a frame every 1/60 s
        live.on_frame(lambda frame: ...)             # each frame as it is shown (do not block)
        live.on("blockProgress", print)              # BML feedback, as in a Scene
        live.say("ann", "Hello!")                    # the builder calls start on the next frame
        live.move_target("ball", (0.5, 1.2, 1.0))    # a named target; gaze follows it from the next frame
        live.bml("ann", '<bml ... composition="REPLACE">...</bml>')

Frame ``k`` is at scene time ``k / fps`` and is due on the wall clock at ``epoch + k / fps``. Two
threads run it: the evaluator (the loop thread) applies commands (BML, builder calls, target moves) and evaluates blocks
of frames; the presenter shows each frame when it is due (:meth:`LiveScene.on_frame` callbacks). Each
block starts as late as it can and still be ready when its first frame is due (the lead: the
:data:`LEAD_SHARE` percentile of how long the blocks of the last second took, waking late included,
commands excluded, and at least the longest of them less a frame; a costlier block shows its frame late
by the difference, and misses it only when it takes a frame longer than the lead), so a command that
arrives before then shows on that frame. Commands are applied between blocks, each where it fits: one
that would leave the next block too little time to be ready when its first frame is due at the block's
usual cost (the median of the last second's; a command takes as long as the last ones of its kind, the
median; the first of a kind as the longest kind known, at most a frame) waits for the gap after that
block, which is made long enough for it (the block holds more frames), so a burst of them delays no
frame. A loop running late spends at most :attr:`LiveScene.command_budget_s` per block on them. Commands wait in a bounded queue: a
full queue raises :class:`~infuse.errors.BusyError` at once.

Evaluating frames one by one costs more per frame than in blocks (each controller's work per block is
much the same for one frame as for eight). So blocks hold :attr:`LiveScene.block_frames` frames: one
while a frame costs under 90% of a frame's time; twice as many (up to ``max_block_frames``) when it
costs more; as soon as the median of the last blocks says a shorter block's frames would cost under 50%
(a shorter block costs at most what a longer one does), that many; and where that bound cannot tell but
the frames cost under 50%, blocks half as long are tried half a second after blocks last grew, twice as
long after each try that grew back (the first frame, evaluated as the loop starts, sizes the first
blocks). With blocks of one frame a command shows at most a frame, the lead
and the commands before it after it arrives; with blocks of B frames, within B frames plus the lead. A
slow moment (the machine busy elsewhere, a costly controller) grows blocks and the lead; both are back
within a second of its end. A frame still waiting when the next one is due is skipped and counts as
missed (:attr:`LiveStats.missed`). At most a block and the frames already due when it started wait to
be shown.

Frames stand on the ground as exported files do: each character is lowered by how low its feet reach at
rest, soles included (:func:`infuse.grounding.foot_height`; a rig with its hips at the origin is lifted).

Blocks are put through the scene's BML generators, their speech synthesized (once, with the marks the
generators added) and their walks' paths planned on the caller's thread before they reach the loop, so
neither stalls a frame.
Old frames, ended activities and finished blocks are forgotten: memory stays bounded.
"""
from __future__ import annotations

import gc
import math
import queue
import statistics
import sys
import threading
import time
from collections import deque
from concurrent.futures import Future
from dataclasses import dataclass, replace
from typing import Callable, Iterable

import numpy as np

from .bml import BmlDocument, Scheduler, builder, parse_bml
from .errors import BusyError, UnusableInputError, UsageError
from .grounding import foot_height
from .runtime.targets import Target
from .scene import Scene

#: Seconds of evaluated frames kept (walks look back 0.5 s to see a character standing).
KEEP_S = 2.0
#: Seconds a block's frames are meant to be ready before the first is due: handing them to the presenter
#: thread, which wakes for them, takes a tenth of a millisecond or so.
LEAD_MARGIN_S = 0.0003
#: The share of one-frame blocks the lead is meant to have ready in time (by the last second's): a longer
#: lead shows fewer frames late, a shorter one shows commands sooner (a command waits for the next block and
#: its lead). Longer blocks, which show a command only frames later anyway and whose costs vary by more,
#: take :data:`LONG_BLOCK_LEAD_SHARE` at least.
LEAD_SHARE = 0.75
LONG_BLOCK_LEAD_SHARE = 0.9
#: Blocks double while a frame costs more than this share of a frame's time, and shrink to a size whose
#: frames would cost under :data:`SHRINK_AT` of it (what is left: commands, and the machine's other work).
GROW_AT, SHRINK_AT = 0.9, 0.5
#: Seconds after blocks last grew before the loop tries blocks half as long whose cost only a try can tell
#: (their frames cost under :data:`SHRINK_AT` of their time in the longer blocks); doubled after each try
#: that grew back, up to :data:`TRY_MAX_S`, and back to this after a try that held.
TRY_S, TRY_MAX_S = 0.5, 8.0
#: Seconds a thread running Python keeps the interpreter before another that waits for it gets it, while a
#: live scene runs (:func:`sys.setswitchinterval`; Python's default is 5 ms). A thread preparing commands
#: (parsing, lip sync, a walk's path) then holds a block's start or its evaluation up by about this, not 5 ms.
SWITCH_INTERVAL_S = 0.001


@dataclass(frozen=True)
class CharacterFrame:
    """One character's pose at one frame: ``rotations`` (J, 4) local joint rotations, scalar-last, the
    root joint's with the character's placement; ``root`` (3,) root translation, metres; ``morphs`` (M,)
    morph weights in the order of the character's morph targets; ``translations`` (J, 3) local joint
    translations, metres (joint 0's is ``root``), for a character whose joints are placed by translation
    (feet hanging from the root, carried on the shins' ends), None for the others (their rest offsets)."""

    rotations: np.ndarray
    root: np.ndarray
    morphs: np.ndarray
    translations: np.ndarray | None = None


@dataclass(frozen=True)
class LiveFrame:
    """A frame as it is shown: its index, scene time (seconds), wall-clock time it was ready
    (:func:`time.perf_counter` seconds) and each character's pose."""

    index: int
    time_s: float
    wall_s: float
    characters: dict[str, CharacterFrame]


class LiveStats:
    """Frame timing of a live loop: frames shown, frames missed (evaluated too late to be shown), commands
    applied, the current block size and lead (how long before its first frame is due a block starts,
    milliseconds), and the evaluation time per frame of the last blocks, on the wall clock and in the loop
    thread's CPU time (milliseconds; they differ when the machine is loaded; the CPU time includes taking
    the frames out), and the part of that CPU time spent in the controllers (the rest: the runtime's and
    the loop's own bookkeeping).
    ``late_ms``: how long after it was due each of the last frames was shown (milliseconds; a block that
    took longer than the lead shows its frames late).
    ``blocks``: the last blocks evaluated, (first frame, frames) each: a session replayed offline with
    the same blocks and commands gives the same frames (other blocks give them to rounding)."""

    def __init__(self, window: int = 3600):
        self.shown = 0
        self.missed = 0
        self.commands = 0
        self.block_frames = 1
        self.lead_ms = 0.0
        self.late_ms: deque[float] = deque(maxlen=window)  # how long after it was due each frame was shown
        self.evaluate_ms: deque[float] = deque(maxlen=window)
        self.evaluate_cpu_ms: deque[float] = deque(maxlen=window)
        self.controllers_cpu_ms: deque[float] = deque(maxlen=window)  # the part of it in the controllers
        self.blocks: deque[tuple[int, int]] = deque(maxlen=window)  # (first frame, frames) of each block

    def summary(self) -> dict:
        """Counts and evaluation-time percentiles (ms) over the window."""
        ms = np.asarray(self.evaluate_ms, dtype=np.float64)
        figures = {"shown": self.shown, "missed": self.missed, "commands": self.commands, "block_frames": self.block_frames,
                   "lead_ms": self.lead_ms}
        if len(ms):
            figures.update(mean_ms=float(ms.mean()), p50_ms=float(np.percentile(ms, 50)),
                           p99_ms=float(np.percentile(ms, 99)), max_ms=float(ms.max()),
                           cpu_mean_ms=float(np.mean(self.evaluate_cpu_ms)),
                           late_p99_ms=float(np.percentile(self.late_ms, 99)) if self.late_ms else 0.0,
                           late_max_ms=max(self.late_ms, default=0.0),
                           controllers_cpu_mean_ms=float(np.mean(self.controllers_cpu_ms)))
        return figures


class _PreparedSpeech:
    """The scheduler's speech timer in a live scene: timings synthesized ahead on the callers' threads
    (:meth:`LiveScene.prepare`), looked up on the loop thread. A timing not prepared is synthesized where it
    is asked for, under the same lock as the scene's speech cache."""

    def __init__(self, cache, voice_of: Callable[[str | None], str | None]):
        self.cache = cache
        self.voice_of = voice_of
        self.timings: dict[tuple, object] = {}
        self.lock = threading.Lock()
        self.local = threading.local()

    def time_speech(self, text, marks, voice=None, language=None):
        voice = voice or self.voice_of(getattr(self.local, "character", None))
        key = (text, tuple(marks), voice, language)
        timing = self.timings.get(key)
        if timing is None:
            with self.lock:
                timing = self.cache.time_speech(text, marks, voice, language)
                self.timings[key] = timing
        return timing


class LiveScene:
    """A scene evaluated against the wall clock on its own thread (see the module doc).

    ``scene``: the :class:`~infuse.scene.Scene` (characters added, blocks maybe scheduled; nothing
    evaluated yet, or its time is taken as now). ``queue_size``: most commands waiting.
    ``command_budget_s``: most seconds per block spent on commands once the block is due (default a
    quarter of a frame).
    ``keep_s``: seconds of evaluated frames kept. ``max_block_frames``: the largest block evaluated at once.
    ``lead_share``: the share of one-frame blocks meant to be ready when their first frame is due
    (:data:`LEAD_SHARE`).
    """

    def __init__(self, scene: Scene, *, queue_size: int = 256, command_budget_s: float | None = None,
                 keep_s: float = KEEP_S, max_block_frames: int = 32, lead_share: float = LEAD_SHARE):
        if not isinstance(scene, Scene):
            raise UsageError(f"LiveScene takes an infuse.scene.Scene, not {type(scene).__name__}")
        self.scene = scene
        self.fps = scene.fps
        self.period_s = 1.0 / scene.fps
        self.command_budget_s = 0.25 * self.period_s if command_budget_s is None else float(command_budget_s)
        self.keep_s = float(keep_s)
        self.max_block_frames = max(1, int(max_block_frames))
        if not 0.0 < lead_share <= 1.0:
            raise UsageError(f"lead_share is a share of blocks, over 0 and at most 1, not {lead_share}")
        self.lead_share = float(lead_share)
        self.block_frames = 1
        self._costs: deque[tuple[int, float]] = deque(maxlen=5)  # (frames, seconds) of the last blocks since a resize
        self._try_wait_s, self._try_at, self._trying = TRY_S, 0.0, False  # shorter blocks tried (see _resize)
        self.stats = LiveStats()
        self.epoch: float | None = None
        self.error: BaseException | None = None
        self._commands: queue.Queue = queue.Queue(maxsize=max(1, int(queue_size)))
        self._frame_callbacks: list[Callable[[LiveFrame], None]] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._speech = _PreparedSpeech(scene.speech, self._voice_of)
        scene.scheduler.speech_timer = self._speech
        self._last: LiveFrame | None = None
        self._pending: deque[tuple[int, dict]] = deque()  # frames evaluated, not shown yet
        self._ready = threading.Condition()
        self._between = threading.Event()  # set while the loop is not evaluating a block
        self._between.set()
        self._presenter: threading.Thread | None = None
        self._lead_s = 0.0  # how long before a block's first frame is due its evaluation starts
        self._usual_s = 0.0  # what a block usually takes (the median the lead is taken with)
        self._leads: deque[tuple[int, int, float]] = deque(maxlen=120)  # (first frame, frames, seconds) per block
        self._held: tuple | None = None  # a command taken from the queue that waits for the next gap
        self._command_s: dict[str, deque[float]] = {}  # kind -> seconds the last commands of that kind took
        self._grounds: dict[str, float] = {}
        self._movable: dict[str, MovableTarget] = {}
        self._warm = False
        self._frozen = False  # objects set aside from the garbage collector by start (gc.freeze)
        self._preparing: dict[str, bool] = {}  # BML element -> whether a controller realizing it prepares ahead
        self._made_before = 0

    # -- the loop -------------------------------------------------------------------------------------
    def warm_up(self, seconds: float = 0.5) -> None:
        """Prepare what each character's first walk or reach would prepare (pack bindings, clip tables) by
        playing the installed controllers' warm-ups (:attr:`~infuse.plugin_types.ControllerFactory.warm_up`)
        for ``seconds`` on a scratch runtime, so that the first one does not stall a frame."""
        for name in list(self.scene.characters):
            self._warm_up(name, seconds)

    def _warm_up(self, name: str, seconds: float = 0.5) -> None:
        from . import registry
        from .runtime import Runtime

        scratch = Runtime(self.fps, report=lambda character, message: None)
        scratch.add_character(self.scene.characters[name].character, name, self.scene.runtime.rig(name).mapping)
        for descriptor in registry.table("controller").values():
            trial = descriptor.warm_up(self.scene.stage, name) if descriptor.warm_up is not None else None
            if trial is not None:
                scratch.activate(name, trial, 0.0)
        if scratch.activities:
            scratch.run(seconds)

    def start(self) -> "LiveScene":
        """Start the loop (after :meth:`warm_up`): the scene's current time is now on the wall clock (its
        frame is evaluated here, and shown at once)."""
        if self._thread is not None:
            raise UsageError("this live scene has already been started")
        if not self._warm:
            self.warm_up()
            self._warm = True
        for name in self.scene.characters:
            self._foot_height(name)  # meshes skinned here, not on the loop thread
        # Python's full garbage collection walks every object: with a scene loaded (meshes, packs, clip
        # tables) it takes tens of milliseconds (70 to 90 ms with the live benchmark's ten characters on
        # a busy machine), frames missed whenever it comes. What is loaded now is collected once and set
        # aside (until stop), so a full collection walks only what was made since.
        gc.collect()
        gc.freeze()
        self._frozen = True
        _switch_often(True)
        # The first frame, evaluated here, tells what a block costs: blocks start as long as it takes to keep
        # up (a block costs much the same whatever its length), so the first seconds miss no frames.
        started = time.perf_counter()
        self._pending.extend(self._evaluate(1))
        first_s = time.perf_counter() - started
        needed = first_s / (GROW_AT * self.period_s)
        self.block_frames = min(1 << max(0, math.ceil(math.log2(max(needed, 1.0)))), self.max_block_frames)
        self.stats.block_frames = self.block_frames
        self._costs.clear()
        self._leads.append((self._pending[0][0], 1, first_s))
        self._update_lead()
        self.epoch = time.perf_counter() - self._pending[0][0] * self.period_s
        self._thread = threading.Thread(target=self._run, name="infuse-live", daemon=True)
        self._presenter = threading.Thread(target=self._present, name="infuse-live-frames", daemon=True)
        self._thread.start()
        self._presenter.start()
        return self

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the loop (after the block it is evaluating); commands still queued get :class:`UsageError`."""
        self._stop.set()
        with self._ready:
            self._ready.notify_all()
        for thread in (self._thread, self._presenter):
            if thread is not None and thread is not threading.current_thread():
                thread.join(timeout_s)
        self._refuse_waiting()
        if self._frozen:
            self._frozen = False
            gc.unfreeze()
            _switch_often(False)

    def _refuse_waiting(self) -> None:
        """Commands still queued (or held for the next gap) get :class:`UsageError` (the loop has stopped)."""
        held, self._held = self._held, None
        while True:
            try:
                future = held[0] if held is not None else self._commands.get_nowait()[0]
            except queue.Empty:
                break
            held = None
            future.set_exception(UsageError(f"the live scene has stopped{f': {self.error}' if self.error else ''}"))

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def __enter__(self) -> "LiveScene":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def due_s(self, frame: int) -> float:
        """Wall-clock (:func:`time.perf_counter`) seconds when frame ``frame`` is due."""
        return self.epoch + frame * self.period_s

    def _run(self) -> None:
        """The evaluator: each block starts as late as it can and still be ready when its first frame is
        due, so that commands arriving until then apply to that frame."""
        scene = self.scene
        try:
            while not self._stop.is_set():
                first = scene.runtime.frame
                planned = self.due_s(first) - self._lead_s - LEAD_MARGIN_S
                begun = max(planned, time.perf_counter())  # a block that is late already starts at once
                commands_s = self._apply_commands(planned)
                if self._stop.is_set():
                    break
                overdue = int((time.perf_counter() - self.due_s(first)) / self.period_s)  # due already: shown no more
                self._between.clear()
                frames = self._evaluate(self.block_frames + self._room() + max(overdue, 0))
                # the lead: from the planned start to the frames in hand, waking late included and commands
                # applied meanwhile left out (a burst of them delays its own block, not every later one's)
                self._leads.append((first, len(frames), time.perf_counter() - begun - commands_s))
                self._update_lead()
                with self._ready:
                    self._pending.extend(frames)
                    self._ready.notify_all()
                if first // int(self.fps) != scene.runtime.frame // int(self.fps):
                    self._forget()  # once a second, after the frames are in the presenter's hands
                self._between.set()
        except BaseException as exc:  # kept (with its traceback) for callers, which get errors from then on
            self._fail(exc)
        finally:
            self._between.set()

    def _wait_for_a_gap(self) -> None:
        """On a caller's thread, wait until the loop is between blocks (at most a block's longest time):
        Python runs one thread at a time, so work begun here while a block is evaluated (parsing,
        synthesizing, planning a walk) would take turns with it and make its frames late. A command that
        arrives while a block is evaluated shows on the next block anyway."""
        if self._thread is not None and threading.current_thread() is not self._thread:
            self._between.wait(self.max_block_frames * self.period_s)

    def _update_lead(self) -> None:
        """The lead for blocks of :attr:`block_frames`: the :attr:`lead_share` percentile (one-frame blocks;
        :data:`LONG_BLOCK_LEAD_SHARE` at least for longer ones) of what the blocks of the last second took
        (at least the last few), from those of this size once there are three, else from all of them, a
        shorter block's scaled by how much longer this one is (a block started late, the machine busy
        elsewhere, moves it for a second at most); and at least the longest of them less a frame, so that
        a block as long is late, not missed (its first frame is shown before the next one is due). Also
        what they usually took: the median."""
        size, now = self.block_frames, self.scene.runtime.frame
        recent = [lead for lead in self._leads if lead[0] >= now - self.fps] or list(self._leads)[-3:]
        same = [seconds for _, frames, seconds in recent if frames == size]
        if len(same) < 3:
            same = [seconds * max(1.0, size / frames) for _, frames, seconds in recent]
        same.sort()
        wanted = self.lead_share if size == 1 else max(self.lead_share, LONG_BLOCK_LEAD_SHARE)
        share = same[max(math.ceil(wanted * len(same)), 1) - 1]
        safe = same[-1] - self.period_s + LEAD_MARGIN_S  # the longest of them still shows its first frame in time
        self._lead_s = min(max(share, safe), self.max_block_frames * self.period_s)
        self._usual_s = min(same[(len(same) - 1) // 2], self._lead_s)
        self.stats.lead_ms = self._lead_s * 1e3

    def _present(self) -> None:
        """The presenter: shows each evaluated frame when it is due; a frame still waiting when the next
        one is due is skipped and counted as missed."""
        try:
            while not self._stop.is_set():
                with self._ready:
                    while not self._pending and not self._stop.is_set():
                        self._ready.wait(0.05)
                    if self._stop.is_set():
                        return
                    index = self._pending[0][0]
                wait = self.due_s(index) - time.perf_counter()
                if wait > 0 and self._stop.wait(wait):
                    return
                with self._ready:
                    now = time.perf_counter()
                    while len(self._pending) > 1 and now >= self.due_s(self._pending[1][0]):
                        self._pending.popleft()
                        self.stats.missed += 1
                    shown = self._pending.popleft()
                self.stats.late_ms.append(max(0.0, now - self.due_s(shown[0])) * 1e3)
                self._show(*shown)
        except BaseException as exc:  # a frame callback's error: kept, as the evaluator's
            self._fail(exc)

    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        self._stop.set()
        with self._ready:
            self._ready.notify_all()
        self._refuse_waiting()

    def _evaluate(self, count: int) -> list[tuple[int, dict]]:
        """Evaluate the next ``count`` frames as one block (at most the runtime's ``block_frames``); their
        indices and poses, stood on the ground as exported files are. Adapts :attr:`block_frames` to what
        evaluation costs (see the module doc)."""
        scene = self.scene
        count = min(count, scene.runtime.block_frames)
        first = scene.runtime.frame
        started, started_cpu, controllers_s = time.perf_counter(), time.thread_time(), scene.runtime.controllers_cpu_s
        scene.step(count)
        spent = time.perf_counter() - started
        count = scene.runtime.frame - first
        self.stats.evaluate_ms.append(spent * 1e3 / count)
        self.stats.blocks.append((first, count))
        self._resize(count, spent)
        self.stats.block_frames = self.block_frames
        frames = self._frames(first, count)
        self.stats.evaluate_cpu_ms.append((time.thread_time() - started_cpu) * 1e3 / count)
        self.stats.controllers_cpu_ms.append((scene.runtime.controllers_cpu_s - controllers_s) * 1e3 / count)
        return frames

    def _frames(self, first: int, count: int) -> list[tuple[int, dict]]:
        """The ``count`` frames evaluated last, from frame ``first``: (index, {name: :class:`CharacterFrame`})
        each, stood on the ground; every character's at once from the runtime's tables
        (:meth:`~infuse.runtime.Runtime.cast_poses`), or one at a time when a character joined within them."""
        runtime, names = self.scene.runtime, list(self.scene.characters)
        cast = runtime.cast_poses(count)
        if cast is not None:
            layout, rotations, roots, morphs = cast
            index = [layout.character_index[name] for name in names]
            roots[:, index, 1] -= np.array([self._foot_height(name) for name in names])
            poses = {name: (rotations[:, slice(*layout.joint_spans[c])], roots[:, c], morphs[:, slice(*layout.morph_spans[c])])
                     for name, c in zip(names, index)}
        else:
            poses = {name: runtime.last_poses(name, count) for name in names}
            for name, (_, root, _) in poses.items():
                root[:, 1] -= self._foot_height(name)
        frames: list[tuple[int, dict]] = [(first + k, {}) for k in range(count)]
        for name, (r, t, m) in poses.items():
            translations = runtime.last_translations(name, count) if name in runtime.translated else None
            if translations is None:
                for (_, shown), rotations, root, morphs in zip(frames, r, t, m):
                    shown[name] = CharacterFrame(rotations, root, morphs)
            else:
                translations[:, 0] = t
                for (_, shown), rotations, root, morphs, moved in zip(frames, r, t, m, translations):
                    shown[name] = CharacterFrame(rotations, root, morphs, moved)
        return frames

    def _resize(self, frames: int, seconds: float) -> None:
        """Adapt :attr:`block_frames` to what the block just evaluated (``frames`` frames in ``seconds``)
        cost, by the median of the blocks since the last resize (three at least: one late block, the
        machine busy elsewhere, resizes nothing). Blocks double while a frame costs over
        :data:`GROW_AT` of its time. They shrink at once to the shortest size whose frames would cost
        under :data:`SHRINK_AT` of it, counting a shorter block as costly as the longer ones measured (a
        block costs much the same whatever its length, and never more for fewer frames). Where that
        bound keeps them long but their frames cost under :data:`SHRINK_AT` of their time, blocks half
        as long are tried, :data:`TRY_S` after blocks last grew (a try that grows back waits twice as
        long for the next, up to :data:`TRY_MAX_S`): what a block costs is partly its frames, so a
        shorter one may fit where the bound says it might not."""
        self._costs.append((frames, seconds))
        if len(self._costs) < 3:
            return
        per_frame = statistics.median(s / f for f, s in self._costs)
        per_block = statistics.median([s for f, s in self._costs if f >= self.block_frames] or [math.inf])
        size, now, trying = self.block_frames, time.perf_counter(), False
        if per_frame > GROW_AT * self.period_s:
            size = min(2 * size, self.max_block_frames)
            if self._trying:
                self._try_wait_s = min(2.0 * self._try_wait_s, TRY_MAX_S)
            self._try_at = now + self._try_wait_s
        else:
            if self._trying:
                self._try_wait_s = TRY_S
            while size > 1 and per_block / (size // 2) < SHRINK_AT * self.period_s:
                size //= 2
            if size == self.block_frames > 1 and per_frame < SHRINK_AT * self.period_s and now >= self._try_at:
                size, trying = size // 2, True
        self._trying = trying
        if size != self.block_frames:
            self.block_frames = size
            self._costs.clear()

    def _foot_height(self, name: str) -> float:
        """How low (m) the character's feet reach, soles included, at rest: its frames are lowered by it, as
        :meth:`~infuse.runtime.Runtime.export` grounds a clip (measured before the loop starts, or here)."""
        height = self._grounds.get(name)
        if height is None:
            rig = self.scene.runtime.rig(name)
            height = self._grounds[name] = _rest_foot_height(rig.character.asset, rig.mapping)
        return height

    def _apply_commands(self, until: float) -> float:
        """Apply commands, waiting for them, until the wall clock reaches ``until`` (the block's planned
        start). A command runs when it is expected (it takes as long as the last ones of its kind, the
        median) to end early enough for the block, at its usual cost (the median of the last second's), to
        be ready when its first frame is due: it may start the block a little late (a costly block then
        shows its frame late by as much), which costs less than the frame it would wait otherwise. A loop
        running late (the block's planned start passed before the gap began) runs commands while they are
        expected to fit :attr:`command_budget_s`. One that does not fit waits for the next gap, which
        :meth:`_room` makes long enough, and goes first in it. Returns the seconds spent on commands after
        ``until``."""
        late_s = 0.0
        waited = self._held is not None
        behind = time.perf_counter() >= until
        latest = until + LEAD_MARGIN_S + self._lead_s - self._usual_s  # a usual block still ready in time
        while not self._stop.is_set():
            now = time.perf_counter()
            wait = until - now
            command = self._held
            if command is None:
                if wait <= 0 and (late_s >= self.command_budget_s if behind else now >= latest):
                    return late_s
                try:
                    command = self._commands.get(timeout=min(wait, 0.05)) if wait > 0 else self._commands.get_nowait()
                except queue.Empty:
                    if wait <= 0:
                        return late_s
                    continue
            self._held = None
            future, function, args, kind = command
            started = time.perf_counter()
            expected = self._expected_s(kind)
            fits = late_s + expected <= self.command_budget_s if behind else started + expected <= latest
            if not waited and not fits:
                self._held = command  # it would hold the block up: first thing after it
                if started < until:
                    self._stop.wait(until - started)
                return late_s
            waited = False
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(function(*args))
                except Exception as exc:  # noqa: BLE001 - the caller gets it; the loop goes on
                    future.set_exception(exc)
            ended = time.perf_counter()
            self._command_s.setdefault(kind, deque(maxlen=8)).append(ended - started)
            self.stats.commands += 1
            late_s += max(0.0, ended - max(started, until))
        return late_s

    def _room(self) -> int:
        """Frames added to the next block so that the gap after it fits the command held for it: a block
        of n frames is ready as its first frame is due, and the next one starts the lead before its own
        first frame, n frames later. The loop evaluates a longer block, which costs little more, rather
        than let the command run into a frame's time."""
        if self._held is None:
            return 0
        needed = math.ceil((self._expected_s(self._held[3]) + self._lead_s) / self.period_s)
        return min(max(needed - self.block_frames, 0), self.max_block_frames - self.block_frames)

    def _expected_s(self, kind: str) -> float:
        """Seconds a command of ``kind`` is expected to take: the median of the last ones of its kind (one
        slowed down by the machine's other work does not hold the next ones back). The first of a kind
        is expected to take as long as the longest kind known, at most a frame's time (a character added,
        which takes far longer, would hold a long block for each new kind): it then waits for a gap made
        long enough rather than run into a frame's time. The very first command, nothing known, is
        expected to take no time (commands take a millisecond or two on the loop: walks plan their paths
        before), so that it shows on the next frame."""
        taken = self._command_s.get(kind)
        if taken:
            return statistics.median(taken)
        known = [statistics.median(other) for other in self._command_s.values()]
        return min(max(known), self.period_s) if known else 0.0

    def _show(self, index: int, characters: dict) -> None:
        frame = LiveFrame(index, index / self.fps, time.perf_counter(), characters)
        self._last = frame
        self.stats.shown += 1
        for callback in list(self._frame_callbacks):
            callback(frame)

    def _forget(self) -> None:
        """Keep memory bounded: old frames, ended activities and utterances, delivered feedback. An
        utterance goes once no activity plays it and it was made before the last call (one prepared on a
        caller's thread may not be scheduled yet)."""
        scene = self.scene
        scene.forget(self.keep_s)
        cache = scene.speech
        playing = {(a.source.parameters.get("tts") or {}).get("utterance") for a in scene.activities.values()
                   if a.source is not None and a.controller.speaks}
        if not self._speech.lock.acquire(blocking=False):
            return  # a synthesis is running on a caller's thread: let utterances go next time
        try:
            released = {i for i in range(self._made_before) if cache.utterances[i] is not None and i not in playing}
            if released:
                self._speech.timings = {k: t for k, t in self._speech.timings.items()
                                        if (t.details or {}).get("utterance") not in released}
                cache.release(released)
            self._made_before = len(cache.utterances)
        finally:
            self._speech.lock.release()

    # -- commands -------------------------------------------------------------------------------------
    def submit(self, function: Callable, *args, kind: str | None = None) -> Future:
        """Run ``function(*args)`` on the loop thread before the next frame; returns its future. ``kind``
        names what it does (default: the function's name): the loop expects a command to take as long as
        the last ones of its kind, and starts it where it fits between two blocks.
        :class:`BusyError` when the queue is full, :class:`UsageError` when the loop is not running."""
        if self.error is not None or self._stop.is_set():
            raise UsageError(f"the live scene has stopped{f': {self.error}' if self.error else ''}")
        future: Future = Future()
        try:
            self._commands.put_nowait((future, function, args, kind or getattr(function, "__qualname__", "command")))
        except queue.Full:
            raise BusyError(f"{self._commands.maxsize} commands are waiting; try again later") from None
        if self._stop.is_set():  # stopped meanwhile: nothing will take it
            self._refuse_waiting()
        return future

    def call(self, function: Callable, *args, timeout_s: float = 10.0, kind: str | None = None):
        """:meth:`submit` and wait for the result (the exception it raised is raised here)."""
        if self._thread is None:
            return function(*args)  # not started: nothing runs concurrently
        return self.submit(function, *args, kind=kind).result(timeout_s)

    def on_frame(self, callback: Callable[[LiveFrame], None]) -> Callable[[], None]:
        """Call ``callback(frame)`` on the presenter thread as each frame is shown (it must return at once);
        returns a function that unsubscribes."""
        self._frame_callbacks.append(callback)
        return lambda: self._frame_callbacks.remove(callback) if callback in self._frame_callbacks else None

    def on(self, kinds: str | Iterable[str] | None, callback: Callable) -> Callable[[], None]:
        """Call ``callback(event)`` on the evaluator thread for BML feedback of ``kinds`` (see :meth:`Scene.on`),
        as frames are evaluated."""
        return self.scene.on(kinds, callback)

    @property
    def last_frame(self) -> LiveFrame | None:
        """The frame shown last (None before the first)."""
        return self._last

    # -- BML ------------------------------------------------------------------------------------------
    def parse(self, character: str | None, bml) -> list:
        """Parse ``bml`` (text, bytes or a document) into its blocks, each with its character (``character``
        or the one it names), put them through the scene's BML generators (their ``generatedBml`` feedback
        is given here) and synthesize their speech, once, with what the generators marked in it; runs on
        the caller's thread. :class:`~infuse.errors.InputError` for malformed XML, :class:`UsageError` for
        unknown characters. Begins between two blocks (:meth:`_wait_for_a_gap`)."""
        self._wait_for_a_gap()
        document = bml if isinstance(bml, BmlDocument) else parse_bml(bml)
        blocks = []
        for block in document.blocks:
            name = character if character is not None else block.character_id
            if name is None:
                raise UsageError(f"block {block.id!r} names no character; give the character")
            resolved = self.scene.resolve_name(name)
            if resolved not in self.scene.characters:
                raise UsageError(f"no character {name!r}; characters: {', '.join(self.scene.characters) or 'none'}")
            blocks.append(replace(block, character_id=resolved))
        blocks = [generated for block in blocks for generated in self.scene.scheduler.generate(block)]
        self.prepare(blocks)
        return blocks

    def prepare(self, blocks) -> None:
        """Synthesize the speech of ``blocks`` (parsed, with their characters, generated) ahead, and let
        the controllers that realize their behaviours work out what they can ahead
        (:attr:`~infuse.plugin_types.ControllerFactory.prepare`: a walk plans its path), on this thread.
        What a controller cannot prepare is left to the loop, which realizes it and reports its problems."""
        from . import registry

        elements = {b.element for block in blocks for b in block.behaviours}
        # Scheduled on a scratch planner (0.5 ms for a nod) only for speech, or for behaviours whose
        # controllers prepare, or may (an element not scheduled here yet)
        if "speech" not in elements and all(self._preparing.get(element) is False for element in elements):
            return
        planner = Scheduler(speech_timer=self._speech, locate=self.scene.locate)
        for block in blocks:
            self._speech.local.character = block.character_id
            try:
                record = planner.schedule_block(block, 0.0, block.character_id)
            finally:
                self._speech.local.character = None
            for activation in record.activations:
                try:
                    descriptor = registry.realizer(activation.controller)
                    prepare = descriptor.prepare if descriptor is not None else None
                    self._preparing[activation.element] = prepare is not None or self._preparing.get(activation.element, False)
                    if prepare is not None:
                        prepare(activation, self.scene.stage)
                except Exception:  # noqa: BLE001 - only a head start: the loop realizes it and reports why not
                    continue

    def bml(self, character: str | None, bml) -> list[str]:
        """Schedule BML from the next frame on; returns the block ids. Runs on the caller's thread up to
        the scheduling itself (parse, speech synthesis)."""
        return self.call(self.schedule, self.parse(character, bml), kind="bml")

    def schedule(self, blocks) -> list[str]:
        """Schedule blocks returned by :meth:`parse` now (on the loop thread: inside :meth:`submit`);
        their ids (the generators' blocks for other characters included)."""
        ids = []
        for block in blocks:
            self._speech.local.character = block.character_id
            try:
                ids.append(self.scene.bml(block.character_id, BmlDocument((block,)), generated=True))
            finally:
                self._speech.local.character = None
        return ids

    def _voice_of(self, character: str | None) -> str | None:
        entry = self.scene.characters.get(character) if character else None
        return entry.voice if entry is not None else None

    # -- the builder, live ----------------------------------------------------------------------------
    #: Scene builder methods a live scene offers, each starting on the next frame.
    BUILDER = ("say", "gaze", "head", "nod", "shake", "expression", "walk_to", "reach", "point", "grab", "release")

    def prepare_call(self, method: str, character: str, arguments: dict) -> list | None:
        """Check a builder call, on the caller's thread. A ``say`` is made into its block here (the scene's
        ``say``, its id taken now), parsed and prepared (:meth:`parse`); its blocks are returned, for
        :meth:`builder_call`. So are the other calls' blocks, written as the scene's builder writes them,
        unless the call gives ``at`` (a walk too: it is planned from where the character will be then),
        names a point (it becomes a scene target on the loop) or fails (the loop makes it, and raises its
        error); None then."""
        if method not in self.BUILDER:
            raise UsageError(f"no live builder method {method!r}; methods: {', '.join(self.BUILDER)}")
        name = self.scene.resolve_name(character)
        if name not in self.scene.characters:
            raise UsageError(f"no character {character!r}; characters: {', '.join(self.scene.characters) or 'none'}")
        if method == "walk_to" and arguments.get("at") is None:  # its path is planned here (prepare), not on the loop's thread
            try:
                written = _Written(self.scene).walk_to(name, **arguments)
            except TypeError as exc:
                raise UsageError(f"{method}: {exc}") from None
            return self.parse(name, written)
        if method != "say":
            return self._written_ahead(method, name, arguments)
        text = arguments.get("text")
        if not isinstance(text, str):
            raise UsageError("say needs the text to speak")
        unknown = set(arguments) - {"text", "voice"}
        if unknown:
            raise UsageError(f"say takes text and voice, not {', '.join(sorted(unknown))}")
        content = builder.element("text", {}, builder.speech_text(text))
        speech = builder.element("speech", {"id": "s1", "voice": arguments.get("voice")}, content)
        return self.parse(name, builder.block(self.scene.block_id("say"), name, speech))

    def _written_ahead(self, method: str, name: str, arguments: dict) -> list | None:
        """A builder call's blocks, written and parsed on this thread (see :meth:`prepare_call`), or None."""
        if arguments.get("at") is not None:
            return None
        try:
            written = getattr(_Written(self.scene), method)(name, **arguments)
        except Exception:  # noqa: BLE001 - the loop makes the call itself and raises its error there, as ever
            return None
        return self.parse(name, written)

    def builder_call(self, method: str, character: str, arguments: dict, prepared: list | None = None) -> str:
        """Run a builder method of the scene now (on the loop thread: inside :meth:`submit`); the block id.
        ``prepared``: what :meth:`prepare_call` returned (the call's blocks, scheduled as they are)."""
        if method not in self.BUILDER:
            raise UsageError(f"no live builder method {method!r}; methods: {', '.join(self.BUILDER)}")
        if prepared is not None:
            return self.schedule(prepared)[0]
        self._speech.local.character = self.scene.resolve_name(character)
        try:
            return getattr(self.scene, method)(character, **arguments)
        finally:
            self._speech.local.character = None

    def _build(self, method: str, character: str, **arguments) -> str:
        arguments = {k: v for k, v in arguments.items() if v is not None}
        prepared = self.prepare_call(method, character, arguments)
        return self.call(self.builder_call, method, character, arguments, prepared, kind=method)

    def say(self, character: str, text: str, voice: str | None = None) -> str:
        """Speak ``text`` from the next frame (BML ``<sync id="..."/>`` marks allowed); returns the block id."""
        return self._build("say", character, text=text, voice=voice)

    def gaze(self, character: str, target, duration: float | None = None, influence: str = "HEAD") -> str:
        """Look at ``target`` (a name or a point) from the next frame (see :meth:`Scene.gaze`)."""
        return self._build("gaze", character, target=target, duration=duration, influence=influence)

    def head(self, character: str, lexeme: str = "NOD", repeats: float = 1.0, amount: float = 0.5) -> str:
        """NOD, SHAKE, TOSS, TILT, WIGGLE or WAGGLE from the next frame."""
        return self._build("head", character, lexeme=lexeme, repeats=repeats, amount=amount)

    def nod(self, character: str, repeats: float = 1.0, amount: float = 0.5) -> str:
        return self._build("nod", character, repeats=repeats, amount=amount)

    def shake(self, character: str, repeats: float = 2.0, amount: float = 0.5) -> str:
        return self._build("shake", character, repeats=repeats, amount=amount)

    def expression(self, character: str, lexeme: str, amount: float = 0.7, duration: float | None = None) -> str:
        """A facial expression (``smile``, ``RAISE_BROWS``...) from the next frame."""
        return self._build("expression", character, lexeme=lexeme, amount=amount, duration=duration)

    def walk_to(self, character: str, target, manner: str = "walk", speed: float | None = None) -> str:
        """Walk to a point (x, z) / (x, y, z) or a named object or character from the next frame (its path
        planned on this thread, before the command reaches the loop)."""
        return self._build("walk_to", character, target=target, manner=manner, speed=speed)

    def reach(self, character: str, target, action: str = "touch", hand: str | None = None) -> str:
        """Reach for an object from the next frame."""
        return self._build("reach", character, target=target, action=action, hand=hand)

    def point(self, character: str, target, hand: str | None = None) -> str:
        """Point at ``target`` (a name or a point) with ``hand`` (left, right, both) from the next frame."""
        return self._build("point", character, target=target, hand=hand)

    def grab(self, character: str, obj: str, hand: str | None = None) -> str:
        """Take object ``obj`` in a hand (left or right) and hold it, from the next frame."""
        return self._build("grab", character, obj=obj, hand=hand)

    def release(self, character: str, obj: str | None = None) -> str:
        """Let go of what the character holds (``obj``: only that object) from the next frame."""
        return self._build("release", character, obj=obj)

    # -- the cast, live -------------------------------------------------------------------------------
    def add_character(self, source, name: str | None = None, *, position=(0.0, 0.0, 0.0), facing=None,
                      packs: Iterable[str] = (), voice: str | None = None, idle: bool | None = None) -> str:
        """Add a character while the scene runs (see :meth:`Scene.add_character`); returns its name.

        Its file is read and mapped on the caller's thread; it joins the scene between two frames, on the
        loop thread, where its packs are infused (with the scene's ``pack_cache`` they are infused here
        first, and the loop only reads them back); then its first walk and reach are prepared here."""
        from .asset import Asset, Character
        from .fileio import load
        from .mapping import map_skeleton
        from .packs import infuse_character

        if isinstance(source, Character):
            character = source
        else:
            asset = source if isinstance(source, Asset) else load(source)
            stem = asset.path.stem if asset.path is not None else "character"
            character = Character(name or stem, asset, map_skeleton(asset))
        packs = (packs,) if isinstance(packs, str) else tuple(packs)
        if packs and self.scene.pack_cache is not None:
            infuse_character(character, list(packs), mapping=character.mapping, cache=self.scene.pack_cache)
        # measured here (skinning its feet), not on the loop thread; a character mapped only as it joins is
        # measured there
        height = None if character.mapping is None else _rest_foot_height(character.asset, character.mapping)

        def join() -> str:
            added = self.scene.add_character(character, name, position=position, facing=facing, packs=packs,
                                             voice=voice, idle=idle)
            if height is not None:
                self._grounds[added] = height
            return added
        added = self.call(join, timeout_s=120.0, kind="add")
        self._warm_up(added)
        return added

    # -- targets --------------------------------------------------------------------------------------
    def move_target(self, name: str, position) -> float:
        """Put the named target ``name`` at ``position`` (x, y, z) metres from the next frame on (it is
        added when new); returns the scene time (seconds) from which it stands there."""
        point = np.asarray(position, dtype=np.float64).reshape(-1)
        if point.shape != (3,) or not np.all(np.isfinite(point)):
            raise UsageError(f"target {name!r}: a position is three finite numbers (x, y, z) metres, got {position!r}")
        return self.call(self.place_target, str(name), point, kind="target")

    def place_target(self, name: str, point) -> float:
        """Put target ``name`` at ``point`` (3,) metres now (on the loop thread: inside :meth:`submit`);
        the scene time from which it stands there."""
        point = np.asarray(point, dtype=np.float64)
        target = self._movable.get(name)
        if target is None:
            target = self._movable[name] = MovableTarget(point)
            self.scene.add_target(name, target)
        target.point = point
        return self.scene.time


class _Written(builder.BuilderCalls):
    """The scene builder's block for a call, written as XML text, not scheduled; its block id taken from
    the scene, the names it gives as targets spelled as the scene spells them."""

    def __init__(self, scene: Scene):
        self.scene = scene

    def _submit(self, character: str, what: str, behaviour: str, at, composition: str = "MERGE") -> str:
        return builder.block(self.scene.block_id(what), character, behaviour, composition)

    def _target_name(self, target) -> str:
        if isinstance(target, str):
            return self.scene.resolve_name(target)
        raise UsageError("only calls that name no point are written ahead")


def _rest_foot_height(asset, mapping) -> float:
    """The lowest point (m) of a character's feet at rest, soles included (:func:`~infuse.grounding.foot_height`);
    0 for a character without both legs mapped (it is not grounded)."""
    try:
        return foot_height(asset, mapping)
    except UnusableInputError:
        return 0.0


class MovableTarget(Target):
    """A named target a client moves: it stands at :attr:`point` (3,) metres for every frame evaluated
    after the move (frames are evaluated as time goes, so the latest move holds)."""

    def __init__(self, point):
        self.point = np.asarray(point, dtype=np.float64)

    def positions(self, times, block=None) -> np.ndarray:
        """(F, 3) metres: the point at every time of ``times`` (F,)."""
        return np.broadcast_to(self.point, (len(times), 3)).copy()


_switching = {"scenes": 0, "before": None}  # live scenes running, and the switch interval before the first
_switching_lock = threading.Lock()


def _switch_often(starting: bool) -> None:
    """Threads switch every :data:`SWITCH_INTERVAL_S` (at most) while a live scene runs; the interval the
    process had is back once the last one stops."""
    with _switching_lock:
        if starting:
            if _switching["scenes"] == 0:
                _switching["before"] = sys.getswitchinterval()
                sys.setswitchinterval(min(sys.getswitchinterval(), SWITCH_INTERVAL_S))
            _switching["scenes"] += 1
        elif _switching["scenes"] > 0:
            _switching["scenes"] -= 1
            if _switching["scenes"] == 0 and _switching["before"] is not None:
                sys.setswitchinterval(_switching["before"])
