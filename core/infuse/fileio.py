"""Loading and saving files through whichever reader or writer plugin handles their type."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import references, registry
from .asset import Asset
from .atomic import atomic_path
from .errors import PARSE_ERRORS, InfuseError, InputError, UnsupportedFormatError, UsageError
from .motion import Motion
from .plugin_types import normalized_extension



def _pick(kind: str, table: dict, path: Path, format: str | None):
    if format:
        if format not in table:
            raise UnsupportedFormatError(path, f"no {kind} named {format!r}; installed: {', '.join(sorted(table)) or 'none'}")
        return table[format]
    ext = normalized_extension(path)
    for item in table.values():
        if ext in item.extensions:
            return item
    known = sorted({e for item in table.values() for e in item.extensions})
    raise UnsupportedFormatError(path, f"no installed {kind} handles {ext or 'files without extension'!r}; known: {', '.join(known)}")


def load(path: str | Path, format: str | None = None, **options) -> Asset:
    """Read ``path`` with the reader for its extension (or the reader named ``format``).

    ``options`` go to the reader: ``units`` and ``up_axis`` override detection. Malformed files
    raise :class:`InputError` naming the file, the place and the problem. ``allow_external=True`` lets
    the file's references to other files lead outside its folder (see :mod:`infuse.references`).
    """
    allowed = options.pop("allow_external", None)
    if allowed is not None:
        with references.allow_external(bool(allowed)):
            return load(path, format, **options)
    path = Path(path)
    if not path.exists():
        raise InputError(path, None, "file not found")
    if path.is_dir():
        raise InputError(path, None, "is a folder, expected a file")
    reader = _pick("reader", registry.table_for_file("reader", path, format), path, format)
    try:
        # Hostile numbers (1e308 offsets) may overflow in a reader's arithmetic; what it returns is then
        # refused by the model's own checks (finite, bounded), so numpy's warnings would only be noise.
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return reader.read(path, **options)
    except InputError as exc:
        if exc.file is None:  # raised by the core model's own checks, which do not know the file
            raise exc.naming(path) from None
        raise
    except InfuseError:
        raise
    except RecursionError:
        raise InputError(path, None, f"cannot be read as {reader.name}: nesting too deep") from None
    except PARSE_ERRORS as exc:
        raise InputError(path, None, f"cannot be read as {reader.name}: {type(exc).__name__}: {exc}") from exc


def save(asset: Asset | Motion, path: str | Path, format: str | None = None, **options) -> Path:
    """Write ``asset`` to ``path`` atomically with the writer for its extension; returns ``path``.

    A :class:`~infuse.motion.Motion` is written as a file of its skeleton holding that one clip.
    """
    path = Path(path)
    if isinstance(asset, Motion):
        asset = Asset(path=None, format="motion", skeleton=asset.skeleton, motions={asset.name or "clip": asset})
    elif not isinstance(asset, Asset):
        raise UsageError(f"{path}: save writes an Asset or a Motion, not a {type(asset).__name__}")
    writer = _pick("writer", registry.table_for_file("writer", path, format), path, format)
    with atomic_path(path) as tmp:
        writer.write(asset, tmp, **options)
    return path


def json_ready(value, digits: int | None = None):
    """``value`` with numpy arrays and scalars made plain lists and numbers, dict keys made strings and
    anything else JSON cannot hold written as its ``str``; Python floats rounded to ``digits`` when given.
    Infinities and NaN, which JSON cannot hold, become ``None`` (an unbounded limit reads as null)."""
    if isinstance(value, dict):
        return {str(k): json_ready(v, digits) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v, digits) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist(), digits)
    if isinstance(value, (np.floating, np.integer)):
        return json_ready(value.item(), digits)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, float) and digits is not None:
        return round(value, digits)
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)
