"""Parsing Acclaim ``.amc`` motions, vectorized over lines with numpy string operations.

Layout: ``#`` comments and ``:FULLY-SPECIFIED`` / ``:DEGREES`` / ``:RADIANS`` header keywords, then
for each frame a line with the frame number followed by one line per animated bone,
``NAME v1 v2 ...`` (the root's values in the ASF ``:root order``, a bone's in its ``dof`` order).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from infuse.errors import InputError


@dataclass
class AmcFile:
    path: Path
    angle_unit: str | None  # "deg", "rad" or None when the header does not say
    first_frame: int
    frames: int
    lines: dict[str, np.ndarray]  # bone name (in order of appearance) -> (F,) line numbers of its values
    values: dict[str, list[str]]  # bone name -> per-frame value strings (parsed by :func:`bone_values`)
    problems: list[InputError]  # bones missing from, or repeated in, a frame (see :meth:`check_frames`)

    def check_frames(self) -> None:
        """Raise the first problem with the frame structure (call after checking bone names)."""
        if self.problems:
            raise self.problems[0]


#: Most the longest line of an ``.amc`` may exceed the mean line (frame numbers and bone rows: about 3).
MAX_WIDTH_RATIO = 16


def parse_amc(path: Path, text: str) -> AmcFile:
    """Split ``.amc`` text into frames and per-bone value lines (each bone should appear once per frame)."""
    # One fixed-width byte array of the lines (every line is short, see reader._read_text; bytes take a
    # quarter of the memory of str), processed whole.
    lines = text.replace("\t", " ").encode("utf-8").split(b"\n")
    # The array is as wide as the longest line: lines of very unequal length (a few long ones among
    # millions of short ones) would make it many times the file's size. An AMC's lines are alike.
    widest = max(lines, key=len)
    if len(lines) * len(widest) > MAX_WIDTH_RATIO * len(text) + (1 << 20):
        line = lines.index(widest) + 1
        raise InputError(path, f"line {line}", f"lines of very unequal length ({len(widest)} characters here, "
                         f"{len(text) / len(lines):.1f} on average): not an AMC motion")
    raw = np.array(lines)
    del lines
    stripped = np.char.strip(np.char.partition(raw, b"#")[:, 0]) if raw.size else raw
    del raw
    numbers = np.nonzero(stripped != b"")[0]
    if numbers.size == 0:
        raise InputError(path, None, "empty file")
    content = stripped[numbers]
    del stripped
    header = np.char.startswith(content, b":")
    angle_unit = None
    for line in content[header]:
        word = line.split()[0].upper().decode("utf-8", "replace")
        if word in (":DEGREES", ":DEGREE"):
            angle_unit = "deg"
        elif word in (":RADIANS", ":RADIAN"):
            angle_unit = "rad"
        elif word != ":FULLY-SPECIFIED":
            raise InputError(path, f"line {numbers[np.nonzero(content == line)[0][0]] + 1}", f"unknown header keyword {word!r}")
    body_start = int(np.argmin(header)) if not header.all() else header.size
    if header[body_start:].any():
        at = body_start + int(np.argmax(header[body_start:]))
        raise InputError(path, f"line {numbers[at] + 1}", "header keyword after the first frame")
    content, numbers = content[body_start:], numbers[body_start:] + 1
    if content.size == 0:
        raise InputError(path, None, "no frames")
    parts = np.char.partition(content, b" ")
    first, rest = parts[:, 0], np.char.strip(parts[:, 2])
    del parts
    is_frame = np.char.isdigit(first) & (rest == b"")
    if not is_frame[0]:
        shown = content[0][:40].decode("utf-8", "replace")
        raise InputError(path, f"line {numbers[0]}", f"expected a frame number, found {shown!r}")
    frame_numbers = np.array([int(f) for f in first[is_frame].tolist()], dtype=object)
    if frame_numbers.size and max(frame_numbers) > np.iinfo(np.int64).max // 2:
        raise InputError(path, f"line {numbers[0]}", "frame numbers too large")
    frame_numbers = frame_numbers.astype(np.int64)
    jumps = np.nonzero(np.diff(frame_numbers) != 1)[0]
    if jumps.size:
        k = jumps[0]
        line = numbers[np.nonzero(is_frame)[0][k + 1]]
        raise InputError(path, f"line {line}", f"frame number {frame_numbers[k + 1]} does not follow {frame_numbers[k]}")
    frame_of = (np.cumsum(is_frame) - 1)[~is_frame]
    frames = int(frame_numbers.size)
    bone_rows = np.nonzero(~is_frame)[0]
    # Rows grouped by bone name in one sort, the names in their first order.
    names, first_row, which = np.unique(first[bone_rows], return_index=True, return_inverse=True)
    order = np.argsort(which, kind="stable")
    groups = np.split(order, np.cumsum(np.bincount(which, minlength=len(names)))[:-1])
    bone_numbers: dict[str, np.ndarray] = {}
    values: dict[str, list[str]] = {}
    problems: list[InputError] = []
    for k in np.argsort(first_row, kind="stable"):
        name = names[k].decode("utf-8", "replace")
        rows = groups[k]
        counts = np.bincount(frame_of[rows], minlength=frames)
        if counts.max() > 1:
            f = int(np.argmax(counts > 1))
            problems.append(InputError(path, f"frame {frame_numbers[f]}", f"bone {name!r} appears {counts[f]} times"))
        elif counts.min() == 0:
            f = int(np.argmin(counts))
            problems.append(InputError(path, f"frame {frame_numbers[f]}", f"bone {name!r} is missing (file truncated?)"))
        bone_numbers[name] = numbers[bone_rows[rows]]
        values[name] = [v.decode("utf-8", "replace") for v in rest[bone_rows[rows]].tolist()]
    return AmcFile(path, angle_unit, int(frame_numbers[0]), frames, bone_numbers, values, problems)


def bone_values(amc: AmcFile, name: str, count: int) -> np.ndarray:
    """(F, count) numbers of bone ``name``; a wrong count, a non-number or NaN raises :class:`InputError`."""
    rows = amc.values[name]
    tokens = " ".join(rows).split()
    if len(tokens) != amc.frames * count:
        for line, row in zip(amc.lines[name], rows):
            if len(row.split()) != count:
                raise InputError(amc.path, f"line {line}", f"bone {name!r} has {len(row.split())} values, its dofs need {count}")
    try:
        out = np.array(tokens, dtype=np.float64).reshape(amc.frames, count)
    except ValueError:
        for line, row in zip(amc.lines[name], rows):
            for tok in row.split():
                try:
                    float(tok)
                except ValueError:
                    raise InputError(amc.path, f"line {line}", f"bone {name!r}: {tok[:30]!r} is not a number") from None
        raise
    bad = ~np.isfinite(out).all(axis=1)
    if bad.any():
        f = int(np.argmax(bad))
        raise InputError(amc.path, f"line {amc.lines[name][f]}", f"bone {name!r}: value is not finite (frame {amc.first_frame + f})")
    return out
