"""The scheduler: BML blocks in, plain timed activations and feedback out.

A :class:`Scheduler` keeps the blocks it was given, per character, so composition works across blocks:
MERGE starts a block at its submission time, APPEND after the character's scheduled blocks end,
REPLACE interrupts them first (ASAP's ``bmla:appendAfter``, ``bmla:chunkAfter`` and ``bmla:interrupt``
name the blocks explicitly). Each behaviour becomes an :class:`Activation`: the controller kind, its
parameters and the global time of every sync point, for controllers to realize. Feedback goes to
``scheduler.feedback`` subscribers: warnings and predictions at once, progress as :meth:`Scheduler.advance`
moves the clock. Before a block is scheduled, the BML generators it turns on (or the scheduler's
``generators``) add behaviours to it (:meth:`Scheduler.generate`, :mod:`infuse.bml.generate`).
"""
from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from .. import limits
from ..errors import InfuseError, UsageError
from .behaviours import BehaviourContext, BehaviourError, installed_handlers
from .feedback import BlockPrediction, BlockProgress, FeedbackBus, GeneratedBml, SyncPointProgress, WarningFeedback
from .generate import PREFIX, GenerationError, GeneratorContext, block_seed, choose, installed_generators, with_issues
from .model import (
    BEHAVIOR_TYPE_NOT_SUPPORTED, CANNOT_CREATE_BEHAVIOR, CUSTOM_ATTRIBUTE_NOT_SUPPORTED, CUSTOM_BEHAVIOUR_NOT_SUPPORTED,
    DIALECT_BML1, IMPOSSIBLE_TO_SCHEDULE, PARSING_FAILURE, Block, BmlDocument, Issue,
)
from .parse import parse_bml, parse_bml_file
from .solve import BlockSolver
from .speech import EngineSpeechTimer, EstimatedSpeechTimer
from .sync import SyncRef, TimingModel


@dataclass(frozen=True)
class Activation:
    """One behaviour to realize: plain timed data for a controller.

    ``sync_times``: sync id -> global seconds, in the behaviour's temporal order (``start`` first, ``end``
    last); ``controller``: the controller kind; ``parameters``: what it needs (JSON-friendly);
    ``persistent``: the effect stays after ``end``; ``stop_s``: set when a later block interrupted it;
    ``sync_aliases``: other names of its sync points (``"ready"`` -> ``"attackPeak"``).
    """

    character: str | None
    block: str
    behaviour: str
    element: str
    controller: str
    parameters: dict
    sync_times: dict
    persistent: bool = False
    required: bool = False
    stop_s: float | None = None
    sync_aliases: dict = field(default_factory=dict)

    def time(self, sync: str) -> float | None:
        """Global time of sync point ``sync`` (any of its names), or None."""
        name = sync if sync in self.sync_times else self.sync_aliases.get(sync)
        return self.sync_times.get(name) if name else None

    @property
    def start(self) -> float:
        return self.sync_times["start"]

    @property
    def end(self) -> float:
        return self.sync_times["end"]

    def as_dict(self) -> dict:
        return {"character": self.character, "block": self.block, "behaviour": self.behaviour, "element": self.element,
                "controller": self.controller, "parameters": self.parameters, "sync_times": dict(self.sync_times),
                "persistent": self.persistent, "required": self.required, "stop_s": self.stop_s,
                "sync_aliases": dict(self.sync_aliases)}


@dataclass
class BlockSchedule:
    """A scheduled block: global start and end (seconds), its activations, what was dropped and why."""

    block: Block
    character: str | None
    start_s: float
    end_s: float
    activations: tuple = ()
    issues: tuple = ()
    failed: str | None = None
    interrupted_at: float | None = None

    @property
    def id(self) -> str:
        return self.block.id

    def activation(self, behaviour_id: str) -> Activation | None:
        return next((a for a in self.activations if a.behaviour == behaviour_id), None)

    def local_times(self) -> dict:
        """Behaviour id -> {sync id: seconds from the block start}."""
        return {a.behaviour: {s: t - self.start_s for s, t in a.sync_times.items()} for a in self.activations}


#: Speech texts a scheduler remembers for generators once it forgets (:meth:`Scheduler.forget`).
SAID_KEPT = 100

# Order of simultaneous progress events: a block starts before its sync points pass, and ends after them.
_RANK_BLOCK_START, _RANK_SYNC, _RANK_BLOCK_END = 0, 1, 2


@dataclass
class Scheduler:
    """Schedules BML blocks for one scene (any number of characters).

    ``handlers``: element -> handler (default: the installed BML behaviour plugins); ``speech_timer``:
    a :class:`~infuse.bml.speech.SpeechTimer` or a TTS engine (real timings), an estimate from the text
    when None; ``clip_timing`` and ``locate``: see
    :class:`~infuse.bml.behaviours.BehaviourContext`. ``generators``: names of BML generators on for every
    block (a block turns one off with ``infuse:NAME="false"``); ``names()`` -> {name: ``"character"`` or
    ``"object"``} tells them who and what is in the scene; ``seed`` makes their random choices repeatable;
    ``generator_table``: name -> generator (default: the installed ones, loaded when first needed).
    """

    handlers: dict | None = None
    speech_timer: object = None
    clip_timing: object = None
    locate: object = None
    feedback: FeedbackBus = field(default_factory=FeedbackBus)
    now: float = 0.0
    generators: tuple = ()
    names: object = None
    seed: int = 0
    generator_table: dict | None = None

    def __post_init__(self):
        if self.handlers is None:
            self.handlers = installed_handlers()
        self.generators = tuple(self.generators)
        if self.generators:
            unknown = [name for name in self.generators if name not in self._generator_table()]
            if unknown:
                raise UsageError(f"no BML generator named {', '.join(map(repr, unknown))}; installed: "
                                 f"{', '.join(sorted(self._generator_table())) or 'none'}")
        if self.speech_timer is None:
            self.speech_timer = EstimatedSpeechTimer()
        elif not hasattr(self.speech_timer, "time_speech") and hasattr(self.speech_timer, "synthesize"):
            self.speech_timer = EngineSpeechTimer(self.speech_timer)  # a TTS engine given directly
        self.blocks: dict[str, BlockSchedule] = {}
        self._said: list[str] = []  # the text of every speech scheduled so far, for generators
        self._pending: list = []
        self._sequence = itertools.count()
        self._cut: list[BlockSchedule] = []  # blocks interrupted since the last take_interrupted()

    # -- input ----------------------------------------------------------------------------------------------
    def submit(self, bml, at: float | None = None, character: str | None = None) -> list[BlockSchedule]:
        """Schedule every block of ``bml`` (XML text or bytes, a :class:`~pathlib.Path`, a parsed document or
        block) at global time ``at`` (default: now). ``character`` applies to blocks that name none.
        Malformed XML raises :class:`~infuse.errors.InputError`; everything else becomes warningFeedback."""
        if isinstance(bml, Path):
            bml = parse_bml_file(bml)
        elif isinstance(bml, (str, bytes)):
            bml = parse_bml(bml)
        blocks = bml.blocks if isinstance(bml, BmlDocument) else (bml,)
        at = self.now if at is None else float(at)
        return [self.schedule_block(b, at, character) for block in blocks for b in self.generate(block, character)]

    # -- generation -----------------------------------------------------------------------------------------
    def _generator_table(self) -> dict:
        if self.generator_table is None:
            self.generator_table = installed_generators()
        return self.generator_table

    def generate(self, block: Block, character: str | None = None) -> list[Block]:
        """``block`` with what the generators it turns on add, then the blocks they make for other characters
        (to schedule in this order, at the same time). Each generator's BML is delivered as ``generatedBml``
        feedback; what goes wrong becomes warnings of the block."""
        if not self.generators and not any(key.startswith(PREFIX) for key in block.attributes):
            return [block]
        character = block.character_id or character
        generators, settings, issues = choose(block, self.generators, self._generator_table())
        extra: list[Block] = []
        names = self.names() if self.names is not None else {}
        for generator in generators:
            context = GeneratorContext(
                character, block.dialect, tuple(n for n, kind in names.items() if kind == "character"),
                tuple(n for n, kind in names.items() if kind == "object"), self.locate or (lambda name: None),
                block_seed(self.seed, block, character), settings[generator.name], tuple(self._said))
            try:
                generation = generator.generate(block, context)
            except (GenerationError, InfuseError) as exc:
                issues.append(Issue(block.id, CANNOT_CREATE_BEHAVIOR, f"generator {generator.name!r} added nothing: {exc}",
                                    block.line))
                continue
            except Exception as exc:  # a third-party generator's bug must not stop the block
                issues.append(Issue(block.id, CANNOT_CREATE_BEHAVIOR, f"generator {generator.name!r} failed "
                                    f"({type(exc).__name__}: {exc}); the block plays without it", block.line))
                continue
            block = generation.block
            extra += generation.blocks
            issues += [Issue(block.id, CANNOT_CREATE_BEHAVIOR, note, block.line) for note in generation.notes]
            if generation.bml:
                self.feedback.emit(GeneratedBml(block.id, generator.name, generation.bml, character))
        return [with_issues(block, issues), *extra]

    def schedule_block(self, block: Block, at: float, character: str | None = None) -> BlockSchedule:
        character = block.character_id or character
        issues = list(block.issues)
        if block.id in self.blocks:
            issues.append(Issue(block.id, PARSING_FAILURE, "a block with this id was scheduled before; references now mean this one", block.line))
        context = BehaviourContext(character=character, dialect=block.dialect, speech_timer=self.speech_timer,
                                   **{k: v for k, v in (("clip_timing", self.clip_timing), ("locate", self.locate)) if v})
        plans, unavailable, failed = {}, {}, None
        for b in block.behaviours:
            reason = self._plan(block, b, context, plans, issues)
            if reason:
                unavailable[b.id] = reason
                if b.required:
                    failed = f"required behaviour {b.id!r} cannot be realized: {reason}"
        start = self._compose(block, at, character, issues)
        if failed is None:
            solver = BlockSolver(block, plans, unavailable, lambda ref: self._external(ref, start),
                                 allow_negative_start=block.dialect != DIALECT_BML1)
            solution = solver.solve()
            issues.extend(solution.issues)
            failed = solution.failed
        if failed:
            issues.append(Issue(block.id, IMPOSSIBLE_TO_SCHEDULE, f"block not executed: {failed}", block.line))
            record = BlockSchedule(block, character, start, start, (), tuple(issues), failed=failed)
        else:
            activations = tuple(
                Activation(character, block.id, b.id, b.element, plans[b.id].controller, plans[b.id].parameters,
                           {s: start + t for s, t in solution.times[b.id].items()}, plans[b.id].persistent, b.required,
                           sync_aliases=dict(plans[b.id].timing.aliases))
                for b in block.behaviours if b.id in solution.times)
            end = max([start] + [a.end for a in activations])
            latest = max([abs(start), abs(end)] + [abs(t) for a in activations for t in a.sync_times.values()])
            if not latest <= limits.MAX_TIME_S:
                failed = (f"block not executed: it reaches {latest:g} s, past the limit of {limits.MAX_TIME_S:g} s "
                          "(infuse.limits.MAX_TIME_S)")
                issues.append(Issue(block.id, IMPOSSIBLE_TO_SCHEDULE, failed, block.line))
                record = BlockSchedule(block, character, start, start, (), tuple(issues), failed=failed)
            else:
                record = BlockSchedule(block, character, start, end, activations, tuple(issues))
        self.blocks[block.id] = record
        self._said += [a.parameters["text"] for a in record.activations
                       if a.controller == "speech" and a.parameters.get("text")]
        for issue in record.issues:
            self.feedback.emit(WarningFeedback(issue.id, issue.type, issue.description, character, issue.line))
        if not record.failed:
            self.feedback.emit(BlockPrediction(block.id, record.start_s, record.end_s, character))
            self._queue_progress(record)
        return record

    def _plan(self, block, b, context, plans, issues) -> str | None:
        """Build ``b``'s plan into ``plans``; returns why it cannot be realized, or None."""
        where = f"{block.id}:{b.id}"
        handler = self.handlers.get(b.element)
        if handler is None:
            custom = ":" in b.element or b.element.startswith("{")
            issues.append(Issue(where, CUSTOM_BEHAVIOUR_NOT_SUPPORTED if custom else BEHAVIOR_TYPE_NOT_SUPPORTED,
                                f"<{b.element}> is not supported; the behaviour is skipped", b.line))
            return f"<{b.element}> is not supported"
        if b.sync_errors:
            text = "; ".join(b.sync_errors.values())
            issues.append(Issue(where, PARSING_FAILURE, f"invalid sync reference, the behaviour is skipped: {text}", b.line))
            return "it has an invalid sync reference"
        accepted = handler.attributes
        if accepted is not None:
            for name in b.attributes:
                if name not in accepted:
                    issues.append(Issue(where, CUSTOM_ATTRIBUTE_NOT_SUPPORTED,
                                        f"attribute {name!r} of <{b.element}> is not supported and is ignored", b.line))
        try:
            plan = handler.plan(b, context)
        except BehaviourError as exc:
            issues.append(Issue(where, CANNOT_CREATE_BEHAVIOR, f"<{b.element}> cannot be realized: {exc}", b.line))
            return str(exc)
        except Exception as exc:  # a third-party handler's bug must not stop the rest of the block
            issues.append(Issue(where, CANNOT_CREATE_BEHAVIOR,
                                f"the <{b.element}> handler failed ({type(exc).__name__}: {exc}); the behaviour is skipped", b.line))
            return "its handler failed"
        for note in plan.notes:
            issues.append(Issue(where, CUSTOM_ATTRIBUTE_NOT_SUPPORTED, note, b.line))
        plans[b.id] = plan
        return None

    # -- composition ----------------------------------------------------------------------------------------
    def _compose(self, block: Block, at: float, character, issues) -> float:
        """The block's global start time; interrupts what REPLACE and ``bmla:interrupt`` say."""
        start = at
        if block.composition == "REPLACE":
            for record in self._own(block, character):
                if record.end_s > at:
                    self.interrupt(record.id, at)
        for name in block.interrupts:
            if name in self.blocks:
                self.interrupt(name, at)
            else:
                issues.append(Issue(block.id, PARSING_FAILURE, f"bmla:interrupt names unknown block {name!r}", block.line))
        if block.composition == "APPEND":
            start = max([at] + [self._effective_end(r) for r in self._own(block, character)])
        for name in block.append_after:
            if name in self.blocks:
                start = max(start, self._effective_end(self.blocks[name]))
            else:
                issues.append(Issue(block.id, PARSING_FAILURE, f"block {name!r} to append after is unknown; not waiting for it", block.line))
        return start

    def _own(self, block: Block, character) -> list[BlockSchedule]:
        """The character's other blocks scheduled so far (not failed): what REPLACE and APPEND compose with."""
        return [r for r in self.blocks.values() if r.character == character and not r.failed and r.id != block.id]

    @staticmethod
    def _effective_end(record: BlockSchedule) -> float:
        return record.interrupted_at if record.interrupted_at is not None else record.end_s

    def interrupt(self, block_id: str, at: float) -> None:
        """Stop block ``block_id`` at global time ``at``: its activations get ``stop_s``, its later feedback is
        withdrawn and its end is reported at ``at``."""
        record = self.blocks[block_id]
        if record.failed or self._effective_end(record) <= at:
            return
        record.interrupted_at = at
        record.activations = tuple(a if a.end <= at and not a.persistent else replace(a, stop_s=at)
                                   for a in record.activations)
        self._cut.append(record)
        started = record.start_s <= at
        self._pending = [p for p in self._pending if not (p[4] == block_id and p[0] > at)]
        heapq.heapify(self._pending)
        if started:
            self._push(at, _RANK_BLOCK_END, block_id, BlockProgress(block_id, "end", at, record.character))
        else:
            self._pending = [p for p in self._pending if p[4] != block_id]
            heapq.heapify(self._pending)
            self.feedback.emit(WarningFeedback(block_id, IMPOSSIBLE_TO_SCHEDULE, "block interrupted before it started",
                                               record.character))

    def take_interrupted(self) -> list[BlockSchedule]:
        """The blocks :meth:`interrupt` cut since the last call, each once, in the order first cut (those let
        go or scheduled again under their id since left out): what plays them is to stop."""
        cut, self._cut = self._cut, []
        taken: dict[int, BlockSchedule] = {}
        for record in cut:
            if self.blocks.get(record.id) is record:
                taken.setdefault(id(record), record)
        return list(taken.values())

    def _external(self, ref: SyncRef, block_start: float) -> float | None:
        record = self.blocks.get(ref.block)
        activation = record.activation(ref.behaviour) if record else None
        if activation is None:
            return None
        ids = tuple(activation.sync_times)
        offsets = tuple(activation.sync_times[s] - activation.start for s in ids)
        sync = TimingModel(ids, offsets, aliases=activation.sync_aliases).resolve(ref.sync, ref.iteration)
        return None if sync is None else activation.sync_times[sync] + ref.offset - block_start

    # -- feedback -------------------------------------------------------------------------------------------
    def _push(self, time: float, rank: int, block_id: str, event) -> None:
        heapq.heappush(self._pending, (time, rank, next(self._sequence), event, block_id))

    def _queue_progress(self, record: BlockSchedule) -> None:
        c, block_id, start = record.character, record.id, record.start_s
        self._push(start, _RANK_BLOCK_START, block_id, BlockProgress(block_id, "start", start, c))
        for a in record.activations:
            for sync, t in a.sync_times.items():
                self._push(t, _RANK_SYNC, block_id, SyncPointProgress(block_id, a.behaviour, sync, t - start, t, c))
        self._push(record.end_s, _RANK_BLOCK_END, block_id, BlockProgress(block_id, "end", record.end_s, c))

    def advance(self, to_time: float) -> list:
        """Move the clock to ``to_time`` (global seconds) and deliver the progress feedback up to it, in order."""
        delivered = []
        while self._pending and self._pending[0][0] <= to_time:
            event = heapq.heappop(self._pending)[3]
            self.feedback.emit(event)
            delivered.append(event)
        if math.isfinite(to_time):
            self.now = max(self.now, to_time)
        return delivered

    def flush(self) -> list:
        """Deliver every pending progress event (the clock runs to the end of everything scheduled)."""
        end = max([self.now] + [p[0] for p in self._pending])
        return self.advance(end)

    def forget(self, before_s: float, said: int = SAID_KEPT) -> None:
        """Keep memory bounded in a scheduler that runs for hours (a live scene): let go of the blocks that
        ended, were cut or failed before ``before_s`` seconds and have no feedback left to deliver, and of
        all but the last ``said`` speech texts (what generators see as said before). A block let go is
        unknown from then on: a later ``bmla:interrupt`` or ``appendAfter`` naming it warns, as for a
        name never scheduled."""
        waiting = {p[4] for p in self._pending}
        gone = [block_id for block_id, record in self.blocks.items() if block_id not in waiting
                and (record.failed or self._effective_end(record) < before_s)]
        for block_id in gone:
            del self.blocks[block_id]
        self._cut = [record for record in self._cut if self.blocks.get(record.id) is record]
        if len(self._said) > said:
            del self._said[:len(self._said) - said]

    # -- output ---------------------------------------------------------------------------------------------
    def activations(self, character: str | None = None) -> list[Activation]:
        """Every activation of scheduled blocks (of ``character`` if given), ordered by start time."""
        out = [a for r in self.blocks.values() for a in r.activations if character is None or r.character == character]
        return sorted(out, key=lambda a: (a.start, a.block, a.behaviour))
