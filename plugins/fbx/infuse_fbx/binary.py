"""The binary FBX container: a tree of named node records, each with typed properties.

Layout (little-endian): a 27-byte header (``Kaydara FBX Binary  \\0``, 0x1A 0x00, uint32
version), then node records until an all-zero record. A record holds its end offset, property
count and property-list length (uint32, or uint64 from version 7500), a name (uint8 length +
bytes), its properties, and its children ending with an all-zero record. Property type codes:
``Y C I F D L`` (int16, bool, int32, float32, float64, int64), ``S R`` (uint32 length + bytes),
``f d l i b`` (arrays: uint32 length, encoding, byte size; encoding 1 is zlib).

Every offset and size is checked against the data, so malformed files raise
:class:`~infuse.errors.InputError` naming the byte offset instead of reading out of bounds.
"""
from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from infuse.errors import InputError

MAGIC = b"Kaydara FBX Binary  \x00"
HEADER_SIZE = 27
MAX_DEPTH = 64

_SCALARS = {b"Y": "<h", b"C": "<?", b"I": "<i", b"F": "<f", b"D": "<d", b"L": "<q"}
_ARRAYS = {b"f": np.dtype("<f4"), b"d": np.dtype("<f8"), b"l": np.dtype("<i8"), b"i": np.dtype("<i4"), b"b": np.dtype("?")}


@dataclass
class Node:
    """One record: ``name``, ``props`` (ints, floats, bools, str/bytes, numpy arrays), ``children``,
    and where it starts (``offset``: a byte offset, or a line number when ``line`` is set)."""

    name: str
    props: list = field(default_factory=list)
    children: list["Node"] = field(default_factory=list)
    offset: int = 0  # byte offset in a binary file, line number in an ASCII one
    line: bool = False

    def find(self, name: str) -> "Node | None":
        return next((c for c in self.children if c.name == name), None)

    def find_all(self, name: str) -> list["Node"]:
        return [c for c in self.children if c.name == name]


def is_binary_fbx(data: bytes) -> bool:
    return data[: len(MAGIC)] == MAGIC


def parse(path: Path, data: bytes) -> tuple[int, Node]:
    """(version, root) of a binary FBX file's bytes; the root's children are the top-level records."""
    if len(data) < HEADER_SIZE or not is_binary_fbx(data):
        raise InputError(path, "header", "not a binary FBX file (no 'Kaydara FBX Binary' header)")
    version = struct.unpack_from("<I", data, 23)[0]
    parser = _Parser(path, data, version)
    root = Node("", offset=0)
    root.children = parser.records(HEADER_SIZE, len(data), 0, top_level=True)
    return version, root


class _Parser:
    def __init__(self, path: Path, data: bytes, version: int):
        self.path = path
        self.data = memoryview(data)
        self.wide = version >= 7500
        self.head = struct.Struct("<QQQ" if self.wide else "<III")
        self.null_size = self.head.size + 1

    def error(self, offset: int, problem: str) -> InputError:
        return InputError(self.path, f"byte {offset}", problem)

    def records(self, pos: int, end: int, depth: int, top_level: bool = False) -> list[Node]:
        """Records from ``pos`` up to the all-zero terminator (or ``end``)."""
        if depth > MAX_DEPTH:
            raise self.error(pos, f"records nested deeper than {MAX_DEPTH}")
        out = []
        while True:
            if pos + self.null_size > end:
                if pos == end or (top_level and out):
                    return out  # lists that fill their parent exactly, or a file without its final terminator
                raise self.error(pos, "record list ends without its terminator (truncated file?)")
            end_offset, num_props, props_len = self.head.unpack_from(self.data, pos)
            name_len = self.data[pos + self.head.size]
            if end_offset == 0:
                if num_props or props_len or name_len:
                    raise self.error(pos, "malformed terminator record")
                return out
            node, pos = self.record(pos, end, end_offset, num_props, props_len, name_len, depth)
            out.append(node)

    def record(self, pos, end, end_offset, num_props, props_len, name_len, depth):
        start = pos
        if not (pos < end_offset <= end):
            raise self.error(pos, f"record end {end_offset} lies outside its parent (ends at {end})")
        pos += self.head.size + 1
        name_bytes = bytes(self.data[pos:pos + name_len])
        pos += name_len
        try:
            name = name_bytes.decode("ascii")
        except UnicodeDecodeError:
            raise self.error(start, "record name is not ASCII") from None
        props_end = pos + props_len
        if props_end > end_offset:
            raise self.error(start, f"record {name!r}: properties overrun the record")
        props = []
        for _ in range(num_props):
            value, pos = self.prop(pos, props_end, name)
            props.append(value)
        if pos != props_end:
            raise self.error(start, f"record {name!r}: property list length does not match its properties")
        node = Node(name, props, offset=start)
        if pos < end_offset:
            node.children = self.records(pos, end_offset, depth + 1)
        return node, end_offset

    def prop(self, pos: int, end: int, owner: str):
        if pos >= end:
            raise self.error(pos, f"record {owner!r}: property list ends early")
        code = bytes(self.data[pos:pos + 1])
        pos += 1
        if code in _SCALARS:
            fmt = struct.Struct(_SCALARS[code])
            self.need(pos, fmt.size, end, owner)
            return fmt.unpack_from(self.data, pos)[0], pos + fmt.size
        if code in (b"S", b"R"):
            self.need(pos, 4, end, owner)
            size = struct.unpack_from("<I", self.data, pos)[0]
            self.need(pos + 4, size, end, owner)
            raw = bytes(self.data[pos + 4:pos + 4 + size])
            return (raw.decode("utf-8", "replace") if code == b"S" else raw), pos + 4 + size
        if code in _ARRAYS:
            self.need(pos, 12, end, owner)
            length, encoding, size = struct.unpack_from("<III", self.data, pos)
            pos += 12
            self.need(pos, size, end, owner)
            return self.array(pos, code, length, encoding, size, owner), pos + size
        raise self.error(pos - 1, f"record {owner!r}: unknown property type {code!r}")

    def need(self, pos: int, size: int, end: int, owner: str) -> None:
        if pos + size > end:
            raise self.error(pos, f"record {owner!r}: property runs past the end of its record")

    def array(self, pos, code, length, encoding, size, owner) -> np.ndarray:
        dtype = _ARRAYS[code]
        expected = length * dtype.itemsize
        raw = bytes(self.data[pos:pos + size])
        if encoding == 1:
            inflater = zlib.decompressobj()
            try:
                raw = inflater.decompress(raw, expected + 1)
            except zlib.error as exc:
                raise self.error(pos, f"record {owner!r}: compressed array is corrupt ({exc})") from None
        elif encoding != 0:
            raise self.error(pos, f"record {owner!r}: unknown array encoding {encoding}")
        if len(raw) != expected:
            raise self.error(pos, f"record {owner!r}: array holds {len(raw)} bytes, {length} values need {expected}")
        return np.frombuffer(raw, dtype=dtype).astype(dtype.newbyteorder("="))
