"""``KHR_draco_mesh_compression``: a primitive's Draco-compressed triangles and attributes, decoded.

The extension names a buffer view holding one Draco mesh (decoded with the ``DracoPy`` package) and
maps glTF attribute semantics to the unique ids of that mesh's attributes. The primitive's own
accessors for those semantics keep ``count``, ``type``, ``componentType`` and ``normalized`` (but no
``bufferView``) and describe the decoded values, so each decoded attribute is read as its accessor says:

- a float accessor takes the values as decoded (Draco has undone its own quantization of positions,
  normals, texture coordinates and weights);
- a normalized integer accessor (data quantized with ``KHR_mesh_quantization`` before compression)
  takes the decoded integers divided as glTF normalizes them (``max(c / 32767, -1)`` etc.);
- any other integer accessor (``JOINTS_0``) takes the integers.

The decoded arrays are handed to the :class:`~infuse_gltf.accessors.AccessorReader`, so the mesh code
reads them like any accessor. Draco holds triangles, so the decoded faces are a triangle list whatever
the primitive's ``mode`` (the extension allows ``TRIANGLES`` and ``TRIANGLE_STRIP``). Attributes the
extension does not name, morph targets among them, are ordinary accessors and are read as usual.
"""
from __future__ import annotations

import numpy as np

from infuse.errors import InputError, MissingFeatureError

from .accessors import COMPONENT_DTYPES, AccessorReader, check_index, normalized_to_float

EXTENSION = "KHR_draco_mesh_compression"


def load_primitive(reader: AccessorReader, prim: dict, place: str) -> np.ndarray:
    """Decode the Draco mesh of primitive ``prim`` (its ``extensions`` hold :data:`EXTENSION`), hand
    every attribute the extension names to ``reader`` under its accessor index, and return the
    (T, 3) int64 triangles.

    Raises :class:`InputError` for malformed extension data or decoded data that does not match its
    accessors, :class:`MissingFeatureError` when ``DracoPy`` is not installed."""
    file = reader.file
    eplace = f"{place}.extensions.{EXTENSION}"
    ext = prim["extensions"][EXTENSION]
    if not isinstance(ext, dict) or not isinstance(ext.get("attributes"), dict):
        raise InputError(file, eplace, "must be an object with attributes")
    view = check_index(file, f"{eplace}.bufferView", ext.get("bufferView"), len(reader.views), "bufferView")
    source = f"bufferViews[{view}]"
    attributes = prim.get("attributes") or {}
    targets: dict[str, tuple[int, int]] = {}  # semantic -> (accessor index, Draco unique id)
    for semantic, uid in ext["attributes"].items():
        if semantic not in attributes:
            raise InputError(file, f"{eplace}.attributes.{semantic}", "names an attribute the primitive does not have")
        if not isinstance(uid, int) or isinstance(uid, bool) or uid < 0:
            raise InputError(file, f"{eplace}.attributes.{semantic}", f"{uid!r} is not a Draco attribute id")
        index = check_index(file, f"{place}.attributes.{semantic}", attributes[semantic], len(reader.accessors), "accessor")
        targets[semantic] = (index, uid)

    raw, _ = reader.view_bytes(view, eplace)
    mesh = decode(bytes(raw), file, eplace)
    faces = getattr(mesh, "faces", None)
    if faces is None:
        raise InputError(file, eplace, "holds a Draco point cloud, not a triangle mesh")
    points = len(mesh.points)
    triangles = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if triangles.size and triangles.max() >= points:
        raise InputError(file, eplace, f"a decoded face names a vertex beyond the {points} decoded")
    if "indices" in prim and prim.get("mode", 4) == 4:
        index = check_index(file, f"{place}.indices", prim["indices"], len(reader.accessors), "accessor")
        count = reader.layout(index, f"accessors[{index}]")[3]
        if count != triangles.size:
            raise InputError(file, f"accessors[{index}]", f"count {count} does not match the {triangles.size} indices Draco decodes")
    for semantic, (index, uid) in targets.items():
        attribute = mesh.get_attribute_by_unique_id(uid)
        if attribute is None:
            raise InputError(file, f"{eplace}.attributes.{semantic}", f"the Draco mesh has no attribute with id {uid}")
        reader.adopt(index, _typed(reader, index, np.asarray(attribute["data"]), points, f"{place}.attributes.{semantic}"), source)
    return triangles


def decode(data: bytes, file, place: str):
    """The ``DracoPy`` mesh (or point cloud) encoded in ``data``."""
    try:
        import DracoPy
    except ImportError:
        raise MissingFeatureError(file, f"it is Draco-compressed ({EXTENSION}) and the DracoPy package is not installed "
                                        "(pip install DracoPy)") from None
    try:
        return DracoPy.decode(data)
    except (DracoPy.FileTypeException, ValueError, RuntimeError) as exc:
        raise InputError(file, place, f"its Draco data does not decode: {exc}") from None


def _typed(reader: AccessorReader, index: int, values: np.ndarray, points: int, place: str) -> np.ndarray:
    """Decoded attribute ``values`` (points, n) as accessor ``index`` describes them, shaped and typed
    as :meth:`AccessorReader.read` returns accessors."""
    file = reader.file
    aplace = f"accessors[{index}]"
    ctype, cols, rows, count = reader.layout(index, aplace)
    if count != points:
        raise InputError(file, aplace, f"count {count} does not match the {points} vertices Draco decodes ({place})")
    values = values.reshape(len(values), -1)
    if cols != 1 or values.shape != (points, rows):
        raise InputError(file, aplace, f"decodes to {values.shape[1]} components per vertex, its type holds {cols * rows} ({place})")
    if ctype == 5126:
        return values.astype(np.float32)
    dtype = COMPONENT_DTYPES[ctype]
    info = np.iinfo(dtype)
    # DracoPy hands some integer attributes over as float32 or a wider integer type: the values are what counts.
    if values.dtype.kind == "f" and not np.all(np.isfinite(values) & (values == np.rint(values))):
        raise InputError(file, aplace, f"decodes to fractional values for an integer accessor ({place})")
    if values.size and (values.min() < info.min or values.max() > info.max):
        raise InputError(file, aplace, f"decodes to values outside the range of its component type ({place})")
    ints = values.astype(dtype)
    return normalized_to_float(ints, ctype) if reader.accessors[index].get("normalized") else ints
