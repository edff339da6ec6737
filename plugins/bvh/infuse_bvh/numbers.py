"""Whitespace-separated decimal numbers -> float64, parsed with numpy over the raw bytes.

Motion blocks are mostly short decimals (``-149.532``, ``5.1072e-06``). For tokens of the form
``[+-]digits[.digits][(e|E)[+-]digits]`` the digits are gathered per token into an integer
mantissa M and a power of ten P, and the value is ``M * 10**P`` (or ``M / 10**-P``). With
M < 2**53 and |P| <= 22 both factors are exact doubles, so the single multiplication or division
is correctly rounded: the result is bit for bit what ``float(token)`` gives (the classic
fast path of decimal-to-binary conversion). The few tokens outside that range are converted
one by one with ``float``; anything else (``nan``, ``inf``, garbage) sends the whole buffer
through ``np.array(buf.split(), float)``, which raises ``ValueError`` on garbage.
"""
from __future__ import annotations

import numpy as np

_POWERS = 10.0 ** np.arange(23)  # 1 ... 1e22, all exact doubles
_EXACT_MANTISSA = 2.0 ** 53
#: Above this share of tokens needing one-by-one conversion, the plain split path is used.
_SLOW_SHARE = 0.01


def whitespace(b: np.ndarray) -> np.ndarray:
    """Where the bytes ``b`` (uint8) hold ASCII whitespace: the separators of ``bytes.split``."""
    return (b == 32) | ((b >= 9) & (b <= 13))


def token_bounds(b: np.ndarray, space: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) byte offsets of the whitespace-separated tokens of ``b``."""
    solid = ~space
    starts = np.flatnonzero(solid & np.concatenate(([True], space[:-1])))
    ends = np.flatnonzero(solid & np.concatenate((space[1:], [True]))) + 1
    return starts, ends


def _ranges(first: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """The concatenation of ``arange(first[i], stop[i])`` for every i."""
    lengths = stop - first
    total = int(lengths.sum())
    shift = np.repeat(first - (np.cumsum(lengths) - lengths), lengths)
    return shift + np.arange(total)


def _digit_values(d: np.ndarray, positions: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Per group of consecutive digit ``positions`` (``counts`` per group), the integer they spell, as float64."""
    group = np.repeat(np.arange(len(counts)), counts)
    place = np.cumsum(counts)[group] - np.arange(1, len(positions) + 1)  # digits to the right
    if place.size and place.max() > 22:
        place = np.minimum(place, 22)  # such groups exceed 2**53 anyway and are redone one by one
    return np.bincount(group, weights=d[positions] * _POWERS[place], minlength=len(counts))


def _vectorized(buf: bytes, b: np.ndarray, space: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray | None:
    """The values of every token, or None when some token is not a plain decimal."""
    count = len(starts)
    d = b - np.uint8(48)
    digit = d < 10
    dot = b == 46
    minus = b == 45
    sign = minus | (b == 43)
    exp_mark = (b | np.uint8(32)) == 101  # 'e' or 'E'
    if not np.all(digit | dot | sign | exp_mark | space):
        return None
    power = np.zeros(count, dtype=np.int64)
    mantissa_end = ends.copy()
    signs_in_exponents = 0
    marks = np.flatnonzero(exp_mark)
    if marks.size:
        mark_token = np.searchsorted(starts, marks, side="right") - 1
        if np.any(mark_token[1:] == mark_token[:-1]) or np.any(marks == starts[mark_token]):
            return None  # two exponents in a token, or a token starting with 'e'
        region = _ranges(marks + 1, ends[mark_token])  # the bytes after each 'e'
        signed = (marks + 1 < ends[mark_token]) & sign[np.minimum(marks + 1, len(b) - 1)]
        exp_len = ends[mark_token] - marks - 1 - signed
        exp_positions = region[digit[region]]
        if np.any(exp_len <= 0) or exp_positions.size != int(exp_len.sum()) or np.any(dot[region]):
            return None  # 'e' without digits, or something other than digits after it
        signs_in_exponents = int(np.count_nonzero(signed))
        if int(np.count_nonzero(sign[region])) != signs_in_exponents:
            return None
        exponent = _digit_values(d, exp_positions, exp_len)
        exponent[signed & minus[np.minimum(marks + 1, len(b) - 1)]] *= -1.0
        power[mark_token] = np.clip(exponent, -10**6, 10**6).astype(np.int64)
        mantissa_end[mark_token] = marks
        digit = digit.copy()
        digit[exp_positions] = False  # the mantissa is what is left
    leading_sign = sign[starts]
    if int(np.count_nonzero(sign)) - signs_in_exponents != int(np.count_nonzero(leading_sign)):
        return None  # a sign inside a mantissa
    # From here every mantissa is [sign] digits [. digits] with at most one dot, so the digit
    # counts follow from lengths alone.
    dots = np.flatnonzero(dot)
    has_dot = np.zeros(count, dtype=np.int64)
    if dots.size == count and np.all((dots >= starts) & (dots < ends)):
        dot_token = np.arange(count)  # one dot in every token, the common case
    else:
        dot_token = np.searchsorted(starts, dots, side="right") - 1
        if np.any(dot_token[1:] == dot_token[:-1]):
            return None  # two dots in a token
    has_dot[dot_token] = 1
    per_token = mantissa_end - starts - leading_sign - has_dot
    mantissa_positions = np.flatnonzero(digit)
    if np.any(per_token <= 0) or mantissa_positions.size != int(per_token.sum()):
        return None  # "-", ".", "+e5"...
    mantissa = _digit_values(d, mantissa_positions, per_token)
    before_dot = dots - starts[dot_token] - leading_sign[dot_token]
    power[dot_token] -= per_token[dot_token] - before_dot  # digits after the dot
    slow = (mantissa >= _EXACT_MANTISSA) | (np.abs(power) > 22)
    scale = _POWERS[np.minimum(np.abs(power), 22)]
    values = np.where(power < 0, mantissa / scale, mantissa * scale)
    values[leading_sign & minus[starts]] *= -1.0
    if slow.any():
        which = np.flatnonzero(slow)
        if len(which) > _SLOW_SHARE * count + 16:
            return None
        values[which] = [float(buf[starts[i]:ends[i]]) for i in which]
    return values


def parse_floats(buf: bytes, b: np.ndarray | None = None, space: np.ndarray | None = None,
                 bounds: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Every whitespace-separated number in ``buf`` as float64, exactly as ``float`` reads each one.

    ``b`` (the bytes as uint8), ``space`` (:func:`whitespace`) and ``bounds`` (:func:`token_bounds`) may be
    passed when the caller has them. Raises ``ValueError`` if a token is not a number.
    """
    if b is None:
        b = np.frombuffer(buf, dtype=np.uint8)
    if space is None:
        space = whitespace(b)
    starts, ends = token_bounds(b, space) if bounds is None else bounds
    if len(starts) == 0:
        return np.zeros(0)
    values = _vectorized(buf, b, space, starts, ends)
    if values is None:
        values = np.array(buf.split(), dtype=np.float64)
    return values
