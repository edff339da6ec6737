"""The controller contract: what a controller plugin builds and the runtime calls.

A :class:`Controller` is one behaviour for one character (a look at a target, a nod, a clip). The
runtime plays it as an :class:`~infuse.runtime.runtime.Activity` between two times, and evaluates
frames in blocks: for each block, every activity of one controller class, layer and priority, over
all characters, is handed to the class at once (``evaluate(jobs, block)``), so a controller can
batch its work over characters and vectorize it over frames. A :class:`Job` is one activity's share
of the block: its character's pose so far, its weight per frame and its persistent state.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

import numpy as np

from .layers import Layer, Mode
from .pose import PoseBlock, PoseTable

State = TypeVar("State")


@dataclass
class Block:
    """The frames being evaluated: ``frames`` (F,) indices and ``times`` (F,) seconds (``frames / fps``);
    ``poses``: each character's :class:`PoseBlock`, views of ``table`` (every character's pose side by side)."""

    runtime: Any
    frames: np.ndarray
    times: np.ndarray
    fps: float
    poses: dict
    table: PoseTable

    @property
    def dt(self) -> float:
        return 1.0 / self.fps

    def __len__(self) -> int:
        return len(self.frames)

    def pose(self, character: str) -> PoseBlock:
        """The :class:`PoseBlock` of a character, as built so far in this block."""
        return self.poses[character]


@dataclass
class Job:
    """One activity in one block: ``pose`` to write, ``weight`` (F,) of the activity, ``local_times``
    (F,) seconds since the activity's start."""

    activity: Any
    pose: PoseBlock
    weight: np.ndarray
    local_times: np.ndarray

    @property
    def controller(self) -> "Controller":
        return self.activity.controller

    @property
    def rig(self):
        return self.activity.rig

    @property
    def binding(self):
        return self.activity.binding

    @property
    def state(self) -> dict:
        return self.activity.state

    def state_of(self, kind: type[State]) -> State:
        """The activity's typed state of class ``kind`` (see :meth:`Activity.state_of
        <infuse.runtime.runtime.Activity.state_of>`)."""
        return self.activity.state_of(kind)

    @property
    def mode(self) -> Mode:
        return self.activity.mode

    def report(self, message: str) -> None:
        """Report something about this character once (see :meth:`Runtime.report`)."""
        self.activity.runtime.report(self.rig.name, message)


class Jobs(list):
    """Every job of one controller class, layer and priority in a block (a list of :class:`Job`), with
    what a class evaluating them together needs at hand: ``weights`` (N, F) and ``local_times`` (N, F),
    the jobs' own stacked, ``table``, the block's :class:`~infuse.runtime.pose.PoseTable`, and :meth:`memo`
    (``ids``: the jobs' activities' ids, when the caller has them)."""

    def __init__(self, jobs, weights: np.ndarray, local_times: np.ndarray, table: PoseTable, memo: list,
                 ids: tuple | None = None):
        super().__init__(jobs)
        self.weights = weights
        self.local_times = local_times
        self.table = table
        self._memo = memo
        self._ids = ids

    def memo(self, make, chosen=None):
        """``make(jobs)``, worked out again only when these jobs (or the ``chosen`` ones among them) are
        not the activities they were at the last call (for what depends only on the activities: their
        bindings stacked, their settings)."""
        jobs = self if chosen is None else chosen
        key = self._ids if chosen is None and self._ids is not None else tuple(job.activity.id for job in jobs)
        if self._memo[0] != key:
            self._memo[:] = [key, make(jobs)]
        return self._memo[1]

    def last(self):
        """What :meth:`memo` made last for this class, layer and priority (None before it made anything):
        what a class working something out again for other activities may take over parts of."""
        return self._memo[1]


def table_columns(jobs: Jobs, indices, morphs: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """Where each job's joints ``indices`` (a sequence of (K_i,) index arrays, one per job; with
    ``morphs``, morph target columns) sit in the jobs' table: (K,) table columns side by side and (K,)
    the job of each; None when two jobs share a character (they then apply one after the other, not
    side by side)."""
    names = [job.rig.name for job in jobs]
    if len(set(names)) < len(names):
        return None
    first = jobs.table.first_morph if morphs else jobs.table.first_joint
    columns = [np.asarray(i, dtype=np.int64) + first[name] for i, name in zip(indices, names)]
    return (np.concatenate(columns) if columns else np.zeros(0, dtype=np.int64),
            np.repeat(np.arange(len(columns)), [len(c) for c in columns]))


class Controller:
    """Base class of runtime controllers.

    Class attributes give the defaults an activity takes unless told otherwise: ``kind`` (the name
    BML activations use), ``layer``, ``mode``, ``priority``, ``blend_in_s`` / ``blend_out_s``
    (seconds), and ``settle_s``: how long after its end an activity is still evaluated (a smoothed
    controller returning to rest). ``speaks`` marks controllers that make the character speak;
    ``duration_s`` (None: open-ended) is how long an activity given no end lasts.

    Subclasses implement :meth:`bind` (per character: which joints, what is missing) and either
    :meth:`evaluate_one` (one job, vectorized over frames) or the class-level :meth:`evaluate` (all
    jobs of the class at once, to batch over characters).
    """

    kind: ClassVar[str] = "controller"
    layer: Layer = Layer.BASE  # per class, or per instance (keyed curves choose theirs)
    mode: ClassVar[Mode] = Mode.OVERRIDE
    priority: ClassVar[int] = 0
    # Per class, or per instance (a gesture's blends follow its phases, a look settles at its own speeds).
    blend_in_s: float = 0.3
    blend_out_s: float = 0.3
    settle_s: float = 0.0
    speaks: bool = False  # per class, or per instance
    #: Natural length in seconds (a nod, a clip played once): an activity without an end lasts this long.
    duration_s: float | None = None
    #: True for a class whose evaluate reads and writes only its own jobs' characters' poses, each job as
    #: it would alone: the runtime then evaluates its activities of different priorities in one call,
    #: where no character of one runs between them (a walk of priority 4 with another character's of 2).
    own_characters_only: ClassVar[bool] = False
    #: About how long one evaluate call takes in a block of one frame, whatever its jobs (milliseconds):
    #: where each character's order leaves a choice, the runtime joins the calls of the costlier class.
    call_ms: ClassVar[float] = 0.1

    def bind(self, rig, report) -> Any:
        """Prepare for character ``rig``; return what :meth:`evaluate_one` needs (kept on the activity).

        Call ``report(message)`` for a feature the character lacks (it is reported once); raise
        :class:`~infuse.errors.MissingFeatureError` when the controller cannot act at all.
        """
        return None

    @classmethod
    def evaluate(cls, jobs: Jobs, block: Block) -> None:
        """Evaluate every job of this class in ``block`` (by default one at a time). A class that
        overrides it evaluates many characters at once: ``jobs`` stacks their weights and times
        (:class:`Jobs`), ``block.table`` holds every character's pose in shared arrays
        (:class:`~infuse.runtime.pose.PoseTable`)."""
        for job in jobs:
            job.controller.evaluate_one(job, block)

    def evaluate_one(self, job: Job, block: Block) -> None:
        raise NotImplementedError(f"{type(self).__name__} implements neither evaluate nor evaluate_one")

    def handover(self, state: dict) -> dict:
        """The state an activity of this controller starts from when it takes over from another activity
        of the same kind on the same character (a walk following a walk): given that one's ``state``
        (left untouched), return what to put into the new activity's empty state. Default ``{}``: start
        afresh."""
        return {}

    def at_rest(self, state: dict) -> bool:
        """Whether an activity with this ``state`` has come to rest: nothing it set going still moves (a
        walk's stop steps are over and its idle fully shown). A scene hands a walk that has arrived over to
        the pack's idle clip only then. Default True: the controller keeps no motion of its own going."""
        return True

    def describe(self) -> str:
        """A short human description (for reports and feedback)."""
        return self.kind
