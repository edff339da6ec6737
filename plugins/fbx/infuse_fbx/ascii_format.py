"""The ASCII FBX container, read into the same node tree as :mod:`.binary`.

Records are ``Name: value, value, ... { children }``; values are numbers, ``"strings"`` or bare
words; arrays are ``*N { a: v,v,... }``; ``;`` starts a comment. A comma may stand before a
record's first value (embedded media: ``Content: , "base64..."``). Integers stay ``int`` (object ids,
times in ticks), other numbers become ``float``; arrays become int64 or float64 numpy arrays.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from infuse.errors import InputError

from .binary import MAX_DEPTH, Node

_TOKEN = re.compile(
    r'(?P<comment>;[^\n]*)'
    r'|(?P<array>\*(?P<count>\d+)\s*\{\s*a\s*:(?P<items>[^}]*)\})'
    r'|(?P<name>[A-Za-z_][\w|\-]*)\s*:'
    r'|(?P<string>"[^"]*")'
    r'|(?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)'
    r'|(?P<word>[A-Za-z_][\w]*)'
    r'|(?P<punct>[{},])'
    r'|(?P<space>\s+)'
)
_INT = re.compile(r"[-+]?\d+$")


def is_ascii_fbx(data: bytes) -> bool:
    head = data[:4096]
    return head.lstrip().startswith(b"; FBX") or b"FBXHeaderExtension:" in head


def parse(path: Path, data: bytes) -> tuple[int, Node]:
    """(version, root) of an ASCII FBX file's bytes."""
    text = data.decode("utf-8", "replace")
    tokens = _tokens(path, text)
    root = Node("", offset=0)
    root.children, end = _records(path, tokens, 0, 0)
    if end != len(tokens):
        raise _error(path, tokens[end], "unexpected '}'")
    header = root.find("FBXHeaderExtension")
    version_node = header.find("FBXVersion") if header is not None else None
    if version_node is None or not version_node.props or not isinstance(version_node.props[0], int):
        raise InputError(path, "FBXHeaderExtension", "no FBXVersion")
    return version_node.props[0], root


def _tokens(path: Path, text: str) -> list[tuple[str, object, int]]:
    """(kind, value, line) tokens; comments and spaces dropped."""
    out = []
    pos, line = 0, 1
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise InputError(path, f"line {line}", f"unexpected character {text[pos]!r}")
        kind = m.lastgroup if m.lastgroup not in ("count", "items") else "array"
        if kind == "array":
            out.append(("array", _array(path, line, int(m["count"]), m["items"]), line))
        elif kind == "name":
            out.append(("name", m["name"], line))
        elif kind == "string":
            out.append(("value", m["string"][1:-1].replace("&quot;", '"'), line))
        elif kind == "number":
            token = m["number"]
            out.append(("value", int(token) if _INT.match(token) else float(token), line))
        elif kind == "word":
            out.append(("value", m["word"], line))
        elif kind == "punct":
            out.append((m["punct"], m["punct"], line))
        line += text.count("\n", pos, m.end())
        pos = m.end()
    return out


def _array(path: Path, line: int, count: int, items: str) -> np.ndarray:
    parts = [p for p in items.replace("\n", " ").split(",") if p.strip()]
    if len(parts) != count:
        raise InputError(path, f"line {line}", f"array declares {count} values and holds {len(parts)}")
    integral = not any(c in items for c in ".eE")
    try:
        return np.array([p.strip() for p in parts], dtype=np.int64 if integral else np.float64)
    except (ValueError, OverflowError):
        raise InputError(path, f"line {line}", "array holds a value that is not a number") from None


def _records(path: Path, tokens, i: int, depth: int) -> tuple[list[Node], int]:
    """Records from token ``i`` up to an unmatched ``}`` (not consumed) or the end."""
    if depth > MAX_DEPTH:
        raise _error(path, tokens[i], f"records nested deeper than {MAX_DEPTH}")
    out = []
    while i < len(tokens) and tokens[i][0] != "}":
        kind, name, line = tokens[i]
        if kind != "name":
            raise _error(path, tokens[i], f"expected a record name, found {str(name)[:30]!r}")
        node = Node(name, offset=line, line=True)
        i += 1
        if i + 1 < len(tokens) and tokens[i][0] == "," and tokens[i + 1][0] in ("value", "array"):
            i += 1  # embedded media is written "Content: , "base64...""
        expect_value = True
        while i < len(tokens) and tokens[i][0] in ("value", "array", ","):
            if (tokens[i][0] == ",") == expect_value:
                raise _error(path, tokens[i], f"record {name!r}: misplaced comma")
            if tokens[i][0] != ",":
                node.props.append(tokens[i][1])
            expect_value = tokens[i][0] == ","
            i += 1
        if i < len(tokens) and tokens[i][0] == "{":
            node.children, i = _records(path, tokens, i + 1, depth + 1)
            if i >= len(tokens):
                raise InputError(path, f"line {line}", f"record {name!r} is not closed (truncated file?)")
            i += 1
        out.append(node)
    return out, i


def _error(path: Path, token, problem: str) -> InputError:
    return InputError(path, f"line {token[2]}", problem)
