"""Parsing SmartBody ``.skm`` motions; the frame block is read with numpy in one go.

Layout::

    # SKM Motion Definition
    # ... Units: cm
    SkMotion
    name "ChrUtah_Walk001"
    channels N
    JOINT TYPE                      (N lines; TYPE XPos YPos ZPos Quat XRot YRot ZRot)
    [start_kt T]
    frames F
    kt TIME fr VALUES...            (F lines)
    ready time: 0.3                 (timing metadata, seconds; or NAME VALUE for other metadata)

A ``Quat`` channel is written as 3 numbers, a rotation vector (axis * angle, radians); Euler
channels are degrees; position channels are in the header's unit.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from infuse.errors import InputError, UnusableInputError

from .sk import POS_CHANNELS, ROT_CHANNELS, declared_units
from .tokens import TokenStream, tokenize

#: Numbers each channel type takes in a frame.
CHANNEL_SIZES = {**{k: 1 for k in POS_CHANNELS}, **{k: 1 for k in ROT_CHANNELS}, "Quat": 3}
_SIGNATURES = ("SkMotion", "HoMotion", "KnMotion")
_FRAMES_LINE = re.compile(r"^[ \t]*frames[ \t]+(\S+)[ \t]*\r?$", re.M)
_KEY_LINE = re.compile(r"^[ \t]*kt[ \t]+(\S+)[ \t]+fr[ \t]+(.*?)[ \t]*\r?$", re.M)
_LAST_KEY_LINE = re.compile(r".*^[ \t]*kt[ \t][^\n]*", re.M | re.S)  # greedy: ends at the last key line
_NONEMPTY_LINE = re.compile(r"^[ \t]*\S", re.M)
_TIMING = re.compile(r"^(\w+)[ \t]+time[ \t]*:?[ \t]*(\S+)$")
_TIMING_PREFIX = re.compile(r"^\w+[ \t]+time\b")
_TAGGED = re.compile(r"^(\w+)[ \t]*:?[ \t]*(\S.*)$")


@dataclass(frozen=True)
class Channel:
    joint: str
    type: str
    line: int

    @property
    def size(self) -> int:
        return CHANNEL_SIZES[self.type]


@dataclass
class SkmFile:
    """A parsed ``.skm``: ``values`` (F, V) hold every frame's numbers in channel order, as written."""

    path: Path
    name: str
    units: str | None
    units_line: int | None
    channels: list[Channel]
    key_times: np.ndarray
    values: np.ndarray
    start_kt: float | None
    timings: dict = field(default_factory=dict)  # name -> seconds, as written
    metadata: dict = field(default_factory=dict)  # other NAME VALUE lines

    @property
    def joints(self) -> list[str]:
        """Joint names in order of first appearance."""
        return list(dict.fromkeys(c.joint for c in self.channels))

    def columns(self) -> np.ndarray:
        """(C,) first column of each channel in ``values``."""
        sizes = np.array([c.size for c in self.channels], dtype=np.int64)
        return np.cumsum(sizes) - sizes


def _line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


def _parse_header(path: Path, header: str) -> tuple[str, list[Channel], float | None]:
    ts = TokenStream(tokenize(header, path), path)
    sig = ts.next("'SkMotion'")
    if sig.text == "HIERARCHY":
        raise UnusableInputError(path, "this .skm holds BVH text; rename it to .bvh to read it")
    if sig.text not in _SIGNATURES:
        raise ts.error(f"expected 'SkMotion' at the start, found {sig.text!r}", sig.line)
    name = path.stem
    if ts.upcoming() == "name":
        ts.pos += 1
        name = ts.word("the motion name")
    ts.expect("channels")
    count = ts.integer("the channel count")
    channels: list[Channel] = []
    seen: set[tuple[str, str]] = set()
    for _ in range(count):
        if ts.finished:
            raise ts.error(f"'channels {count}' but only {len(channels)} channel lines follow before 'frames'")
        joint = ts.next("a channel's joint name")
        kind = ts.next(f"the channel type of joint {joint.text!r}")
        if kind.text in ("Swing", "Twist"):
            raise UnusableInputError(path, f"line {kind.line}: {kind.text} channels (swing-twist joints) are not supported")
        if kind.text not in CHANNEL_SIZES:
            raise InputError(path, f"line {kind.line}", f"channel {joint.text} {kind.text}: unknown channel type "
                             f"(expected XPos, YPos, ZPos, Quat, XRot, YRot or ZRot)")
        key = (joint.text, kind.text)
        if key in seen:
            raise InputError(path, f"line {joint.line}", f"channel {joint.text} {kind.text} is listed twice")
        seen.add(key)
        channels.append(Channel(joint.text, kind.text, joint.line))
    start_kt = None
    if ts.upcoming() == "start_kt":
        ts.pos += 1
        start_kt = ts.number("start_kt")
    tok = ts.peek()
    if tok is not None:
        raise ts.error(f"expected 'frames' after the {count} channels, found {tok.text!r} "
                       f"(is the channel count right?)", tok.line)
    return name, channels, start_kt


def _frame_values(path: Path, text: str, body_start: int, frames: int, channels: list[Channel]):
    """Key times (F,), values (F, V) of the frame block, and where the block ends in ``text``."""
    sizes = np.array([c.size for c in channels])
    width = int(sizes.sum())
    body = text[body_start:]
    rows = _KEY_LINE.findall(body)
    block = body[: m.end()] if (m := _LAST_KEY_LINE.match(body)) else ""
    if len(rows) < frames:
        stray = _first_stray(text, body_start, block)
        if stray is not None and stray[0] < _line_of(text, len(text.rstrip())):
            raise InputError(path, f"line {stray[0]}", f"expected a frame line 'kt TIME fr VALUES', found {stray[1][:40]!r}")
        raise InputError(path, f"line {_line_of(text, len(text.rstrip()))}",
                         f"'frames {frames}' but only {len(rows)} frame lines ('kt TIME fr VALUES') follow (file truncated?)")
    if len(rows) > frames:
        extra = [m for _, m in zip(range(frames + 1), _KEY_LINE.finditer(body))][-1]
        raise InputError(path, f"line {_line_of(text, body_start + extra.start())}",
                         f"more frame lines than 'frames {frames}' announces")
    # The frame block runs to the end of the last key line and must hold nothing else.
    if len(_NONEMPTY_LINE.findall(block)) != frames:
        number, line = _first_stray(text, body_start, block)
        raise InputError(path, f"line {number}", f"expected a frame line 'kt TIME fr VALUES', found {line[:40]!r}")
    times_text, values_text = zip(*rows)
    numbers = " ".join(values_text).split()
    if len(numbers) != frames * width:
        _raise_bad_width(path, text, body_start, block, width)
    try:
        times = np.array(times_text, dtype=np.float64)
        values = np.array(numbers, dtype=np.float64).reshape(frames, width)
    except ValueError:
        _raise_bad_number(path, text, body_start, block)
    if not np.all(np.isfinite(times)):
        frame = int(np.nonzero(~np.isfinite(times))[0][0])
        raise InputError(path, f"frame {frame + 1}", "key time is not finite")
    if not np.all(np.isfinite(values)):
        frame = int(np.nonzero(~np.isfinite(values).all(axis=1))[0][0])
        col = int(np.nonzero(~np.isfinite(values[frame]))[0][0])
        channel = channels[int(np.searchsorted(np.cumsum(sizes), col, side="right"))]
        raise InputError(path, f"frame {frame + 1}", f"channel {channel.joint} {channel.type}: value is not finite ({values[frame, col]})")
    return times, values, body_start + len(block)


def _block_lines(text: str, body_start: int, block: str):
    first = _line_of(text, body_start)
    for i, line in enumerate(block.split("\n")):
        if line.strip():
            yield first + i, line


def _first_stray(text: str, body_start: int, block: str) -> tuple[int, str] | None:
    """The first non-empty line of the frame block that is not a frame line: (line number, text)."""
    for number, line in _block_lines(text, body_start, block):
        if not _KEY_LINE.match(line):
            return number, line.strip()
    return None


def _raise_bad_width(path, text, body_start, block, width):
    frame = 0
    for number, line in _block_lines(text, body_start, block):
        frame += 1
        count = len(_KEY_LINE.match(line).group(2).split())
        if count != width:
            raise InputError(path, f"line {number}", f"frame {frame} has {count} values, the channels need {width}")
    raise InputError(path, None, "frame value count does not match the channels")


def _raise_bad_number(path, text, body_start, block):
    frame = 0
    for number, line in _block_lines(text, body_start, block):
        frame += 1
        m = _KEY_LINE.match(line)
        for tok in [m.group(1)] + m.group(2).split():
            try:
                float(tok)
            except ValueError:
                raise InputError(path, f"line {number}", f"frame {frame}: {tok[:30]!r} is not a number") from None
    raise InputError(path, None, "a frame value is not a number")


def _parse_metadata(path: Path, text: str, start: int) -> tuple[dict, dict]:
    timings: dict[str, float] = {}
    other: dict[str, object] = {}
    first = _line_of(text, start)
    for i, raw in enumerate(text[start:].split("\n")):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        where = f"line {first + i}"
        if line.startswith("kt ") or line == "kt":
            raise InputError(path, where, "a frame line after the frame block (malformed, or more frames than 'frames' announces)")
        m = _TIMING.match(line)
        tagged = _TAGGED.match(line)
        if _TIMING_PREFIX.match(line) and not m:
            raise InputError(path, where, f"expected 'NAME time: SECONDS', found {line[:40]!r}")
        hit = m or tagged
        if hit is None:
            raise InputError(path, where, f"expected metadata 'NAME time: SECONDS' or 'NAME VALUE', found {line[:40]!r}")
        name, value = hit.group(1), hit.group(2)
        try:
            seconds = float(value)
        except ValueError:
            if m:
                raise InputError(path, where, f"{name}: time {value!r} is not a number") from None
            other[name] = value
            continue
        if not np.isfinite(seconds):
            raise InputError(path, where, f"{name}: time is not finite")
        timings[name] = seconds
    return timings, other


def parse_skm(path: Path, text: str) -> SkmFile:
    """Parse ``.skm`` text; malformed input raises :class:`InputError` naming the line, channel or frame."""
    m = _FRAMES_LINE.search(text)
    if m is None:
        if not text.strip():
            raise InputError(path, None, "empty file")
        raise InputError(path, None, "no 'frames N' line (not a SmartBody motion, or truncated)")
    name, channels, start_kt = _parse_header(path, text[: m.start()])
    frames_line = _line_of(text, m.start())
    try:
        frames = int(m.group(1))
    except ValueError:
        raise InputError(path, f"line {frames_line}", f"frame count {m.group(1)!r} is not a whole number") from None
    if frames < 1:
        raise InputError(path, f"line {frames_line}", f"frame count must be at least 1, found {frames}")
    if not channels:
        raise InputError(path, None, "no channels")
    times, values, end = _frame_values(path, text, m.end(), frames, channels)
    timings, other = _parse_metadata(path, text, end)
    units, units_line = declared_units(text[: m.start()], path)
    return SkmFile(path, name, units, units_line, channels, times, values, start_kt, timings, other)
