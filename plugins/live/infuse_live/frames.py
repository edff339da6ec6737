"""A live frame as a message: JSON text (:func:`frame_text`) or one binary message (:func:`binary_frame`).

The JSON numbers are written by :func:`decimal_texts`, vectorized over every number of a frame, instead of
one ``float.__repr__`` call per number in :func:`json.dumps` (ten characters: 0.1 ms a frame instead of 1.5).
"""
from __future__ import annotations

import json
import struct
from functools import lru_cache

import numpy as np

from infuse.live import LiveFrame

from .protocol import dumps

#: Decimals sent for rotations (quaternion components) and positions (metres) in the pose stream.
ROTATION_DECIMALS, POSITION_DECIMALS, MORPH_DECIMALS = 6, 6, 4
#: Largest magnitude written by :func:`decimal_texts` itself (larger ones, and non-finite ones, by json.dumps).
_LARGEST = 1e12
#: The three ASCII digits of 0..999 (1000,) as 3-byte items, and how many of them are trailing zeros.
_TRIPLES = np.array([f"{i:03d}".encode() for i in range(1000)], dtype="S3").view("V3")
_TRAILING = np.array([3 if i == 0 else len(f"{i:03d}") - len(f"{i:03d}".rstrip("0")) for i in range(1000)])


@lru_cache(maxsize=8)
def _layout(groups: int) -> tuple[np.dtype, np.ndarray]:
    """A number's text for ``groups`` three-digit groups of integer digits: the record of its columns
    (sign, integer digits, point, six decimals, comma), and which columns a number keeps, for each (sign,
    integer digits 1..3*groups, decimals 1..6) as row ``sign + 2 * (digits - 1 + 3 * groups * (decimals - 1))``,
    one (W,)-byte item each."""
    width = 3 * groups
    record = np.dtype([("sign", "u1"), *((f"integer{g}", "V3") for g in range(groups)), ("point", "u1"),
                       ("high", "V3"), ("low", "V3"), ("comma", "u1")])
    rows = [[bool(sign), *(j >= width - digits for j in range(width)), True, *(i < decimals for i in range(6)), True]
            for decimals in range(1, 7) for digits in range(1, width + 1) for sign in (0, 1)]
    return record, np.array(rows, dtype=bool).view(f"V{width + 9}").ravel()


def decimal_texts(parts: list[np.ndarray], decimals: list[int]) -> list[str]:
    """Each array of ``parts`` (any shape, flattened) rounded to its ``decimals`` (0 to 6), as JSON array
    text: the numbers ``json.dumps`` writes for the rounded values (``np.round``), parsing to the same
    floats, in fixed-point notation (``json.dumps`` writes below 1e-4 in exponent form). Shortest digits,
    at least one after the point (``1.0``, ``-0.0``, ``0.25``)."""
    sizes = [int(np.size(p)) for p in parts]
    if not sum(sizes):
        return ["[]"] * len(parts)
    values = np.concatenate([np.asarray(p, dtype=np.float64).ravel() for p in parts])
    scale = np.repeat(10.0 ** np.asarray(decimals, dtype=np.float64), sizes)
    if not np.all(np.abs(values) < _LARGEST):  # non-finite or huge: json.dumps as it always does
        return [json.dumps(np.round(np.asarray(p, dtype=np.float64).ravel(), d).tolist(), separators=(",", ":"))
                for p, d in zip(parts, decimals)]
    # |value| rounded to d decimals, times 10^6, as an integer: np.round's rint(value * 10^d) (divided by
    # 10^d, the same float the text parses to) with 6 - d zeros after it
    whole = np.rint(np.abs(values) * scale).astype(np.int64) * (1_000_000 // scale.astype(np.int64))
    integer, fraction = np.divmod(whole, 1_000_000)
    high, low = np.divmod(fraction, 1000)
    groups = -(-len(str(int(integer.max()))) // 3)
    record, patterns = _layout(groups)
    text = np.empty(len(values), dtype=record)
    text["sign"] = ord("-")
    rest = integer
    for g in range(groups - 1, -1, -1):
        rest, triple = np.divmod(rest, 1000)
        text[f"integer{g}"] = _TRIPLES.take(triple)
    text["point"] = ord(".")
    text["high"] = _TRIPLES.take(high)
    text["low"] = _TRIPLES.take(low)
    text["comma"] = ord(",")
    sign = np.signbit(values)
    digits = 1 + np.searchsorted(10 ** np.arange(1, 3 * groups, dtype=np.int64), integer, side="right")
    kept = np.maximum(6 - np.where(low == 0, 3 + _TRAILING[high], _TRAILING[low]), 1)
    keep = patterns.take(sign + 2 * (digits - 1 + 3 * groups * (kept - 1))).view(bool)
    joined = text.view(np.uint8)[keep].tobytes().decode("ascii")
    bounds = np.concatenate([[0], np.cumsum(sign + digits + kept + 2)])[np.cumsum([0, *sizes])]
    return ["[" + joined[start:end - 1] + "]" if end > start else "[]" for start, end in zip(bounds[:-1], bounds[1:])]


def frame_text(frame: LiveFrame) -> str:
    """A ``frame`` message as JSON text: per character ``rotations`` (J*4, scalar-last, flat), ``root``
    (3,) metres and ``morphs`` (M,), and ``translations`` (J*3, local, metres, flat) for a character that
    has them (:attr:`~infuse.live.CharacterFrame.translations`), rounded (:data:`ROTATION_DECIMALS`...)."""
    characters = list(frame.characters.items())
    parts, decimals = [], []
    for _, c in characters:
        parts += [c.rotations, c.root, c.morphs]
        decimals += [ROTATION_DECIMALS, POSITION_DECIMALS, MORPH_DECIMALS]
        if c.translations is not None:
            parts.append(c.translations)
            decimals.append(POSITION_DECIMALS)
    texts = iter(decimal_texts(parts, decimals))
    poses = []
    for name, c in characters:
        pose = f'{dumps(name)}:{{"rotations":{next(texts)},"root":{next(texts)},"morphs":{next(texts)}'
        poses.append(pose + ("}" if c.translations is None else f',"translations":{next(texts)}}}'))
    return f'{{"type":"frame","frame":{int(frame.index)},"time":{dumps(frame.time_s)},"characters":{{{",".join(poses)}}}}}'


def binary_frame(frame: LiveFrame) -> bytes:
    """A frame as one binary message: a little-endian uint32 N, N bytes of JSON ``{"frame", "time",
    "characters": [[name, J, M], ...]}``, then for each character in that order float32 (little-endian)
    ``rotations`` (J*4), ``root`` (3) and ``morphs`` (M), unrounded. A character with local joint
    translations has ``[name, J, M, true]`` and its ``translations`` (J*3) after its morphs."""
    layout = [[name, len(c.rotations), len(c.morphs)] + ([] if c.translations is None else [True])
              for name, c in frame.characters.items()]
    header = dumps({"frame": frame.index, "time": frame.time_s, "characters": layout}).encode("utf-8")
    values = [part for c in frame.characters.values()
              for part in (c.rotations.ravel(), c.root, c.morphs, *(() if c.translations is None else (c.translations.ravel(),)))]
    body = np.concatenate(values).astype("<f4").tobytes() if values else b""
    return struct.pack("<I", len(header)) + header + body
