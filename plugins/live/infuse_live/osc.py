"""OSC 1.0 messages and bundles written as bytes, for a stream whose messages keep their addresses, type
tags and leading arguments frame after frame and change only their trailing float arguments (VMC's bones
and blend shapes): each message's fixed part is written once, and a frame's floats in one conversion.

OSC writes big-endian: int32 ``i``, float32 ``f``, strings NUL-terminated and padded to 4 bytes. A bundle
is ``#bundle``, a time tag (1: at once) and each message with its int32 size.
"""
from __future__ import annotations

import struct

import numpy as np

#: The time tag of a bundle to act on at once.
IMMEDIATELY = 1
_BUNDLE = b"#bundle\0" + struct.pack(">Q", IMMEDIATELY)


def padded(text: str) -> bytes:
    """An OSC string: UTF-8, NUL-terminated, padded with NULs to a multiple of 4 bytes."""
    data = text.encode("utf-8") + b"\0"
    return data + b"\0" * (-len(data) % 4)


def _argument(value) -> tuple[str, bytes]:
    if isinstance(value, str):
        return "s", padded(value)
    if isinstance(value, (int, np.integer)):
        return "i", struct.pack(">i", int(value))
    return "f", struct.pack(">f", float(value))


class FrameMessages:
    """The messages of every frame, in order: each an address, fixed leading arguments (strings, ints,
    floats) and a number of float arguments that change from frame to frame (:meth:`add`);
    :meth:`bundles` writes a frame's."""

    def __init__(self):
        self.heads: list[bytes] = []  # each message's size prefix, address, type tags and fixed arguments
        self.counts: list[int] = []  # each message's changing float arguments

    def add(self, address: str, *fixed, floats: int = 0) -> None:
        """A message to ``address`` with the arguments ``fixed`` and then ``floats`` float arguments."""
        tags, values = zip(*(_argument(v) for v in fixed)) if fixed else ((), ())
        head = padded(address) + padded("," + "".join(tags) + "f" * floats) + b"".join(values)
        self.heads.append(struct.pack(">i", len(head) + 4 * floats) + head)
        self.counts.append(int(floats))

    def bundles(self, values: np.ndarray, max_bytes: int) -> list[bytes]:
        """The messages with ``values`` (sum of their float counts,) as their changing arguments, in order,
        as bundles of at most ``max_bytes`` each (a message goes whole into one; a new bundle starts where
        the next message would not fit)."""
        data = np.asarray(values, dtype=">f4").tobytes()
        out, parts, size, at = [], [_BUNDLE], len(_BUNDLE), 0
        for head, count in zip(self.heads, self.counts):
            message = head + data[at:at + 4 * count]
            at += 4 * count
            if size + len(message) > max_bytes and len(parts) > 1:
                out.append(b"".join(parts))
                parts, size = [_BUNDLE], len(_BUNDLE)
            parts.append(message)
            size += len(message)
        out.append(b"".join(parts))
        return out
