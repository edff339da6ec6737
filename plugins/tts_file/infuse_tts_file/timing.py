"""Timing files -> labelled tiers: ``{"phones": [(start_s, end_s, label, place)], "words": [...], "marks": [...]}``.

Formats, chosen by extension and content:

- Praat TextGrid, long and short text formats, UTF-8 or UTF-16 (the Montreal Forced Aligner's
  default output). Interval tiers named ``phones``/``phonemes``/``segments`` (also
  ``"<speaker> - phones"``) and ``words``; a point tier ``marks`` or ``sync`` gives sync marks.
- JSON: the Montreal Forced Aligner's / praatio's (``{"tiers": {name: {"entries": [[s, e, label]]}}}``
  or ``{"tiers": [{"name", "entries"}]}``), or infuse's own
  (``{"phonemes": [{"start", "end", "phoneme"}] or [[s, e, p]], "words": [...], "marks": {name: t}}``,
  which is also what ``Utterance.to_dict()`` writes), with an optional ``"alphabet"``.
- TSV / CSV / whitespace-separated text (``.tsv``, ``.csv``, ``.txt``): ``start end phoneme`` per
  line in seconds, an optional header line, ``#`` comments; HTK label files (``.lab``) in units of
  100 ns.

Times are seconds. ``place`` says where an entry came from (line, tier and index), for errors.
"""
from __future__ import annotations

import csv
import io
import json
import math
import re
from pathlib import Path

from infuse.errors import InputError

Entry = tuple[float, float, str, str]  # start_s, end_s, label, place

PHONE_TIERS = ("phones", "phone", "phonemes", "phoneme", "segments", "segment", "mau")
WORD_TIERS = ("words", "word", "ort")
MARK_TIERS = ("marks", "mark", "sync", "sync points", "syncs")
HTK_UNIT_S = 1e-7


def read_timing(path: Path) -> dict:
    """``{"phones": [Entry], "words": [Entry], "marks": [(time_s, name, place)], "alphabet": str | None}``."""
    raw = path.read_bytes()
    text = _decode(raw, path)
    suffix = path.suffix.lower()
    if suffix == ".textgrid" or text.lstrip().startswith('File type = "ooTextFile"'):
        return _from_tiers(parse_textgrid(text, path), path)
    if suffix == ".json" or text.lstrip().startswith(("{", "[")):
        return _from_json(text, path)
    return {"phones": parse_table(text, path, HTK_UNIT_S if suffix == ".lab" else 1.0), "words": [], "marks": [], "alphabet": None}


def _decode(raw: bytes, path: Path) -> str:
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        return raw.decode("utf-16")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"byte {exc.start}", "not UTF-8 or UTF-16 text") from None


# -- TextGrid --------------------------------------------------------------------------------------

_TG_TOKEN = re.compile(r'"((?:[^"]|"")*)"|(\[[^\]\n]*\])|(<exists>|<absent>)|([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(\S+)')


def parse_textgrid(text: str, path: Path) -> list[dict]:
    """Tiers of a TextGrid (long or short format): ``[{"name", "kind": "interval"|"point", "entries"}]``.

    Praat's text formats are a sequence of strings and numbers; labels (``xmin =``), bracketed
    indices (``intervals [3]:``) and flags are decoration, so both formats read the same way.
    """
    values: list[tuple[str, str | float, int]] = []  # (kind, value, line)
    line = 1
    pos = 0
    for m in _TG_TOKEN.finditer(text):
        line += text.count("\n", pos, m.start())
        pos = m.start()
        if m.group(1) is not None:
            values.append(("s", m.group(1).replace('""', '"'), line))
        elif m.group(4) is not None:
            values.append(("n", float(m.group(4)), line))
    it = iter(values)

    def take(kind: str, what: str):
        try:
            k, v, ln = next(it)
        except StopIteration:
            raise InputError(path, "end of file", f"expected {what}, the file ends early") from None
        if k != kind:
            raise InputError(path, f"line {ln}", f"expected {what}, found {v!r}")
        return v, ln

    file_type, _ = take("s", '"ooTextFile"')
    obj_class, ln = take("s", '"TextGrid"')
    if file_type != "ooTextFile" or obj_class != "TextGrid":
        raise InputError(path, f"line {ln}", f"not a TextGrid (file type {file_type!r}, class {obj_class!r})")
    take("n", "xmin")
    take("n", "xmax")
    count, ln = take("n", "the number of tiers")
    tiers = []
    for t in range(int(count)):
        cls, ln = take("s", "a tier class")
        name, _ = take("s", "a tier name")
        take("n", "tier xmin")
        take("n", "tier xmax")
        n, _ = take("n", "the number of entries")
        if cls not in ("IntervalTier", "TextTier"):
            raise InputError(path, f"line {ln}", f"unknown tier class {cls!r}")
        entries = []
        for i in range(int(n)):
            place = f"tier {name!r} entry {i + 1}"
            if cls == "IntervalTier":
                start, ln = take("n", f"the start of {place}")
                end, _ = take("n", f"the end of {place}")
                label, _ = take("s", f"the label of {place}")
                entries.append((start, end, label, f"line {ln} ({place})"))
            else:
                time, ln = take("n", f"the time of {place}")
                label, _ = take("s", f"the mark of {place}")
                entries.append((time, time, label, f"line {ln} ({place})"))
        tiers.append({"name": name, "kind": "interval" if cls == "IntervalTier" else "point", "entries": entries})
    return tiers


def _tier_role(name: str, kind: str) -> str | None:
    key = name.strip().lower()
    key = key.rsplit(" - ", 1)[-1].strip() if " - " in key else key  # "<speaker> - phones"
    if kind == "point":
        return "marks" if key in MARK_TIERS else None
    if key in PHONE_TIERS:
        return "phones"
    if key in WORD_TIERS:
        return "words"
    return None


def _from_tiers(tiers: list[dict], path: Path) -> dict:
    out: dict = {"phones": None, "words": [], "marks": [], "alphabet": None}
    for tier in tiers:
        role = _tier_role(tier["name"], tier["kind"])
        if role == "phones" and out["phones"] is None:
            out["phones"] = tier["entries"]
        elif role == "words" and not out["words"]:
            out["words"] = tier["entries"]
        elif role == "marks":
            out["marks"] = [(s, label, place) for s, _, label, place in tier["entries"]]
    if out["phones"] is None:
        names = ", ".join(repr(t["name"]) for t in tiers) or "none"
        raise InputError(path, "tiers", f"no phone tier (named one of {', '.join(PHONE_TIERS[:4])}); tiers found: {names}")
    return out


# -- JSON -----------------------------------------------------------------------------------------------

def _from_json(text: str, path: Path) -> dict:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(path, f"line {exc.lineno}", f"not valid JSON: {exc.msg}") from None
    if isinstance(doc, dict) and "tiers" in doc:
        tiers_doc = doc["tiers"]
        if isinstance(tiers_doc, dict):
            tiers_doc = [dict(t, name=name) if isinstance(t, dict) else t for name, t in tiers_doc.items()]
        if not isinstance(tiers_doc, list):
            raise InputError(path, "tiers", "expected an object or a list of tiers")
        tiers = []
        for i, t in enumerate(tiers_doc):
            if not isinstance(t, dict):
                raise InputError(path, f"tiers[{i}]", "expected an object with a name and entries")
            name = str(t.get("name", ""))
            kind = "point" if str(t.get("type", t.get("class", ""))).lower() in ("point", "pointtier", "texttier") else "interval"
            entries = _json_entries(t.get("entries", t.get("intervals", t.get("points"))), path, f"tiers[{name!r}]", kind)
            tiers.append({"name": name, "kind": kind, "entries": entries})
        return _from_tiers(tiers, path)
    if isinstance(doc, list):
        doc = {"phonemes": doc}
    if not isinstance(doc, dict):
        raise InputError(path, None, "expected a JSON object with phonemes (or tiers)")
    phones_doc = doc.get("phonemes", doc.get("phones"))
    if phones_doc is None:
        raise InputError(path, "phonemes", 'no "phonemes" list (or MFA "tiers") in the document')
    phones = _json_entries(phones_doc, path, "phonemes", "interval")
    words = _json_entries(doc.get("words") or [], path, "words", "interval")
    marks_doc = doc.get("marks") or {}
    if isinstance(marks_doc, dict):
        marks = [(_number(t, path, f"marks.{name}"), str(name), f"marks.{name}") for name, t in marks_doc.items()]
    elif isinstance(marks_doc, list):
        marks = [(s, label, place) for s, _, label, place in _json_entries(marks_doc, path, "marks", "point")]
    else:
        raise InputError(path, "marks", "expected an object {name: time} or a list")
    return {"phones": phones, "words": words, "marks": marks, "alphabet": doc.get("alphabet")}


_LABEL_KEYS = ("phoneme", "phone", "label", "text", "word", "name", "mark")


def _json_entries(items, path: Path, where: str, kind: str) -> list[Entry]:
    if items is None:
        raise InputError(path, where, "missing entries")
    if not isinstance(items, list):
        raise InputError(path, where, "expected a list")
    out: list[Entry] = []
    for i, item in enumerate(items):
        place = f"{where}[{i}]"
        if isinstance(item, dict):
            label = next((item[k] for k in _LABEL_KEYS if k in item), None)
            start = item.get("start", item.get("begin", item.get("xmin", item.get("time"))))
            end = item.get("end", item.get("xmax", start if kind == "point" else None))
        elif isinstance(item, (list, tuple)) and len(item) in (2, 3):
            if kind == "point" and len(item) == 2:
                (start, label), end = item, item[0]
            elif len(item) == 3:
                start, end, label = item
            else:
                raise InputError(path, place, "expected [start, end, label]")
        else:
            raise InputError(path, place, "expected [start, end, label] or an object with start, end and a label")
        if label is None or not isinstance(label, str):
            raise InputError(path, place, "missing or non-text label")
        out.append((_number(start, path, place), _number(end, path, place), label, place))
    return out


def _number(value, path: Path, place: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(path, place, f"expected a finite time in seconds, got {value!r}")
    return float(value)


# -- tables ------------------------------------------------------------------------------------------------

def parse_table(text: str, path: Path, unit_s: float = 1.0) -> list[Entry]:
    """``start end label`` rows (tab, comma or spaces); an optional header row; ``#`` comments."""
    sample = "\n".join(text.splitlines()[:5])
    delimiter = "\t" if "\t" in sample else "," if "," in sample else None
    rows = csv.reader(io.StringIO(text), delimiter=delimiter) if delimiter else (line.split() for line in io.StringIO(text))
    out: list[Entry] = []
    for number, row in enumerate(rows, start=1):
        cells = [c.strip() for c in row]
        if not cells or not any(cells) or cells[0].startswith("#"):
            continue
        place = f"line {number}"
        if len(cells) < 3:
            raise InputError(path, place, f"expected 3 columns (start, end, phoneme), found {len(cells)}")
        try:
            start, end = float(cells[0]) * unit_s, float(cells[1]) * unit_s
        except ValueError:
            if not out and number == _first_row(text):
                continue  # a header row
            raise InputError(path, place, f"expected times in the first two columns, found {cells[0]!r}, {cells[1]!r}") from None
        if not (math.isfinite(start) and math.isfinite(end)):
            raise InputError(path, place, "times must be finite numbers")
        out.append((start, end, cells[2], place))
    return out


def _first_row(text: str) -> int:
    for number, line in enumerate(text.splitlines(), start=1):
        if line.strip() and not line.strip().startswith("#"):
            return number
    return 0
