"""The glTF container: a ``.glb`` (header, JSON chunk, BIN chunk) or a ``.gltf`` JSON file with its buffers.

Parsing yields a :class:`GltfDocument`: the JSON document as plain Python objects and the binary
buffers as read-only ``memoryview`` slices of the file (no copies). External buffers (``.bin`` beside a
``.gltf``) and ``data:`` URIs are resolved. Malformed containers raise
:class:`~infuse.errors.InputError` naming the place (``"GLB header"``, ``"buffers[1]"``...).
"""
from __future__ import annotations

import base64
import binascii
import json
import struct
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote

from infuse import limits, references
from infuse.errors import InputError

GLB_MAGIC = b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942


@dataclass
class GltfDocument:
    """A parsed glTF asset.

    - ``json``: the glTF JSON document (dicts and lists).
    - ``buffers``: one entry per ``json["buffers"]`` item: the bytes (``memoryview``), or ``None`` for a
      buffer without data (an ``EXT_meshopt_compression`` fallback buffer).
    - ``path``: the file it came from (external images are resolved against its folder); ``container``:
      ``"glb"`` or ``"gltf"``.
    """

    json: dict
    buffers: list = field(default_factory=list)
    path: Path | None = None
    container: str = "glb"

    @property
    def base_dir(self) -> Path | None:
        return self.path.parent if self.path is not None else None


def parse_file(path: str | Path) -> GltfDocument:
    """Parse a ``.glb``/``.vrm``/``.vrma`` (binary) or ``.gltf`` (JSON) file; the format is told by its first bytes."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(path, None, f"cannot read: {exc.strerror or exc}") from None
    return parse_bytes(data, path)


def parse_bytes(data: bytes, path: str | Path | None = None) -> GltfDocument:
    """Parse glTF content from memory; ``path`` names the file in errors and locates external buffers."""
    path = Path(path) if path is not None else None
    if data[:4] == GLB_MAGIC:
        doc, bin_chunk = _split_glb(data, path)
        container = "glb"
    elif data.lstrip(b"\xef\xbb\xbf \t\r\n")[:1] == b"{":
        doc, bin_chunk = _decode_json(data, path, "JSON"), None
        container = "gltf"
    else:
        raise InputError(path, None, f"not a glTF or GLB file: it starts with {bytes(data[:8])!r}, "
                         "neither the GLB header 'glTF' nor a JSON object")
    if not isinstance(doc, dict):
        raise InputError(path, "JSON", "the document is not a JSON object")
    version = str((doc.get("asset") or {}).get("version", "")) if isinstance(doc.get("asset"), dict) else ""
    if not version.startswith("2."):
        raise InputError(path, "asset.version", f"not a glTF 2.0 asset (version {version or 'missing'!r})")
    _check_top_level(doc, path)
    buffers = _load_buffers(doc, bin_chunk, path)
    return GltfDocument(doc, buffers, path, container)


#: The glTF 2.0 top-level arrays: each holds objects (the ``extensions...`` ones hold names).
OBJECT_ARRAYS = ("accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials", "meshes",
                 "nodes", "samplers", "scenes", "skins", "textures")


def _check_top_level(doc: dict, path: Path | None) -> None:
    """The shape the glTF 2.0 schema gives the top level: arrays of objects, arrays of names, objects."""
    for key in OBJECT_ARRAYS:
        value = doc.get(key, [])
        if not isinstance(value, list):
            raise InputError(path, key, "is not an array")
        bad = next((i for i, item in enumerate(value) if not isinstance(item, dict)), None)
        if bad is not None:
            raise InputError(path, f"{key}[{bad}]", "is not an object")
    for key in ("extensionsUsed", "extensionsRequired"):
        value = doc.get(key, [])
        if not isinstance(value, list) or not all(isinstance(name, str) for name in value):
            raise InputError(path, key, "is not an array of extension names")
    for key in ("asset", "extensions"):
        if key in doc and not isinstance(doc[key], dict):
            raise InputError(path, key, "is not an object")
    scene = doc.get("scene", 0)
    if not isinstance(scene, int) or isinstance(scene, bool):
        raise InputError(path, "scene", f"{scene!r} is not a scene index")


def _split_glb(data: bytes, path: Path | None) -> tuple[dict, memoryview | None]:
    if len(data) < 12:
        raise InputError(path, "GLB header", f"truncated: {len(data)} bytes, the header alone is 12")
    _, version, length = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise InputError(path, "GLB header", f"GLB version {version}, expected 2")
    if length > len(data):
        raise InputError(path, "GLB header", f"truncated: header says {length} bytes, file has {len(data)}")
    if length < len(data):
        raise InputError(path, "GLB header", f"header says {length} bytes but the file has {len(data)} (trailing data)")
    view = memoryview(data)
    chunks: list[tuple[int, memoryview]] = []
    offset = 12
    while offset < length:
        if offset + 8 > length:
            raise InputError(path, f"GLB chunk {len(chunks)}", "truncated chunk header")
        clen, ctype = struct.unpack_from("<II", data, offset)
        start = offset + 8
        if start + clen > length:
            raise InputError(path, f"GLB chunk {len(chunks)}", f"chunk length {clen} runs past the end of the file")
        chunks.append((ctype, view[start:start + clen]))
        offset = start + clen
        offset += (-offset) % 4  # chunks are 4-byte aligned
    if not chunks or chunks[0][0] != CHUNK_JSON:
        raise InputError(path, "GLB chunk 0", "the first chunk is not JSON")
    doc = _decode_json(chunks[0][1], path, "JSON chunk")
    bin_chunk = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == CHUNK_BIN else None
    return doc, bin_chunk


def _decode_json(raw, path: Path | None, place: str):
    try:
        text = bytes(raw).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(path, place, f"not UTF-8 text (byte {exc.start})") from None
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(path, f"{place} line {exc.lineno} column {exc.colno}", f"bad JSON: {exc.msg}") from None
    except RecursionError:
        raise InputError(path, place, f"bad JSON: nested deeper than the parser can follow (infuse.limits.MAX_NESTING "
                         f"is {limits.MAX_NESTING})") from None
    limits.check(path, place, "JSON nesting", limits.json_depth(document), "MAX_NESTING")
    return document


def decode_data_uri(uri: str, path: Path | None, place: str) -> bytes:
    """The bytes of a ``data:[mime];base64,...`` URI."""
    head, _, payload = uri.partition(",")
    if not head.endswith(";base64"):
        raise InputError(path, place, "data URI is not base64")
    try:
        return base64.b64decode(payload, validate=False)
    except (binascii.Error, ValueError) as exc:
        raise InputError(path, place, f"bad base64 in data URI: {exc}") from None


def read_uri(uri: str, path: Path | None, place: str, max_bytes: int | None = None) -> bytes:
    """The bytes behind a buffer or image URI (``data:`` or a path relative to the glTF file, confined to
    its folder: see :mod:`infuse.references`), at most ``max_bytes`` of a file."""
    if not isinstance(uri, str):
        raise InputError(path, place, "uri is not a string")
    if uri.startswith("data:"):
        return decode_data_uri(uri, path, place)
    if "://" in uri or uri.lower().startswith("file:"):
        raise InputError(path, place, f"external URL {uri[:80]!r} is not read (only files beside the glTF)")
    if path is None:
        raise InputError(path, place, f"external file {uri[:80]!r} cannot be resolved without a file path")
    return references.read(path, unquote(uri), place, "buffer or image file", max_bytes)


def _load_buffers(doc: dict, bin_chunk: memoryview | None, path: Path | None) -> list:
    buffers = doc.get("buffers", [])
    if not isinstance(buffers, list):
        raise InputError(path, "buffers", "is not an array")
    out: list = []
    for i, buf in enumerate(buffers):
        place = f"buffers[{i}]"
        if not isinstance(buf, dict):
            raise InputError(path, place, "is not an object")
        length = buf.get("byteLength")
        if not isinstance(length, int) or isinstance(length, bool) or length < 0:
            raise InputError(path, place, f"byteLength {length!r} is not a non-negative integer")
        uri = buf.get("uri")
        if uri is None:
            if i == 0 and bin_chunk is not None:
                data = bin_chunk
            elif (buf.get("extensions") or {}).get("EXT_meshopt_compression", {}).get("fallback"):
                out.append(None)  # no data: every view of it is meshopt-compressed elsewhere
                continue
            else:
                raise InputError(path, place, "missing buffer: no uri and no GLB BIN chunk")
        else:
            data = memoryview(read_uri(uri, path, place, max_bytes=length))
        if len(data) < length:
            raise InputError(path, place, f"truncated: byteLength {length} but only {len(data)} bytes present")
        out.append(data[:length].toreadonly())
    return out
