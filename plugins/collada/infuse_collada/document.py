"""A parsed COLLADA document: safe XML parsing, ids, URL references and numeric arrays.

Parsing never resolves entities, loads a DTD or touches the network. Namespaces are dropped
(COLLADA 1.4 and 1.5 differ only in their namespace for what infuse reads), so lookups use
plain tag names.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from lxml import etree

from infuse.errors import InputError

_PARSER_OPTIONS = dict(resolve_entities=False, no_network=True, huge_tree=False, load_dtd=False,
                       remove_comments=True, remove_pis=True)


class Document:
    """The root ``<COLLADA>`` element of ``path`` and an index of its elements by ``id``."""

    def __init__(self, path: Path):
        self.path = path
        try:
            # From bytes, so bad encodings are syntax errors too (lxml reports them as OSError on files).
            self.root = etree.fromstring(path.read_bytes(), etree.XMLParser(**_PARSER_OPTIONS))
        except etree.XMLSyntaxError as exc:
            raise InputError(path, f"line {exc.lineno}" if exc.lineno else None, f"not well-formed XML: {exc.msg}") from None
        for el in self.root.iter():
            if isinstance(el.tag, str) and el.tag.startswith("{"):
                el.tag = el.tag.split("}", 1)[1]
        if self.root.tag != "COLLADA":
            raise InputError(path, f"line {self.root.sourceline}", f"root element is <{self.root.tag}>, expected <COLLADA>")
        self.ids: dict[str, etree._Element] = {}
        for el in self.root.iter():
            if isinstance(el.tag, str) and el.get("id") is not None:
                self.ids.setdefault(el.get("id"), el)

    def error(self, element, problem: str) -> InputError:
        """An :class:`InputError` placed at ``element`` (its line and tag)."""
        return InputError(self.path, place(element), problem)

    def resolve(self, url: str | None, referrer) -> etree._Element:
        """The element a local URL (``#id``) points to; raises :class:`InputError` when it is missing."""
        if not url or not url.startswith("#"):
            raise self.error(referrer, f"expected a local reference '#id', got {url!r}")
        target = self.ids.get(url[1:])
        if target is None:
            raise self.error(referrer, f"reference {url!r} points to no element")
        return target

    def floats(self, element, expected: int | None = None) -> np.ndarray:
        """The finite numbers in ``element``'s text, optionally exactly ``expected`` of them."""
        text = element.text or ""
        try:
            values = np.array(text.split(), dtype=np.float64)
        except ValueError:
            bad = next(t for t in text.split() if not _is_float(t))
            raise self.error(element, f"not a number: {bad[:40]!r}") from None
        if expected is not None and values.size != expected:
            raise self.error(element, f"expected {expected} numbers, found {values.size}")
        if not np.all(np.isfinite(values)):
            raise self.error(element, "value is not finite (NaN or infinity)")
        return values

    def ints(self, element, expected: int | None = None) -> np.ndarray:
        """The integers in ``element``'s text (int64), optionally exactly ``expected`` of them."""
        tokens = (element.text or "").split()
        try:
            values = np.array(tokens, dtype=np.int64)
        except (ValueError, OverflowError):
            bad = next(t for t in tokens if not _is_int(t))
            raise self.error(element, f"not an integer: {bad[:40]!r}") from None
        if expected is not None and values.size != expected:
            raise self.error(element, f"expected {expected} integers, found {values.size}")
        return values

    def source(self, url: str | None, referrer, numeric: bool = True) -> np.ndarray:
        """A ``<source>``'s data as a (count, stride) array (floats, or strings when not ``numeric``)."""
        src = self.resolve(url, referrer)
        accessor = src.find("technique_common/accessor")
        array = next((c for c in src if c.tag.endswith("_array")), None)
        if array is None:
            raise self.error(src, "source has no data array")
        if numeric:
            if array.tag not in ("float_array", "int_array"):
                raise self.error(array, f"expected numbers, found <{array.tag}>")
            data = self.floats(array)
        else:
            data = np.array((array.text or "").split(), dtype=object)
        if accessor is None:
            return data.reshape(-1, 1)
        count = _int_attr(self, accessor, "count")
        stride = _int_attr(self, accessor, "stride", 1)
        offset = _int_attr(self, accessor, "offset", 0)
        if stride < 1 or offset + count * stride > data.size:
            raise self.error(accessor, f"accessor needs {offset + count * stride} values, the array has {data.size}")
        return data[offset:offset + count * stride].reshape(count, stride)


def place(element) -> str:
    """``line N <tag id=...>``: where an element is, for error messages."""
    ident = element.get("id") or element.get("sid") or element.get("name")
    tag = f"<{element.tag}{' ' + repr(ident) if ident else ''}>"
    return f"line {element.sourceline} {tag}" if element.sourceline else tag


def _int_attr(doc: Document, element, name: str, default: int | None = None) -> int:
    raw = element.get(name)
    if raw is None:
        if default is None:
            raise doc.error(element, f"missing attribute {name!r}")
        return default
    try:
        value = int(raw)
    except ValueError:
        raise doc.error(element, f"attribute {name}={raw!r} is not an integer") from None
    if value < 0:
        raise doc.error(element, f"attribute {name}={raw!r} is negative")
    return value


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _is_int(token: str) -> bool:
    try:
        value = int(token)
    except ValueError:
        return False
    return abs(value) < 2**63
