"""The plain model a BML document parses into: blocks, behaviours, constraints, warnings.

Nothing here knows XML or time solving; it is data that the parser fills and the scheduler reads.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .sync import SyncRef

#: Block composition modes (BML 1.0).
COMPOSITIONS = ("MERGE", "APPEND", "REPLACE")

#: Dialects a block can be written in; they differ in what they tolerate (see :class:`Block`).
DIALECT_BML1 = "bml1.0"
DIALECT_SMARTBODY = "smartbody"
DIALECT_DRAFT = "draft"

# warningFeedback types, as the BML 1.0 feedback vocabulary names them.
PARSING_FAILURE = "PARSING_FAILURE"
NO_SUCH_TARGET = "NO_SUCH_TARGET"
IMPOSSIBLE_TO_SCHEDULE = "IMPOSSIBLE_TO_SCHEDULE"
BEHAVIOR_TYPE_NOT_SUPPORTED = "BEHAVIOR_TYPE_NOT_SUPPORTED"
CUSTOM_BEHAVIOUR_NOT_SUPPORTED = "CUSTOM_BEHAVIOUR_NOT_SUPPORTED"
CUSTOM_ATTRIBUTE_NOT_SUPPORTED = "CUSTOM_ATTRIBUTE_NOT_SUPPORTED"
CANNOT_CREATE_BEHAVIOR = "CANNOT_CREATE_BEHAVIOR"
#: A behaviour realized only in part (infuse's own type: the description says what the character lacks).
BEHAVIOR_DEGRADED = "BEHAVIOR_DEGRADED"


@dataclass(frozen=True)
class Issue:
    """Something that went wrong but did not stop the document: becomes a warningFeedback.

    ``id`` is ``"block"`` or ``"block:behaviour"``; ``type`` one of the constants above; ``line`` the
    source line when known.
    """

    id: str
    type: str
    description: str
    line: int | None = None


@dataclass(frozen=True)
class Node:
    """A child element of a behaviour that the behaviour's plugin interprets (``<stance>``, ``<lexeme>``...).

    ``name`` and attribute keys follow :mod:`infuse.bml.names`; ``text`` is the stripped text content.
    """

    name: str
    attributes: dict
    text: str = ""
    children: tuple = ()
    line: int | None = None


@dataclass(frozen=True)
class Behaviour:
    """One behaviour element of a block.

    ``element``: its name (see :mod:`infuse.bml.names`); ``attributes``: every attribute except ``id`` and
    the sync attributes, names normalized; ``sync_refs``: sync point -> parsed reference (BML spelling);
    ``sync_errors``: sync point -> why its reference could not be parsed. Speech gets ``text`` (white space
    collapsed) and ``marks``: (mark id, character offset in ``text``) for inline ``<sync>``/``<tm>``/``<mark>``.
    ``required`` is True inside ``<required>``; ``id_given`` is False when infuse had to name it.
    """

    element: str
    id: str
    attributes: dict
    sync_refs: dict
    sync_errors: dict = field(default_factory=dict)
    text: str | None = None
    marks: tuple = ()
    children: tuple = ()
    required: bool = False
    line: int | None = None
    id_given: bool = True

    def attribute(self, *names: str, default=None):
        """The first of ``names`` present (for dialects that spell one attribute several ways)."""
        for name in names:
            if name in self.attributes:
                return self.attributes[name]
        return default


@dataclass(frozen=True)
class Constraint:
    """A ``<constraint>`` child: ``kind`` is ``"synchronize"`` (all ``syncs`` at one time, and ``ref`` if set),
    ``"before"`` (every sync at or before ``ref``) or ``"after"`` (every sync at or after ``ref``). ``error`` says why a constraint could not be parsed."""

    kind: str
    syncs: tuple[SyncRef, ...]
    ref: SyncRef | None = None
    id: str | None = None
    required: bool = False
    line: int | None = None
    error: str | None = None


@dataclass(frozen=True)
class Block:
    """One ``<bml>`` block.

    ``composition`` is MERGE, APPEND or REPLACE; ``append_after`` and ``interrupts`` list block ids from the
    ASAP extensions (``bmla:appendAfter``/``bmla:chunkAfter``, ``bmla:interrupt``). In the ``smartbody``
    and ``draft`` dialects a behaviour may start before its block (the realizer plays the part after the
    block start); in BML 1.0 such a behaviour cannot be scheduled.
    """

    id: str
    character_id: str | None
    composition: str
    behaviours: tuple[Behaviour, ...]
    constraints: tuple[Constraint, ...]
    dialect: str = DIALECT_BML1
    append_after: tuple[str, ...] = ()
    interrupts: tuple[str, ...] = ()
    attributes: dict = field(default_factory=dict)
    issues: tuple[Issue, ...] = ()
    line: int | None = None

    def behaviour(self, behaviour_id: str) -> Behaviour | None:
        for b in self.behaviours:
            if b.id == behaviour_id:
                return b
        return None


@dataclass(frozen=True)
class BmlDocument:
    """A parsed file or string: its blocks in document order, and where it came from."""

    blocks: tuple[Block, ...]
    file: str | None = None
    comments: tuple[str, ...] = ()

    @property
    def issues(self) -> tuple[Issue, ...]:
        return tuple(i for b in self.blocks for i in b.issues)
