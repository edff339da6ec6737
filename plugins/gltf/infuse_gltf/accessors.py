"""Accessors as numpy arrays: every component type, normalized integers, ``byteStride``, sparse storage.

:class:`AccessorReader` returns ``(count, components)`` arrays (``(count, cols, rows)`` for matrices,
column-major as stored) viewed straight onto the buffer with ``np.ndarray(buffer=...)`` when possible.
Normalized integers become float64 per the glTF rules (``max(c / 127, -1)`` etc.). Out-of-range indices,
views running past their buffer and compressed views that cannot be decoded raise errors that name the
accessor (``"accessors[3]"``). Accessors whose data another decoder produced (Draco primitives, see
:mod:`infuse_gltf.draco`) are handed over with :meth:`AccessorReader.adopt` and read like the others.
"""
from __future__ import annotations

import numpy as np

from infuse import limits
from infuse.errors import InputError, MissingFeatureError

from . import meshopt
from .container import GltfDocument

COMPONENT_DTYPES: dict[int, np.dtype] = {
    5120: np.dtype("<i1"),
    5121: np.dtype("<u1"),
    5122: np.dtype("<i2"),
    5123: np.dtype("<u2"),
    5125: np.dtype("<u4"),
    5126: np.dtype("<f4"),
}
#: Divisors of normalized integer component types.
NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0, 5125: 4294967295.0}
#: Accessor type -> (columns, rows); vectors and scalars are one column.
TYPE_SHAPES: dict[str, tuple[int, int]] = {
    "SCALAR": (1, 1), "VEC2": (1, 2), "VEC3": (1, 3), "VEC4": (1, 4),
    "MAT2": (2, 2), "MAT3": (3, 3), "MAT4": (4, 4),
}
#: Extensions that compress buffer views; only meshopt compresses non-mesh data (animations, skins).
VIEW_COMPRESSION = ("EXT_meshopt_compression", "KHR_meshopt_compression")
#: Extensions that compress a mesh primitive's data (decoded by :mod:`infuse_gltf.draco`).
MESH_COMPRESSION = ("KHR_draco_mesh_compression",)


def check_index(file, place: str, value, count: int, what: str) -> int:
    """``value`` as an index into an array of ``count`` items, or :class:`InputError`."""
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < count:
        raise InputError(file, place, f"{what} index {value!r} out of range (there are {count})")
    return value


def _int_field(file, place: str, obj: dict, key: str, default=None, minimum: int = 0) -> int:
    value = obj.get(key, default)
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise InputError(file, place, f"{key} {value!r} is not an integer >= {minimum}")
    return value


class AccessorReader:
    """Reads the accessors of one :class:`GltfDocument`, caching decoded arrays by index.

    ``mesh``: the reads are mesh data, so meshopt views in the index modes or with the octahedral
    filter are decoded (they are refused for skeleton and clip data)."""

    def __init__(self, doc: GltfDocument, mesh: bool = False):
        self.doc = doc
        self.mesh = mesh
        self.file = doc.path
        self.accessors = doc.json.get("accessors", [])
        self.views = doc.json.get("bufferViews", [])
        if not isinstance(self.accessors, list) or not isinstance(self.views, list):
            raise InputError(self.file, "accessors" if not isinstance(self.accessors, list) else "bufferViews", "is not an array")
        self._cache: dict[int, np.ndarray] = {}
        self._finite: set[int] = set()
        self._decoded: dict[int, memoryview] = {}
        self._adopted: dict[int, str] = {}  # accessor index -> where its adopted data came from

    def _compression(self, view_index: int) -> str | None:
        view = self.views[view_index]
        ext = view.get("extensions") if isinstance(view, dict) else None
        return next((name for name in VIEW_COMPRESSION if name in ext), None) if isinstance(ext, dict) else None

    def view_bytes(self, view_index, place: str) -> tuple[memoryview, int | None]:
        """The bytes of a buffer view and its byteStride."""
        view_index = check_index(self.file, place, view_index, len(self.views), "bufferView")
        vplace = f"bufferViews[{view_index}]"
        view = self.views[view_index]
        if not isinstance(view, dict):
            raise InputError(self.file, vplace, "is not an object")
        compression = self._compression(view_index)
        buffer_index = check_index(self.file, vplace, view.get("buffer"), len(self.doc.buffers), "buffer")
        data = self.doc.buffers[buffer_index]
        offset = _int_field(self.file, vplace, view, "byteOffset", 0)
        length = _int_field(self.file, vplace, view, "byteLength", None, 1)
        if compression:
            data, offset = self._decompressed(view_index, view["extensions"][compression], length, vplace, compression), 0
        elif data is None:
            raise InputError(self.file, vplace, f"buffers[{buffer_index}] has no data")
        if offset + length > len(data):
            raise InputError(self.file, vplace, f"byteOffset {offset} + byteLength {length} runs past buffers[{buffer_index}] ({len(data)} bytes)")
        stride = view.get("byteStride")
        if stride is not None and (not isinstance(stride, int) or isinstance(stride, bool) or not 4 <= stride <= 252 or stride % 4):
            raise InputError(self.file, vplace, f"byteStride {stride!r} must be a multiple of 4 in [4, 252]")
        return data[offset:offset + length], stride

    def _decompressed(self, view_index: int, ext, length: int, place: str, name: str) -> memoryview:
        """The decoded bytes of a meshopt-compressed view (decoded once)."""
        done = self._decoded.get(view_index)
        if done is not None:
            return done
        if not isinstance(ext, dict):
            raise InputError(self.file, f"{place}.extensions.{name}", "is not an object")
        source_index = check_index(self.file, f"{place}.extensions.{name}", ext.get("buffer"), len(self.doc.buffers), "buffer")
        source = self.doc.buffers[source_index]
        start = _int_field(self.file, f"{place}.extensions.{name}", ext, "byteOffset", 0)
        size = _int_field(self.file, f"{place}.extensions.{name}", ext, "byteLength", None, 1)
        if source is None or start + size > len(source):
            raise InputError(self.file, f"{place}.extensions.{name}", f"compressed bytes lie outside buffers[{source_index}]")
        try:
            decoded = meshopt.decode_view(ext, source[start:start + size], mesh=self.mesh)
        except meshopt.MeshoptUnsupported as exc:
            raise MissingFeatureError(self.file, f"{place} is compressed with {name}: {exc}") from None
        except meshopt.MeshoptError as exc:
            raise InputError(self.file, f"{place}.extensions.{name}", str(exc)) from None
        if len(decoded) < length:
            raise InputError(self.file, place, f"decodes to {len(decoded)} bytes, byteLength is {length}")
        self._decoded[view_index] = memoryview(decoded)
        return self._decoded[view_index]

    def read(self, index, place: str = "accessor", check_finite: bool = True) -> np.ndarray:
        """Accessor ``index`` as a read-only array: ``(count, n)`` for vectors/scalars (n = 1..4) or
        ``(count, cols, rows)`` for matrices. Float and normalized data are float32/float64; other
        integers keep their dtype. NaN or infinity raises :class:`InputError` unless ``check_finite``
        is False (the caller then checks many accessors at once, and asks again to name a bad one)."""
        index = check_index(self.file, place, index, len(self.accessors), "accessor")
        out = self._cache.get(index)
        if out is None:
            out = self._decode(index)
            out.setflags(write=False)
            self._cache[index] = out
        if check_finite and index not in self._finite:
            if out.dtype.kind == "f" and not np.all(np.isfinite(out)):
                bad = int(np.nonzero(~np.isfinite(out.reshape(len(out), -1)).all(axis=1))[0][0])
                raise InputError(self.file, f"accessors[{index}] element {bad}", "value is not finite (NaN or infinity)")
            self._finite.add(index)
        return out

    def adopt(self, index: int, values: np.ndarray, source: str) -> None:
        """Take ``values`` (shaped and typed as :meth:`read` returns them) as accessor ``index``'s data,
        decoded from ``source`` (a place such as ``"bufferViews[4]"``). One accessor decoded from two
        different sources raises :class:`InputError`."""
        earlier = self._adopted.get(index)
        if earlier is not None and earlier != source:
            raise InputError(self.file, f"accessors[{index}]", f"is decoded from both {earlier} and {source}")
        values.setflags(write=False)
        self._adopted[index] = source
        self._cache[index] = values
        self._finite.discard(index)

    def layout(self, index: int, place: str) -> tuple[int, int, int, int]:
        """``(componentType, columns, rows, count)`` of accessor ``index``, checked."""
        acc = self.accessors[index]
        if not isinstance(acc, dict):
            raise InputError(self.file, place, "is not an object")
        ctype = acc.get("componentType")
        if not isinstance(ctype, int) or ctype not in COMPONENT_DTYPES:
            raise InputError(self.file, place, f"componentType {ctype!r} is not a glTF component type")
        if not isinstance(acc.get("type"), str) or acc["type"] not in TYPE_SHAPES:
            raise InputError(self.file, place, f"type {acc.get('type')!r} is not a glTF accessor type")
        if acc.get("normalized") and ctype == 5126:
            raise InputError(self.file, place, "normalized is set on a float accessor")
        cols, rows = TYPE_SHAPES[acc["type"]]
        count = _int_field(self.file, place, acc, "count", None, 1)
        limits.check(self.file, place, "count x components", count * cols * rows, "MAX_ELEMENTS")
        return ctype, cols, rows, count

    def _decode(self, index: int) -> np.ndarray:
        place = f"accessors[{index}]"
        ctype, cols, rows, count = self.layout(index, place)
        acc = self.accessors[index]
        dtype = COMPONENT_DTYPES[ctype]
        offset = _int_field(self.file, place, acc, "byteOffset", 0)
        if offset % dtype.itemsize:
            raise InputError(self.file, place, f"byteOffset {offset} is not a multiple of the component size {dtype.itemsize}")
        # Matrix columns start on 4-byte boundaries (MAT2/MAT3 of bytes or shorts are padded).
        col_stride = -(-rows * dtype.itemsize // 4) * 4 if cols > 1 else rows * dtype.itemsize
        element = col_stride * cols
        if "bufferView" in acc:
            raw, stride = self.view_bytes(acc["bufferView"], place)
            stride = stride or element
            if offset + stride * (count - 1) + element > len(raw):
                raise InputError(self.file, place, f"{count} elements at byteOffset {offset} run past the end of bufferViews[{acc['bufferView']}]")
            arr = np.ndarray((count, cols, rows), dtype, buffer=raw, offset=offset, strides=(stride, col_stride, dtype.itemsize))
        else:
            arr = np.zeros((count, cols, rows), dtype)
        if "sparse" in acc:
            arr = self._apply_sparse(np.array(arr), acc["sparse"], count, dtype, (cols, rows), place)
        if acc.get("normalized"):
            arr = normalized_to_float(arr, ctype)
        return arr.reshape(count, rows) if cols == 1 else arr

    def _apply_sparse(self, arr: np.ndarray, sparse: dict, count: int, dtype, shape, place: str) -> np.ndarray:
        place = f"{place}.sparse"
        if not isinstance(sparse, dict):
            raise InputError(self.file, place, "is not an object")
        n = _int_field(self.file, place, sparse, "count", None, 1)
        if n > count:
            raise InputError(self.file, place, f"count {n} exceeds the accessor count {count}")
        idx_spec, val_spec = sparse.get("indices"), sparse.get("values")
        if not isinstance(idx_spec, dict) or not isinstance(val_spec, dict):
            raise InputError(self.file, place, "indices and values must be objects")
        ctype = idx_spec.get("componentType")
        idx_dtype = {5121: np.dtype("<u1"), 5123: np.dtype("<u2"), 5125: np.dtype("<u4")}.get(ctype) if isinstance(ctype, int) else None
        if idx_dtype is None:
            raise InputError(self.file, f"{place}.indices", f"componentType {idx_spec.get('componentType')!r} must be an unsigned integer type")
        indices = self._packed(idx_spec, idx_dtype, (n,), f"{place}.indices")
        if np.any(indices >= count) or np.any(np.diff(indices.astype(np.int64)) <= 0):
            raise InputError(self.file, f"{place}.indices", "indices must be strictly increasing and below the accessor count")
        values = self._packed(val_spec, dtype, (n,) + shape, f"{place}.values")
        arr[indices] = values
        return arr

    def _packed(self, spec: dict, dtype, shape, place: str) -> np.ndarray:
        raw, _ = self.view_bytes(spec.get("bufferView"), place)
        offset = _int_field(self.file, place, spec, "byteOffset", 0)
        size = int(np.prod(shape)) * dtype.itemsize
        if offset + size > len(raw):
            raise InputError(self.file, place, "runs past the end of its bufferView")
        return np.frombuffer(raw, dtype, int(np.prod(shape)), offset).reshape(shape)


def normalized_to_float(values: np.ndarray, component_type: int) -> np.ndarray:
    """Normalized integers of ``component_type`` as float64 (``max(c / 127, -1)`` etc.)."""
    return np.maximum(values.astype(np.float64) / NORMALIZED_DIVISORS[component_type], -1.0)


def compression_extensions(doc_json: dict) -> list[str]:
    """Compression extensions the document declares (mesh, buffer-view or quantization)."""
    used = set(doc_json.get("extensionsUsed") or []) | set(doc_json.get("extensionsRequired") or [])
    return sorted(e for e in used if e in VIEW_COMPRESSION + MESH_COMPRESSION + ("KHR_mesh_quantization",))
