"""BVH text -> :class:`BvhDocument`: the file's own numbers, in its own units and axes.

The HIERARCHY block is read line by line (it is small); the MOTION block is read in one go with
numpy: values per line are counted on the raw bytes and all numbers are converted at once
(:mod:`.numbers`), so a file's frame count never drives a Python loop. Malformed input raises
:class:`infuse.errors.InputError` naming the line, joint or frame.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from infuse import limits
from infuse.errors import InputError

from .numbers import parse_floats, token_bounds, whitespace

#: Channel names as written by convention; files are matched case-insensitively.
CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CHANNEL_BY_KEY = {c.lower(): c for c in CHANNEL_NAMES}
_MOTION_LINE = re.compile(rb"^[ \t]*MOTION[ \t\r]*$", re.MULTILINE | re.IGNORECASE)
_FRAMES = re.compile(r"^\s*Frames\s*:\s*(\S*)\s*$", re.IGNORECASE)
_FRAME_TIME = re.compile(r"^\s*Frame\s*Time\s*:\s*(\S*)\s*$", re.IGNORECASE)


@dataclass(frozen=True)
class BvhDocument:
    """The contents of a BVH file, unconverted (file units, file axes, Euler angles in degrees).

    - ``names`` (J,), ``parents`` (J,) in file order (parents precede children, -1 for roots).
    - ``offsets`` (J, 3): OFFSET of each joint; ``channels``: per joint, its channel names in file order.
    - ``end_site_parents`` (E,), ``end_site_offsets`` (E, 3).
    - ``frame_time`` seconds; ``values`` (F, C) every channel of every frame, C = total channels,
      columns in file order (joint by joint, channels in their listed order).
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    end_site_parents: np.ndarray
    end_site_offsets: np.ndarray
    frame_time: float
    values: np.ndarray


def _numbers(file, lineno: int, what: str, words: list[str], count: int) -> list[float]:
    if len(words) != count:
        raise InputError(file, f"line {lineno}", f"{what} needs {count} numbers, got {len(words)}")
    try:
        out = [float(w) for w in words]
    except ValueError:
        raise InputError(file, f"line {lineno}", f"{what} has a value that is not a number: {' '.join(words)!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise InputError(file, f"line {lineno}", f"{what} has a value that is not finite: {' '.join(words)!r}")
    return out


def _parse_hierarchy(file, text: str):
    """Joints, offsets, channels and end sites from the text before MOTION."""
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float] | None] = []
    channels: list[tuple[str, ...]] = []
    name_lines: dict[str, int] = {}
    site_parents: list[int] = []
    site_offsets: list[list[float] | None] = []
    # Each open block: ("joint", index) or ("site", index); ``pending`` waits for its "{".
    stack: list[tuple[str, int]] = []
    pending: tuple[str, int] | None = None
    seen_hierarchy = False
    lineno = 0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        words = raw.split()
        while words:
            key = words[0]
            upper = key.upper()
            if not seen_hierarchy:
                if upper != "HIERARCHY":
                    raise InputError(file, f"line {lineno}", f"expected HIERARCHY, found {key[:40]!r}: not a BVH file")
                seen_hierarchy = True
                words = words[1:]
                continue
            if key == "{":
                if pending is None:
                    raise InputError(file, f"line {lineno}", "'{' without a ROOT, JOINT or End Site before it")
                stack.append(pending)
                pending = None
                words = words[1:]
                continue
            if key == "}":
                if pending is not None:
                    raise InputError(file, f"line {lineno}", "'}' where '{' was expected")
                if not stack:
                    raise InputError(file, f"line {lineno}", "unbalanced braces: '}' closes nothing")
                kind, i = stack.pop()
                if kind == "joint" and offsets[i] is None:
                    raise InputError(file, f"joint {names[i]!r}", "has no OFFSET")
                if kind == "site" and site_offsets[i] is None:
                    raise InputError(file, f"line {lineno}", "End Site has no OFFSET")
                words = words[1:]
                continue
            if pending is not None:
                raise InputError(file, f"line {lineno}", f"expected '{{', found {key[:40]!r}")
            if upper in ("ROOT", "JOINT"):
                parts = raw.split(None, 1)
                if parts[0] != key:
                    raise InputError(file, f"line {lineno}", f"{upper} must start its line")
                rest = parts[1].strip() if len(parts) > 1 else ""  # names may contain spaces
                opens = rest.endswith("{")  # "JOINT name {" on one line
                if opens:
                    rest = rest[:-1].strip()
                if not rest:
                    raise InputError(file, f"line {lineno}", f"{upper} without a name")
                if upper == "ROOT" and stack:
                    raise InputError(file, f"line {lineno}", f"ROOT {rest!r} inside another joint (unbalanced braces)")
                if upper == "JOINT":
                    if not stack or stack[-1][0] != "joint":
                        raise InputError(file, f"line {lineno}", f"JOINT {rest!r} outside a joint")
                if rest in name_lines:
                    raise InputError(file, f"line {lineno}", f"duplicate joint name {rest!r} (first on line {name_lines[rest]})")
                name_lines[rest] = lineno
                names.append(rest)
                parents.append(stack[-1][1] if stack else -1)
                offsets.append(None)
                channels.append(())
                pending = ("joint", len(names) - 1)
                if opens:
                    stack.append(pending)
                    pending = None
                break
            if upper == "END":
                if len(words) < 2 or words[1].upper() != "SITE":
                    raise InputError(file, f"line {lineno}", f"expected 'End Site', found {raw.strip()[:40]!r}")
                if not stack or stack[-1][0] != "joint":
                    raise InputError(file, f"line {lineno}", "End Site outside a joint")
                site_parents.append(stack[-1][1])
                site_offsets.append(None)
                pending = ("site", len(site_parents) - 1)
                words = words[2:]
                continue
            if not stack:
                raise InputError(file, f"line {lineno}", f"{key[:40]!r} outside any joint")
            kind, i = stack[-1]
            owner = f"joint {names[i]!r}" if kind == "joint" else "End Site"
            if upper == "OFFSET":
                values = _numbers(file, lineno, f"OFFSET of {owner}", words[1:4], 3)
                if kind == "joint":
                    offsets[i] = values
                else:
                    site_offsets[i] = values
                words = words[4:]
                continue
            if upper == "CHANNELS":
                if kind != "joint":
                    raise InputError(file, f"line {lineno}", "End Site cannot have CHANNELS")
                if len(words) < 2 or not words[1].isdigit():
                    raise InputError(file, f"line {lineno}", f"CHANNELS of {owner} needs a count")
                count = int(words[1])
                listed = words[2:2 + count]
                if len(listed) != count or len(words) > 2 + count and words[2 + count].lower() in _CHANNEL_BY_KEY:
                    raise InputError(file, f"line {lineno}", f"CHANNELS of {owner} says {count} but lists {len(words) - 2}")
                unknown = [c for c in listed if c.lower() not in _CHANNEL_BY_KEY]
                if unknown:
                    raise InputError(file, f"line {lineno}", f"unknown channel {unknown[0]!r} in {owner}")
                chans = tuple(_CHANNEL_BY_KEY[c.lower()] for c in listed)
                if len(set(chans)) != len(chans):
                    raise InputError(file, f"line {lineno}", f"{owner} lists a channel twice")
                if channels[i]:
                    raise InputError(file, f"line {lineno}", f"{owner} has a second CHANNELS line")
                channels[i] = chans
                words = words[2 + count:]
                continue
            raise InputError(file, f"line {lineno}", f"unexpected {key[:40]!r} in the hierarchy")
    if not seen_hierarchy:
        raise InputError(file, "line 1", "empty file" if not text.strip() else "no HIERARCHY")
    if pending is not None or stack:
        open_kind, i = pending or stack[-1]
        what = f"joint {names[i]!r}" if open_kind == "joint" else "an End Site"
        raise InputError(file, f"line {lineno}", f"unbalanced braces: {what} is never closed (file truncated?)")
    if not names:
        raise InputError(file, f"line {lineno}", "no ROOT joint")
    return names, parents, offsets, channels, site_parents, site_offsets


def _header_value(file, lines: list[str], index: int, lineno: int, pattern: re.Pattern, label: str) -> str:
    if index >= len(lines):
        raise InputError(file, f"line {lineno}", f"missing '{label}:' line (file truncated?)")
    match = pattern.match(lines[index])
    if not match:
        raise InputError(file, f"line {lineno}", f"expected '{label}:', found {lines[index].strip()[:40]!r}")
    return match.group(1)


def _line_counts(newlines: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (0-based) numbers of the non-empty lines and how many tokens each holds."""
    before = np.searchsorted(starts, newlines)  # tokens ahead of each line end
    per_line = np.diff(np.concatenate(([0], before, [len(starts)])))
    lines = np.flatnonzero(per_line)
    return lines, per_line[lines]


def _first_bad_token(buf: bytes, starts: np.ndarray) -> int:
    """Index of the first token that is not a number (only called once parsing failed)."""
    for i, token in enumerate(buf.split()):
        try:
            float(token)
        except ValueError:
            return i
    return len(starts) - 1


def _parse_motion(file, buf: bytes, first_line: int, frames: int, channels: list[tuple[str, ...]], names: list[str]) -> np.ndarray:
    """(frames, C) values from the bytes after 'Frame Time', whose first line is ``first_line`` (1-based)."""
    width = sum(len(c) for c in channels)
    b = np.frombuffer(buf, dtype=np.uint8)
    space = whitespace(b)
    bounds = token_bounds(b, space)
    starts = bounds[0]
    newlines = np.flatnonzero(b == 10)
    lines, counts = _line_counts(newlines, starts)
    total = len(starts)

    def line_of(token: int) -> int:
        return first_line + int(np.searchsorted(newlines, starts[token]))

    if len(lines) == frames and np.any(counts != width):
        k = int(np.argmax(counts != width))
        raise InputError(file, f"line {first_line + int(lines[k])} (frame {k})",
                         f"frame has {int(counts[k])} values, expected {width} (one per channel)")
    if total != frames * width:
        # Name the first frame whose line does not hold one value per channel, else the end.
        bad = np.nonzero(counts[: frames] != width)[0]
        if total < frames * width:
            k = int(bad[0]) if bad.size else min(len(lines), frames - 1)
            line = first_line + (int(lines[k]) if k < len(lines) else (int(lines[-1]) + 1 if len(lines) else 0))
            raise InputError(file, f"line {line} (frame {k})",
                             f"motion data ends early: {total} values for {frames} frames of {width} channels (file truncated?)")
        k = int(bad[0]) if bad.size else frames
        line = first_line + int(lines[min(k, len(lines) - 1)])
        raise InputError(file, f"line {line} (frame {k})",
                         f"{total} values where {frames} frames of {width} channels need {frames * width}")
    if total == 0:
        return np.zeros((frames, width))
    try:
        values = parse_floats(buf, b, space, bounds)
    except ValueError:
        i = _first_bad_token(buf, starts)
        token = buf[starts[i]:].split(None, 1)[0][:40].decode("utf-8", "replace")
        raise InputError(file, f"line {line_of(i)} (frame {i // max(width, 1)})",
                         f"{token!r} is not a number") from None
    values = values.reshape(frames, width)
    finite = np.isfinite(values)
    if not finite.all():
        i = int(np.argmin(finite.ravel()))
        frame, column = divmod(i, width)
        owners = [(n, c) for n, chans in zip(names, channels) for c in chans]
        joint, chan = owners[column]
        raise InputError(file, f"line {line_of(i)} (frame {frame})",
                         f"joint {joint!r} {chan} is not a finite number ({values.ravel()[i]})")
    return values


def _decode(file, data: bytes) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")  # some exporters write joint names in a legacy code page


def parse(path: str | Path, data: bytes | None = None) -> BvhDocument:
    """Parse a BVH file (or its bytes ``data``) without converting units or axes."""
    file = str(path)
    if data is None:
        data = Path(path).read_bytes()
    if not data.strip():
        raise InputError(file, "line 1", "empty file")
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        raise InputError(file, f"line {line}", "binary data (NUL byte): not a BVH text file")
    if b"\n" not in data and b"\r" in data:  # classic Mac line ends
        data = data.replace(b"\r", b"\n")
    match = _MOTION_LINE.search(data)
    header_end = match.start() if match else len(data)
    header = _decode(file, data[:header_end])
    names, parents, offsets, channels, site_parents, site_offsets = _parse_hierarchy(file, header)
    motion_line = header.count("\n") + 1
    if match is None:
        raise InputError(file, f"line {motion_line}", "missing MOTION section (file truncated?)")
    # "Frames:" and "Frame Time:" are the two non-empty lines after MOTION; the data follows them.
    rest = data[match.end():]
    newline = rest.find(b"\n")
    pos = len(rest) if newline < 0 else newline + 1  # skip what is left of the MOTION line
    lineno = motion_line
    meta_lines: list[tuple[int, str]] = []
    while len(meta_lines) < 2 and pos < len(rest):
        lineno += 1
        end = rest.find(b"\n", pos)
        end = len(rest) if end < 0 else end
        if rest[pos:end].strip():
            meta_lines.append((lineno, _decode(file, rest[pos:end])))
        pos = end + 1
    texts = [t for _, t in meta_lines]
    line_of = [n for n, _ in meta_lines]
    frames_text = _header_value(file, texts, 0, line_of[0] if line_of else motion_line + 1, _FRAMES, "Frames")
    time_text = _header_value(file, texts, 1, line_of[1] if len(line_of) > 1 else lineno, _FRAME_TIME, "Frame Time")
    try:
        frames = int(frames_text)
    except ValueError:
        raise InputError(file, f"line {line_of[0]}", f"Frames must be a whole number, got {frames_text[:40]!r}") from None
    if frames < 0:
        raise InputError(file, f"line {line_of[0]}", f"Frames must not be negative, got {frames}")
    limits.check(file, f"line {line_of[0]}", "Frames", frames, "MAX_FRAMES")
    limits.check(file, f"line {line_of[0]}", "frames x joints", frames * len(names), "MAX_FRAME_JOINTS")
    try:
        frame_time = float(time_text)
    except ValueError:
        raise InputError(file, f"line {line_of[1]}", f"Frame Time must be a number, got {time_text[:40]!r}") from None
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise InputError(file, f"line {line_of[1]}", f"Frame Time must be positive seconds, got {time_text}")
    values = _parse_motion(file, rest[pos:], lineno + 1, frames, channels, names)
    return BvhDocument(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        offsets=np.array(offsets, dtype=np.float64).reshape(-1, 3),
        channels=tuple(channels),
        end_site_parents=np.array(site_parents, dtype=np.int64),
        end_site_offsets=np.array(site_offsets, dtype=np.float64).reshape(-1, 3),
        frame_time=frame_time,
        values=values,
    )
