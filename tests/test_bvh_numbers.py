"""The BVH plugin's vectorized number parser reads every token exactly as Python's float does."""
from __future__ import annotations

import numpy as np
import pytest

from infuse_bvh.numbers import _vectorized, parse_floats, token_bounds, whitespace

rng = np.random.default_rng(5)


def _random_tokens(n: int, kinds=(0, 1, 3, 4, 5)) -> list[str]:
    tokens = []
    for _ in range(n):
        kind = rng.choice(kinds)
        value = rng.normal() * 10.0 ** rng.integers(-8, 9)
        if kind == 0:
            tokens.append(f"{value:.6f}")
        elif kind == 1:
            tokens.append(f"{value:.{rng.integers(1, 12)}g}")  # exponents of every size
        elif kind == 2:
            tokens.append(f"{value:.17e}".replace("e", "E"))  # more digits than a double holds exactly
        elif kind == 3:
            tokens.append(str(int(value)))
        elif kind == 4:
            tokens.append(f"+{abs(value):.3f}" if rng.integers(2) else f"-{abs(value):.3f}")
        elif kind == 5:
            tokens.append(rng.choice(["-0", "0", ".5", "5.", "-.25", "007.50", "1e5", "1E+05", "2e-0", "3e22", "-4.5E-12"]))
        else:
            tokens.append(repr(float(value)))  # shortest round-trip form, often 17 digits
    return tokens


def _bits(a: np.ndarray) -> np.ndarray:
    return np.asarray(a, dtype=np.float64).view(np.int64)


def _vectorized_only(text: bytes):
    b = np.frombuffer(text, dtype=np.uint8)
    space = whitespace(b)
    starts, ends = token_bounds(b, space)
    return _vectorized(text, b, space, starts, ends)


@pytest.mark.parametrize("separator", [" ", "\t", "\r\n", "  \n\t "])
def test_values_are_bit_identical_to_float(separator):
    tokens = _random_tokens(5000)
    tokens[::700] = _random_tokens(len(tokens[::700]), kinds=(2,))  # a few need one-by-one conversion
    text = ("\n" + separator.join(tokens) + separator).encode()
    expected = np.array([float(t) for t in tokens])
    fast = _vectorized_only(text)
    assert fast is not None  # the vectorized path handled it
    assert np.array_equal(_bits(fast), _bits(expected))
    assert np.array_equal(_bits(parse_floats(text)), _bits(expected))


def test_many_long_mantissas_fall_back_and_stay_exact():
    tokens = _random_tokens(2000, kinds=(2, 6))
    text = " ".join(tokens).encode()
    assert _vectorized_only(text) is None
    assert np.array_equal(_bits(parse_floats(text)), _bits(np.array([float(t) for t in tokens])))


def test_signs_of_zero_and_edge_forms():
    text = b"-0 0 -0.0 +0 .5 5. -.5 1e0 1E-0 0000.0001 -1.5e-07 123456789012345678 1.5e-300 9007199254740993"
    expected = np.array([float(t) for t in text.split()])
    assert np.array_equal(_bits(_vectorized_only(text)), _bits(expected))


@pytest.mark.parametrize("bad", [b"1 2-3", b"1 .", b"1 1.2.3", b"1 --2", b"1e", b"1e-", b"-e5", b"1e5e5",
                                 b"1.5e3.2", b"1 abc", b"0x10", b"1,5", b"1\x01 2", b"+", b"e"])
def test_garbage_raises_value_error(bad):
    assert _vectorized_only(bad) is None
    with pytest.raises(ValueError):
        parse_floats(bad)


def test_special_values_take_the_general_path():
    values = parse_floats(b"1 nan -inf 2")
    assert np.isnan(values[1]) and values[2] == -np.inf and values[3] == 2.0
    assert parse_floats(b"   \n ").size == 0
