"""Decoding ``EXT_meshopt_compression`` / ``KHR_meshopt_compression`` buffer views (codecs v0 and v1).

Attributes (vertex codec v0): a header byte ``0xa0``, then blocks of up to 256 elements; in a
block every byte lane of the element is stored as groups of 16 deltas, each group packed with 0,
2, 4 or 8 bits per value (a 2-bit mode per group in a header; the largest 2- or 4-bit value
escapes to a following full byte). Deltas are zigzag coded and accumulate, per lane, from the
previous element (the first from the tail that closes the stream). Filters then turn the bytes
into values: ``EXPONENTIAL`` (24-bit mantissa and 8-bit exponent per float), ``QUATERNION`` (three
16-bit components and the index of the dropped largest one) and ``OCTAHEDRAL`` (unit vectors,
normals and tangents).

Triangles (index codec v1, header ``0xe1``): one code byte per triangle that reuses an edge and
vertex of recent triangles (16-entry FIFOs), the next new vertex, or an index stored as a zigzag
LEB128 delta. Indices (``0xd1``): LEB128 zigzag deltas against one of two baselines. Both are
sequential state machines, decoded triangle by triangle.
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


def _leb128(data: bytes, pos: int) -> tuple[int, int]:
    """An unsigned LEB128 value at ``pos`` and the position after it."""
    value = shift = 0
    while True:
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value, pos
        shift += 7
        if shift > 28:
            raise MeshoptError("index varint longer than 5 bytes")


def decode_triangles(data: bytes, count: int) -> np.ndarray:
    """The ``count`` triangle-list indices (uint32) of an index codec stream (mode ``TRIANGLES``)."""
    if count % 3:
        raise MeshoptError(f"TRIANGLES count {count} is not a multiple of 3")
    if len(data) < 1 + count // 3 + 16:
        raise MeshoptError("stream shorter than its codes and tail")
    if data[0] & 0xF0 != 0xE0:
        raise MeshoptError(f"not a meshopt triangle stream (header byte 0x{data[0]:02x})")
    if data[0] & 0x0F != 1:
        raise MeshoptUnsupported(f"index codec version {data[0] & 0x0F} (only version 1 is decoded)")
    codes = data[1:1 + count // 3]
    aux = data[len(data) - 16:]
    pos, end = 1 + count // 3, len(data) - 16
    edges = [(0, 0)] * 16
    verts = [0] * 16
    eo = vo = nxt = last = 0
    out = [0] * count
    try:
        for i, code in enumerate(codes):
            if code < 0xF0:  # an edge of a recent triangle, and a third vertex
                a, b = edges[(eo - 1 - (code >> 4)) & 15]
                y = code & 15
                if y == 0:
                    c, nxt = nxt, nxt + 1
                elif y < 0xD:
                    c = verts[(vo - 1 - y) & 15]
                elif y < 0xF:
                    c = last = last + (1 if y == 0xE else -1)
                else:
                    v, pos = _leb128(data, pos)
                    c = last = last + ((v >> 1) ^ -(v & 1))
                if y == 0 or y >= 0xD:
                    verts[vo] = c
                    vo = (vo + 1) & 15
                edges[eo] = (c, b)
                edges[(eo + 1) & 15] = (a, c)
                eo = (eo + 2) & 15
            else:  # three vertices: new, recent (from the FIFO) or explicit
                if code < 0xFE:
                    z, w = aux[code & 15] >> 4, aux[code & 15] & 15
                    explicit_a = False
                else:
                    byte = data[pos]
                    pos += 1
                    if byte == 0:
                        nxt = 0
                    z, w = byte >> 4, byte & 15
                    explicit_a = code == 0xFF
                if explicit_a:
                    v, pos = _leb128(data, pos)
                    a = last = last + ((v >> 1) ^ -(v & 1))
                else:
                    a, nxt = nxt, nxt + 1
                picked = []
                for k in (z, w):
                    if k == 0:
                        value, nxt = nxt, nxt + 1
                    elif k < 0xF or code < 0xFE:
                        value = verts[(vo - k) & 15]
                    else:
                        v, pos = _leb128(data, pos)
                        value = last = last + ((v >> 1) ^ -(v & 1))
                    picked.append(value)
                b, c = picked
                verts[vo] = a
                vo = (vo + 1) & 15
                for k, value in ((z, b), (w, c)):
                    if k == 0 or (k == 0xF and code >= 0xFE):
                        verts[vo] = value
                        vo = (vo + 1) & 15
                edges[eo] = (b, a)
                edges[(eo + 1) & 15] = (c, b)
                edges[(eo + 2) & 15] = (a, c)
                eo = (eo + 3) & 15
            out[3 * i:3 * i + 3] = (a, b, c)
    except IndexError:
        raise MeshoptError("stream ends inside the triangle data") from None
    if pos != end:
        raise MeshoptError(f"{end - pos} bytes of triangle data left over")
    return np.array(out, dtype=np.int64).astype(np.uint32)


def decode_indices(data: bytes, count: int) -> np.ndarray:
    """The ``count`` indices (uint32) of an index sequence stream (mode ``INDICES``)."""
    if len(data) < 1 + 4:
        raise MeshoptError("stream shorter than its header and tail")
    if data[0] & 0xF0 != 0xD0:
        raise MeshoptError(f"not a meshopt index stream (header byte 0x{data[0]:02x})")
    if data[0] & 0x0F != 1:
        raise MeshoptUnsupported(f"index sequence codec version {data[0] & 0x0F} (only version 1 is decoded)")
    base = [0, 0]
    out = [0] * count
    pos = 1
    try:
        for i in range(count):
            v, pos = _leb128(data, pos)
            k = v & 1
            base[k] += (v >> 2) ^ -((v >> 1) & 1)
            out[i] = base[k]
    except IndexError:
        raise MeshoptError("stream ends inside the index data") from None
    if len(data) - pos != 4:
        raise MeshoptError(f"stream has {len(data) - pos} bytes after the indices, expected a 4-byte tail")
    return np.array(out, dtype=np.int64).astype(np.uint32)


def _unfilter_octahedral(raw: np.ndarray, stride: int) -> np.ndarray:
    itype = np.dtype("<i1") if stride == 4 else np.dtype("<i2")
    v = raw.view(itype).reshape(len(raw), 4).astype(np.float64)
    one = np.where(v[:, 2] != 0, v[:, 2], 1.0)
    x, y = v[:, 0] / one, v[:, 1] / one
    z = 1.0 - np.abs(x) - np.abs(y)
    t = np.minimum(z, 0.0)
    x, y = x - np.copysign(t, x), y - np.copysign(t, y)
    length = np.maximum(np.sqrt(x * x + y * y + z * z), 1e-12)
    top = 127.0 if stride == 4 else 32767.0
    out = np.empty((len(raw), 4), dtype=itype)
    out[:, :3] = np.rint(np.stack([x, y, z], axis=1) / length[:, None] * top)
    out[:, 3] = v[:, 3]
    return out.view(np.uint8).reshape(raw.shape)


def decode_view(ext: dict, source: bytes, mesh: bool = False) -> bytes:
    """The bytes of a compressed buffer view, from its extension object and the compressed bytes.

    Index modes and the octahedral filter only ever hold mesh data (indices, normals, tangents):
    they are decoded for ``mesh`` reads only; elsewhere (a skeleton, a clip) they are refused.
    """
    mode = ext.get("mode")
    flt = ext.get("filter", "NONE")
    count, stride = ext.get("count"), ext.get("byteStride")
    if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (count, stride)):
        raise MeshoptError("count and byteStride must be positive integers")
    # Checked before decoding: the most a codec packs into one compressed byte is 64 bytes (a vertex
    # stream of zeros: two header bits per group of 16 bytes) or 3 indices (a triangle code byte).
    most = 3 * stride * len(source) if mode in ("TRIANGLES", "INDICES") else 64 * len(source)
    if count * stride > most:
        raise MeshoptError(f"count {count} x byteStride {stride} is more than {len(source)} compressed bytes can hold")
    if not mesh and (mode != "ATTRIBUTES" or flt == "OCTAHEDRAL"):
        what = f"mode {mode!r}" if mode != "ATTRIBUTES" else f"filter {flt!r}"
        raise MeshoptUnsupported(f"{what} holds mesh data (indices or normals), not skeleton or clip data")
    if mode in ("TRIANGLES", "INDICES"):
        if stride not in (2, 4):
            raise MeshoptError(f"{mode} needs a byteStride of 2 or 4")
        indices = (decode_triangles if mode == "TRIANGLES" else decode_indices)(bytes(source), count)
        return indices.astype("<u2" if stride == 2 else "<u4").tobytes()
    if mode != "ATTRIBUTES":
        raise MeshoptUnsupported(f"mode {mode!r} is not a meshopt mode")
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
    if flt == "OCTAHEDRAL":
        if stride not in (4, 8):
            raise MeshoptError("OCTAHEDRAL filter needs a byteStride of 4 or 8")
        return _unfilter_octahedral(raw, stride).tobytes()
    raise MeshoptUnsupported(f"filter {flt!r} is not decoded")
