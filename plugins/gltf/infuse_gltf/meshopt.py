"""Decoding ``EXT_meshopt_compression`` / ``KHR_meshopt_compression`` attribute views (vertex codec v0).

The format (meshoptimizer's vertex codec, as the extension specifies it): a header byte ``0xa0``,
then blocks of up to 256 elements; in a block every byte lane of the element is stored as groups
of 16 deltas, each group packed with 0, 2, 4 or 8 bits per value (a 2-bit mode per group in a
header; the largest 2- or 4-bit value escapes to a following full byte). Deltas are zigzag coded
and accumulate, per lane, from the previous element (the first from the tail that closes the
stream). Filters then turn the bytes into values: ``EXPONENTIAL`` (24-bit mantissa and 8-bit
exponent per float) and ``QUATERNION`` (three 16-bit components and the index of the dropped largest one).

Only ``mode: ATTRIBUTES`` with the filters animation and skin data use is decoded; index buffers
and octahedral normals only ever hold mesh data, which infuse does not read.
"""
from __future__ import annotations

import numpy as np

HEADER = 0xA0
GROUP = 16
BLOCK_BYTES = 8192
BLOCK_MAX = 256
TAIL_MIN = 32

# Per byte: the 2-bit values (high bits first) and the 4-bit values.
_TWO_BIT = [[(b >> s) & 3 for s in (6, 4, 2, 0)] for b in range(256)]
_FOUR_BIT = [[(b >> 4) & 15, b & 15] for b in range(256)]


class MeshoptError(ValueError):
    """The compressed stream is malformed."""


class MeshoptUnsupported(MeshoptError):
    """The stream uses a mode, filter or codec version not decoded here."""


def _block_size(stride: int) -> int:
    return min((BLOCK_BYTES // stride) & ~(GROUP - 1), BLOCK_MAX)


def _decode_bytes(data: bytes, pos: int, size: int, out: bytearray) -> int:
    """Decode ``size`` (a multiple of 16) byte deltas into ``out``; returns the new read position."""
    groups = size // GROUP
    header = data[pos:pos + (groups + 3) // 4]
    pos += len(header)
    for g in range(groups):
        mode = (header[g // 4] >> ((g % 4) * 2)) & 3
        start = g * GROUP
        if pos + (0, 4, 8, GROUP)[mode] > len(data):
            raise MeshoptError("stream ends inside a group")
        if mode == 0:
            out[start:start + GROUP] = bytes(GROUP)
        elif mode == 3:
            out[start:start + GROUP] = data[pos:pos + GROUP]
            pos += GROUP
        else:
            packed = 4 if mode == 1 else 8
            table, sentinel = (_TWO_BIT, 3) if mode == 1 else (_FOUR_BIT, 15)
            values = [v for byte in data[pos:pos + packed] for v in table[byte]]
            pos += packed
            for i, v in enumerate(values):
                if v == sentinel:
                    v = data[pos]
                    pos += 1
                out[start + i] = v
    return pos


def decode_vertex_buffer(data: bytes, count: int, stride: int) -> np.ndarray:
    """The (count, stride) uint8 elements encoded in ``data``."""
    if stride % 4 or not 0 < stride <= 256:
        raise MeshoptError(f"byteStride {stride} must be a multiple of 4 up to 256")
    tail = max(stride, TAIL_MIN)
    if len(data) < 1 + tail:
        raise MeshoptError("stream shorter than its header and tail")
    if data[0] & 0xF0 != HEADER:
        raise MeshoptError(f"not a meshopt vertex stream (header byte 0x{data[0]:02x})")
    if data[0] & 0x0F != 0:
        raise MeshoptUnsupported(f"vertex codec version {data[0] & 0x0F} (only version 0 is decoded)")
    last = np.frombuffer(data, np.uint8, stride, len(data) - stride).copy()
    out = np.empty((count, stride), dtype=np.uint8)
    pos = 1
    block = _block_size(stride)
    lane = bytearray(BLOCK_MAX)
    try:
        for first in range(0, count, block):
            n = min(block, count - first)
            aligned = (n + GROUP - 1) & ~(GROUP - 1)
            for k in range(stride):
                pos = _decode_bytes(data, pos, aligned, lane)
                deltas = np.frombuffer(lane, np.uint8, n)
                unzigzag = (-(deltas & 1).astype(np.int16) ^ (deltas >> 1)).astype(np.uint8)
                unzigzag[:1] += last[k:k + 1]
                out[first:first + n, k] = np.cumsum(unzigzag, dtype=np.uint8)
            last = out[first + n - 1].copy()
    except IndexError:
        raise MeshoptError("stream ends inside a block") from None
    if len(data) - pos != tail:
        raise MeshoptError(f"stream has {len(data) - pos} bytes after the blocks, expected a {tail}-byte tail")
    return out


def _unfilter_exponential(raw: np.ndarray) -> np.ndarray:
    v = raw.view("<i4")
    mantissa = (v << 8) >> 8
    exponent = v >> 24
    return np.ldexp(mantissa.astype(np.float64), exponent).astype("<f4").view(np.uint8).reshape(raw.shape)


def _unfilter_quaternion(raw: np.ndarray) -> np.ndarray:
    itype = np.dtype("<i2")
    q = raw.view(itype).reshape(len(raw), 4).astype(np.int64)
    top = 32767.0
    scale = (1.0 / np.sqrt(2.0)) / (q[:, 3] | 3)
    xyz = q[:, :3] * scale[:, None]
    w = np.sqrt(np.maximum(1.0 - np.sum(xyz * xyz, axis=1), 0.0))
    comps = np.concatenate((xyz, w[:, None]), axis=1)
    rounded = np.trunc(comps * top + np.where(comps >= 0, 0.5, -0.5)).astype(np.int64)
    qc = q[:, 3] & 3
    out = np.empty_like(rounded)
    rows = np.arange(len(q))
    for k, shift in enumerate((1, 2, 3, 0)):  # x, y, z go after the dropped component, w in its place
        out[rows, (qc + shift) & 3] = rounded[:, k]
    return out.astype(itype).view(np.uint8).reshape(raw.shape)


def decode_view(ext: dict, source: bytes) -> bytes:
    """The bytes of a compressed buffer view, from its extension object and the compressed bytes."""
    mode = ext.get("mode")
    flt = ext.get("filter", "NONE")
    count, stride = ext.get("count"), ext.get("byteStride")
    if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (count, stride)):
        raise MeshoptError("count and byteStride must be positive integers")
    if mode != "ATTRIBUTES":
        raise MeshoptUnsupported(f"mode {mode!r} holds mesh indices, which infuse does not decode")
    raw = decode_vertex_buffer(bytes(source), count, stride)
    if flt == "NONE":
        return raw.tobytes()
    if flt == "EXPONENTIAL":
        if stride % 4:
            raise MeshoptError("EXPONENTIAL filter needs a byteStride multiple of 4")
        return _unfilter_exponential(raw).tobytes()
    if flt == "QUATERNION":
        if stride != 8:
            raise MeshoptError("QUATERNION filter needs a byteStride of 8")
        return _unfilter_quaternion(raw).tobytes()
    raise MeshoptUnsupported(f"filter {flt!r} is not decoded (it holds mesh normals or tangents)")
