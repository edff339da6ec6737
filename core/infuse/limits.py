"""Bounds on what an input file may ask for, checked before anything is allocated or run.

A file declares counts and sizes (frames, accessor elements, joints, nesting, BML behaviours, times)
ahead of its data. Readers compare each declared count with the data actually present and with these
bounds, and raise :class:`~infuse.errors.LimitError` naming the bound, so that a corrupted count never
turns into gigabytes allocated or hours of work. The bounds are far above any real character or clip.
"""
from __future__ import annotations

from .errors import InputError, LimitError

#: Joints in one skeleton (real rigs: 20 to 1,000).
MAX_JOINTS = 10_000
#: Ancestors of a joint or node (real rigs: under 100).
MAX_DEPTH = 1_000
#: Nesting of a JSON document's arrays and objects (glTF nests about 8 deep).
MAX_NESTING = 100
#: Frames in one clip: 100 hours at 30 fps.
MAX_FRAMES = 10_800_000
#: Frame rate of a clip, frames per second (a frame time under 0.1 ms is a corrupted number; glTF's
#: float32 key times could not tell the frames apart).
MAX_FPS = 10_000.0
#: Frames x joints of one clip, the rows of its (F, J, 4) rotations: 1 GiB of float64 rotations.
MAX_FRAME_JOINTS = 1 << 25
#: Elements (numbers) one array of a file may declare: 1 GiB of float64.
MAX_ELEMENTS = 1 << 27
#: Largest coordinate, metres: a skeleton or a root path beyond 1,000 km is a corrupted number (float32,
#: which glTF stores, keeps no centimetres there).
MAX_COORDINATE_M = 1e6
#: Latest time a BML block, behaviour or scene may ask for, seconds (one day).
MAX_TIME_S = 86_400.0
#: Elements (blocks, behaviours, constraints, speech marks) in one BML document: real documents hold
#: tens; scheduling costs about half a millisecond per behaviour.
MAX_BML_ELEMENTS = 20_000
#: Pixels of one texture image (Pillow's own bomb limit is checked with this one).
MAX_IMAGE_PIXELS = 1 << 28


def check(file, place: str | None, what: str, asked: int | float, limit: str) -> None:
    """Raise :class:`~infuse.errors.LimitError` when ``asked`` is over the bound named ``limit``."""
    bound = globals()[limit]
    if asked > bound:
        raise LimitError(file, place, what, asked, limit, bound)


def check_coordinates(file, place: str | None, values, what: str = "coordinate") -> None:
    """Raise :class:`~infuse.errors.InputError` unless every value is finite and within
    :data:`MAX_COORDINATE_M` (``values``: any array of metres)."""
    import numpy as np

    values = np.asarray(values, dtype=np.float64)
    if values.size == 0:
        return
    finite = np.isfinite(values)
    if not finite.all():
        raise InputError(file, place, f"{what} is not finite ({values.ravel()[np.argmin(finite.ravel())]})")
    largest = float(np.max(np.abs(values)))
    if largest > MAX_COORDINATE_M:
        raise LimitError(file, place, f"{what} (metres)", largest, "MAX_COORDINATE_M", MAX_COORDINATE_M)


def json_depth(document) -> int:
    """Nesting depth of a parsed JSON document (0 for a number or string), walked without recursion."""
    deepest, stack = 0, [(document, 0)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict):
            node = node.values()
        elif not isinstance(node, list):
            continue
        deepest = max(deepest, depth + 1)
        stack.extend((child, depth + 1) for child in node if isinstance(child, (dict, list)))
    return deepest
