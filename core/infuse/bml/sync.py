"""Sync points, sync references and the timing model a behaviour offers the scheduler.

Times are seconds. A sync reference names a point in time: an absolute time from the start of the
block (``"2.5"``), or a sync point of a behaviour with an optional offset: ``"b1:end+0.5"``,
``"bml2:b1:stroke"`` (another block), ``"s1:tm1"`` (a speech mark), ``"g1:stroke:2"`` (the second
stroke of a repeated behaviour), ``"h1:start-1"``.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from .. import limits

#: The BML 1.0 sync points, in temporal order.
STANDARD_SYNC_POINTS = ("start", "ready", "strokeStart", "stroke", "strokeEnd", "relax", "end")
_STANDARD_RANK = {s: i for i, s in enumerate(STANDARD_SYNC_POINTS)}  # the BML order of ties in time
#: Other spellings found in documents -> the BML 1.0 name.
SYNC_ALIASES = {"stroke_start": "strokeStart", "stroke_end": "strokeEnd"}
#: Attribute names that carry sync references on a behaviour element (``attackPeak`` is the face sync point).
SYNC_ATTRIBUTES = frozenset(STANDARD_SYNC_POINTS) | frozenset(SYNC_ALIASES) | {"attackPeak"}

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_ABSOLUTE = re.compile(rf"\s*({_NUMBER})\s*")
_LAST_PART = re.compile(r"(?P<name>.*?)\s*(?P<offset>[+-]\s*(?:\d+(?:\.\d*)?|\.\d+))?\s*")


class SyncRefError(ValueError):
    """A sync reference that does not follow the BML syntax."""


@dataclass(frozen=True)
class SyncRef:
    """One parsed sync reference.

    ``time`` is set for an absolute reference (seconds from the block start); otherwise ``behaviour``
    and ``sync`` name the point, ``block`` the other block (None: the same block), ``iteration`` the
    stroke number (None: the first) and ``offset`` seconds added to it.
    """

    text: str
    time: float | None = None
    block: str | None = None
    behaviour: str | None = None
    sync: str | None = None
    iteration: int | None = None
    offset: float = 0.0

    @property
    def is_absolute(self) -> bool:
        return self.time is not None

    @property
    def point(self) -> str:
        """The sync point name with its iteration (``"stroke:2"``), without offset."""
        return f"{self.sync}:{self.iteration}" if self.iteration and self.iteration > 1 else str(self.sync)

    def __str__(self) -> str:
        return self.text


def canonical_sync(name: str) -> str:
    """A sync point name in the BML 1.0 spelling (``stroke_start`` -> ``strokeStart``)."""
    return SYNC_ALIASES.get(name, name)


def _check_time(raw: str, seconds: float) -> None:
    if not abs(seconds) <= limits.MAX_TIME_S:
        raise SyncRefError(f"sync reference {raw!r}: {seconds:g} s is past the limit of {limits.MAX_TIME_S:g} s "
                           "(infuse.limits.MAX_TIME_S)")


def parse_sync_ref(text: str) -> SyncRef:
    """Parse a sync reference; raises :class:`SyncRefError` naming what is wrong."""
    raw = text
    m = _ABSOLUTE.fullmatch(text)
    if m:
        value = float(m.group(1))
        if not math.isfinite(value):
            raise SyncRefError(f"sync reference {raw!r} is not a finite time")
        _check_time(raw, value)
        return SyncRef(raw, time=value)
    parts = [p.strip() for p in text.split(":")]
    last = _LAST_PART.fullmatch(parts[-1])
    if last is None:  # a line break inside the name
        raise SyncRefError(f"sync reference {raw!r} is not a name with an optional offset")
    offset = float(last.group("offset").replace(" ", "")) if last.group("offset") else 0.0
    _check_time(raw, offset)
    parts[-1] = last.group("name")
    iteration = None
    if len(parts) >= 3 and parts[-1].isdigit():
        iteration = int(parts.pop())
        if canonical_sync(parts[-1]) != "stroke":
            raise SyncRefError(f"sync reference {raw!r}: only stroke can take an iteration number, not {parts[-1]!r}")
        if iteration < 1:
            raise SyncRefError(f"sync reference {raw!r}: stroke iterations count from 1")
    if len(parts) == 2:
        block, behaviour, sync = None, parts[0], parts[1]
    elif len(parts) == 3:
        block, behaviour, sync = parts
    else:
        raise SyncRefError(f"sync reference {raw!r} is neither a time nor [block:]behaviour:sync[+offset]")
    if not behaviour or not sync or (block is not None and not block):
        raise SyncRefError(f"sync reference {raw!r} has an empty part")
    return SyncRef(raw, block=block, behaviour=behaviour, sync=canonical_sync(sync), iteration=iteration, offset=offset)


class TimingError(ValueError):
    """Constraints a behaviour cannot meet (its sync points would go backwards, or a rigid behaviour would stretch)."""


@dataclass(frozen=True)
class TimingModel:
    """How a behaviour's sync points sit in time, as its plugin describes it.

    ``sync_ids`` are in temporal order and ``offsets_s`` their natural times from the start (seconds,
    non-decreasing, first 0). A ``stretchable`` behaviour is time-warped piecewise linearly between
    constrained points (outside them it keeps its natural durations); a rigid one (speech) only moves.
    ``aliases`` maps other names of the same points (``"ready"`` -> ``"attackPeak"``).
    """

    sync_ids: tuple[str, ...]
    offsets_s: tuple[float, ...]
    stretchable: bool = True
    aliases: dict = field(default_factory=dict)

    def __post_init__(self):
        if len(self.sync_ids) != len(self.offsets_s) or not self.sync_ids:
            raise ValueError("a timing model needs one offset per sync point, and at least one")
        if self.sync_ids[0] != "start" or self.sync_ids[-1] != "end":
            raise ValueError("a timing model starts with 'start' and ends with 'end'")
        if any(b < a for a, b in zip(self.offsets_s, self.offsets_s[1:])) or not all(map(math.isfinite, self.offsets_s)):
            raise ValueError(f"timing model offsets must be finite and non-decreasing: {self.offsets_s}")

    @classmethod
    def from_points(cls, points: dict[str, float], stretchable: bool = True, aliases: dict | None = None) -> "TimingModel":
        """A model from ``{sync: seconds from start}``; points are ordered by time, ties by the BML order
        (``start`` first, ``end`` last, others as given)."""
        rank = _STANDARD_RANK

        def key(item):
            name, t = item  # "stroke:3" ranks as "stroke"
            return (t, 0 if name == "start" else 2 if name == "end" else 1, rank.get(name.split(":")[0], len(rank)))
        items = sorted(points.items(), key=key)
        start = dict(items)["start"]
        return cls(tuple(k for k, _ in items), tuple(v - start for _, v in items), stretchable, dict(aliases or {}))

    @property
    def duration_s(self) -> float:
        return self.offsets_s[-1]

    def resolve(self, name: str, iteration: int | None = None) -> str | None:
        """The sync id this model uses for ``name`` (and stroke ``iteration``), or None if it has no such point."""
        name = canonical_sync(name)
        name = self.aliases.get(name, name)
        if iteration and iteration > 1:
            name = f"{name}:{iteration}"
        elif name not in self.sync_ids and f"{name}:1" in self.sync_ids:
            name = f"{name}:1"
        return name if name in self.sync_ids else None

    def place(self, known: dict[str, float], allow_negative_start: bool = True, tolerance_s: float = 1e-6) -> dict[str, float]:
        """Times of every sync point given the times of some (``known``: sync id -> seconds).

        With nothing known the behaviour starts at 0. Raises :class:`TimingError` when the known times
        go backwards, when a rigid behaviour would have to stretch, or (``allow_negative_start=False``)
        when it would start before 0.
        """
        offsets = self.offsets_s
        index = {s: i for i, s in enumerate(self.sync_ids)}
        anchors = sorted((index[s], t) for s, t in known.items())
        if not anchors:
            anchors = [(0, 0.0)]
        for (i0, t0), (i1, t1) in zip(anchors, anchors[1:]):
            if t1 < t0 - tolerance_s:
                raise TimingError(f"{self.sync_ids[i1]} ({t1:g} s) would come before {self.sync_ids[i0]} ({t0:g} s)")
            if not self.stretchable and abs((t1 - t0) - (offsets[i1] - offsets[i0])) > max(tolerance_s, 1e-3):
                raise TimingError(f"{self.sync_ids[i0]} and {self.sync_ids[i1]} are {offsets[i1] - offsets[i0]:.3f} s apart "
                                  f"and cannot be placed {t1 - t0:.3f} s apart")
        times = [0.0] * len(offsets)
        first_i, first_t = anchors[0]
        last_i, last_t = anchors[-1]
        for i in range(len(offsets)):
            if i <= first_i:
                times[i] = first_t - (offsets[first_i] - offsets[i])
            elif i >= last_i:
                times[i] = last_t + (offsets[i] - offsets[last_i])
        for (i0, t0), (i1, t1) in zip(anchors, anchors[1:]):
            span = offsets[i1] - offsets[i0]
            for i in range(i0, i1 + 1):
                fraction = (offsets[i] - offsets[i0]) / span if span > 0 else 0.0
                times[i] = t0 + fraction * (t1 - t0)
        if not allow_negative_start and times[0] < -tolerance_s:
            raise TimingError(f"it would start at {times[0]:.3f} s, before its block starts")
        return dict(zip(self.sync_ids, times))
