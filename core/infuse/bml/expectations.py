"""Expected timings written in a BML document's header comment, and how a schedule compares with them.

The BML 1.0 test suite (OpenBMLParser) states what a realizer should do in a comment before the block::

    Required timing:            Realization:
    nod1:start = 1              Invalid timing for nod1, behaviour should be removed ...
    tilt1:start = nod1:end+1
    h1:start = g1:end, > 4

Each line of a ``Required timing``/``Expected timing`` section is one expectation: a chain of terms
(``beh:sync[+offset]`` or a number) joined by ``=``, ``<`` or ``>``; a part after a comma that starts with
an operator continues from the line's first term. ``Realization``/``Expected execution`` sections say which
behaviours must be dropped, and ``Error:`` lines which warnings must appear. Comments are written by
people: a behaviour id that matches none is read as the one id within one typing error of it, and
``stroke-end`` as ``strokeEnd``. An expectation that contradicts the document's own markup (an absolute
sync attribute with another value) is reported as a conflict in the oracle, not as a scheduler mismatch.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from .sync import STANDARD_SYNC_POINTS, canonical_sync

TOLERANCE_S = 1e-3
_TIMING_HEADERS = ("required timing:", "expected timing:")
_OUTCOME_HEADERS = ("realization:", "expected execution:", "expected behavior:", "expected behaviour:")
_TERM = re.compile(r"\s*(?:(?P<number>[+-]?\d+(?:\.\d*)?)|(?P<beh>[\w .-]+?):(?P<sync>stroke-end|stroke-start|[A-Za-z_]\w*)"
                   r"\s*(?P<off>[+-]\s*\d+(?:\.\d*)?)?)\s*$", re.I)
_DROPPED = (re.compile(r"invalid timing for (\w+)", re.I), re.compile(r"(\w+) should be (?:omitted|removed)", re.I))


@dataclass(frozen=True)
class Term:
    behaviour: str | None  # None: a number
    sync: str | None
    offset: float

    def __str__(self) -> str:
        if self.behaviour is None:
            return f"{self.offset:g}"
        return f"{self.behaviour}:{self.sync}" + (f"{self.offset:+g}" if self.offset else "")


@dataclass(frozen=True)
class Expectation:
    """``kind``: ``"timing"`` (``relations``: (left, op, right) triples), ``"dropped"`` or ``"warning"`` (``subject``)."""

    text: str
    kind: str
    relations: tuple = ()
    subject: str | None = None


@dataclass(frozen=True)
class Outcome:
    """``status``: ``"matched"``, ``"mismatched"`` or ``"conflict"`` (the comment contradicts the markup)."""

    expectation: Expectation
    status: str
    detail: str = ""


def _term(text: str) -> Term | None:
    m = _TERM.match(text)
    if not m:
        return None
    if m.group("number") is not None:
        return Term(None, None, float(m.group("number")))
    sync = m.group("sync")
    sync = {"stroke-end": "strokeEnd", "stroke-start": "strokeStart"}.get(sync.lower(), canonical_sync(sync))
    return Term(m.group("beh").strip(), sync, float(m.group("off").replace(" ", "")) if m.group("off") else 0.0)


def _relations(line: str):
    """The (left, op, right) triples of one line, or None when it is not a timing statement."""
    relations: list[tuple[Term, str, Term]] = []
    first: Term | None = None
    for part in line.rstrip(";").split(","):
        pieces = re.split(r"\s*([=<>])\s*", part.strip())
        if pieces and pieces[0] == "" and first is not None:
            pieces[0] = "@first"
        found = [first if p == "@first" else _term(p) for p in pieces[0::2]]
        terms = [t for t in found if t is not None]
        if len(pieces) < 3 or len(terms) < len(found):
            return None
        first = first or terms[0]
        relations.extend((a, op, b) for a, op, b in zip(terms, pieces[1::2], terms[1:]))
    return tuple(relations) or None


def expectations_from_comments(comments) -> list[Expectation]:
    """Expectations in the first comment that has a timing or outcome section."""
    for comment in comments:
        lines = [line.strip() for line in comment.splitlines()]
        found, section = [], None
        for line in lines:
            lower = line.lower()
            if lower in _TIMING_HEADERS or lower in _OUTCOME_HEADERS:
                section = "timing" if lower in _TIMING_HEADERS else "outcome"
                continue
            if not line:
                section = None
                continue
            if section is None or lower in ("none", "-"):
                continue
            dropped = [m.group(1) for rx in _DROPPED for m in [rx.search(line)] if m]
            if dropped:
                found.append(Expectation(line, "dropped", subject=dropped[0]))
            elif lower.startswith(("error:", "warning:")):
                subject = re.search(r"[\w.-]+", line.split(":", 1)[1])
                found.append(Expectation(line, "warning", subject=subject.group(0) if subject else None))
            elif section == "timing":
                relations = _relations(line)
                if relations:
                    found.append(Expectation(line, "timing", relations))
        if found:
            # A behaviour the comment says must be dropped: its timing lines restate the request, not the result.
            dropped_ids = {e.subject for e in found if e.kind == "dropped"}
            return [e for e in found if e.kind != "timing" or not any(
                t.behaviour in dropped_ids for rel in e.relations for t in (rel[0], rel[2]))]
    return []


def _squash(name: str) -> str:
    return re.sub(r"[_-]", "", name).lower()


def _close_id(name: str, ids, elements: dict | None = None) -> str | None:
    """``name`` itself, else the one id it could be a typing error for (one edit, or a unique prefix), else the
    only behaviour of the element the name spells (``speech1`` for a block's only ``<speech>``)."""
    if name in ids:
        return name
    def one_edit(a, b):
        if abs(len(a) - len(b)) > 1:
            return False
        if len(a) == len(b):
            return sum(x != y for x, y in zip(a, b)) == 1
        short, long_ = sorted((a, b), key=len)
        return any(long_[:i] + long_[i + 1:] == short for i in range(len(long_)))
    near = [i for i in ids if one_edit(name, i)] or [i for i in ids if i.startswith(name)]
    if not near and elements:
        near = [i for i in ids if elements.get(i) == name.rstrip("0123456789")]
    return near[0] if len(near) == 1 else None


def check(expectations, block, schedule) -> list[Outcome]:
    """Compare ``schedule`` (a :class:`~infuse.bml.schedule.BlockSchedule` of ``block``) with ``expectations``."""
    times = schedule.local_times() if not schedule.failed else {}
    ids = [b.id for b in block.behaviours]
    elements = {b.id: b.element for b in block.behaviours}
    warnings = " ".join(i.description + " " + i.id for i in schedule.issues)
    out = []
    for e in expectations:
        if e.kind == "dropped":
            name = _close_id(e.subject, ids, elements) or e.subject
            ok = name not in times and name in warnings
            out.append(Outcome(e, "matched" if ok else "mismatched",
                               "" if ok else f"{name} was scheduled or not reported"))
        elif e.kind == "warning":
            ok = e.subject is not None and e.subject in warnings
            out.append(Outcome(e, "matched" if ok else "mismatched", "" if ok else "no warning names it"))
        else:
            out.append(_check_timing(e, block, schedule, times, ids, elements))
    return out


class _Conflict(LookupError):
    pass


def _check_timing(e: Expectation, block, schedule, times, ids, elements) -> Outcome:
    notes = []

    def value(term: Term):
        if term.behaviour is None:
            return term.offset
        name = _close_id(term.behaviour, ids, elements)
        if name is None:
            raise LookupError(f"no behaviour {term.behaviour!r}")
        if name != term.behaviour:
            notes.append(f"{term.behaviour!r} read as {name!r}")
        if name not in times:
            raise LookupError(f"{name} was not scheduled")
        sync_times = times[name]
        aliases = schedule.activation(name).sync_aliases
        sync = term.sync if term.sync in sync_times else aliases.get(term.sync) or next(
            (s for s in sync_times if _squash(s) == _squash(term.sync or "")), None)
        if sync is None:
            if term.sync in STANDARD_SYNC_POINTS or term.sync == "attackPeak":
                raise LookupError(f"{name} has no sync point {term.sync!r}")
            raise _Conflict(f"the comment names sync point {term.sync!r}, which {name} does not have in the markup")
        if sync != term.sync:
            notes.append(f"{term.sync!r} read as {sync!r}")
        return sync_times[sync] + term.offset

    for left, op, right in e.relations:
        for term, other in ((left, right), (right, left)):
            if op == "=" and term.behaviour is not None and other.behaviour is None and term.offset == 0:
                b = block.behaviour(_close_id(term.behaviour, ids, elements) or term.behaviour)
                ref = b.sync_refs.get(term.sync) if b else None
                if ref is not None and ref.is_absolute and abs(ref.time - other.offset) > TOLERANCE_S:
                    return Outcome(e, "conflict", f"the comment says {term} = {other} but the markup says "
                                                  f"{term.sync}={ref.text!r}")
    try:
        values, missing = {}, None
        for term in {t for rel in e.relations for t in (rel[0], rel[2])}:
            try:
                values[term] = value(term)
            except _Conflict:
                raise
            except LookupError as exc:
                missing = missing or exc
        if missing:
            raise missing
        failures = []
        for left, op, right in e.relations:
            a, b = values[left], values[right]
            ok = abs(a - b) <= TOLERANCE_S if op == "=" else (a < b + TOLERANCE_S if op == "<" else a > b - TOLERANCE_S)
            if not ok:
                failures.append(f"{left} = {a:.3f} is not {op} {right} = {b:.3f}")
    except _Conflict as exc:
        return Outcome(e, "conflict", str(exc))
    except LookupError as exc:
        return Outcome(e, "mismatched", str(exc))
    detail = "; ".join(failures + notes)
    return Outcome(e, "mismatched" if failures else "matched", detail)
