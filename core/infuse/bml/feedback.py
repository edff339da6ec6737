"""BML feedback: events delivered to Python callbacks and printable as BML 1.0 feedback XML.

``blockProgress`` marks a block's start and end (global seconds), ``syncPointProgress`` each sync point
of each behaviour as it passes (``time`` from the block start, ``globalTime``), ``warningFeedback``
something skipped or impossible, and ``blockPrediction`` the planned start and end of a block.
``generatedBml`` (infuse's own, in its namespace ``urn:infuse:bml``) carries the BML a generator added
to a block before it was scheduled.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

from lxml import etree

from .names import BML_NS, INFUSE_NS


def _make(tag: str, attributes: dict, text: str | None = None, parent=None):
    name = f"{{{BML_NS}}}{tag}"
    el = etree.Element(name, nsmap={None: BML_NS}) if parent is None else etree.SubElement(parent, name)
    for key, value in attributes.items():
        if value is not None:
            el.set(key, _format(value))
    if text:
        el.text = text
    return el


def _element(tag: str, attributes: dict, text: str | None = None) -> str:
    return etree.tostring(_make(tag, attributes, text), encoding="unicode")


def _format(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}" if abs(value) < 1e6 else repr(value)
    return str(value)


@dataclass(frozen=True)
class BlockProgress:
    block: str
    sync: str  # "start" or "end"
    global_time: float
    character: str | None = None
    kind = "blockProgress"

    def to_xml(self) -> str:
        return _element("blockProgress", {"id": f"{self.block}:{self.sync}", "globalTime": self.global_time,
                                          "characterId": self.character})


@dataclass(frozen=True)
class SyncPointProgress:
    block: str
    behaviour: str
    sync: str
    time: float  # seconds from the block start
    global_time: float
    character: str | None = None
    kind = "syncPointProgress"

    def to_xml(self) -> str:
        return _element("syncPointProgress", {"id": f"{self.block}:{self.behaviour}:{self.sync}", "time": self.time,
                                              "globalTime": self.global_time, "characterId": self.character})


@dataclass(frozen=True)
class WarningFeedback:
    id: str
    type: str
    description: str
    character: str | None = None
    line: int | None = None
    kind = "warningFeedback"

    def to_xml(self) -> str:
        return _element("warningFeedback", {"id": self.id, "type": self.type, "characterId": self.character},
                        self.description if self.line is None else f"{self.description} (line {self.line})")


@dataclass(frozen=True)
class BlockPrediction:
    block: str
    global_start: float
    global_end: float
    character: str | None = None
    kind = "blockPrediction"

    def to_xml(self) -> str:
        root = _make("predictionFeedback", {})
        _make("bml", {"id": self.block, "globalStart": self.global_start, "globalEnd": self.global_end,
                      "characterId": self.character}, parent=root)
        return etree.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class GeneratedBml:
    """The BML ``generator`` added to block ``block`` before scheduling (a ``<bml>`` or ``<act>`` document as text)."""

    block: str
    generator: str
    bml: str
    character: str | None = None
    kind = "generatedBml"

    def to_xml(self) -> str:
        root = etree.Element(f"{{{INFUSE_NS}}}generatedBml", nsmap={"infuse": INFUSE_NS})
        for key, value in (("id", self.block), ("generator", self.generator), ("characterId", self.character)):
            if value is not None:
                root.set(key, value)
        root.append(etree.fromstring(self.bml.encode("utf-8"), etree.XMLParser(resolve_entities=False, no_network=True)))
        return etree.tostring(root, encoding="unicode")


def feedback_xml(events: Iterable) -> str:
    """Events as BML feedback XML, one element per line."""
    return "\n".join(e.to_xml() for e in events)


class FeedbackBus:
    """Delivers feedback events to subscribed callbacks, in the order they happen, and keeps a log."""

    def __init__(self) -> None:
        self._subscribers: list[tuple[Callable, frozenset | None]] = []
        self.log: list = []

    def subscribe(self, callback: Callable, kinds: Iterable[str] | None = None) -> Callable[[], None]:
        """Call ``callback(event)`` for each event (of ``kinds`` only, if given); returns an unsubscribe function."""
        entry = (callback, frozenset(kinds) if kinds is not None else None)
        self._subscribers.append(entry)
        return lambda: self._subscribers.remove(entry)

    def emit(self, event) -> None:
        self.log.append(event)
        for callback, kinds in list(self._subscribers):
            if kinds is None or event.kind in kinds:
                callback(event)

    def xml(self) -> str:
        """Everything emitted so far as BML feedback XML."""
        return feedback_xml(self.log)
