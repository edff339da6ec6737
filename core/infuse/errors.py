"""Typed errors. Each one names the input, the place in it and the problem.

The CLI turns them into one line on stderr and an exit code:
0 ok; 2 bad input or usage (:class:`InputError`, :class:`UsageError`); 3 the input is valid but
cannot be used for what was asked (:class:`UnusableInputError` and subclasses such as
:class:`NotHumanoidError`, or a feature whose optional extra is not installed); 1 is a bug.
"""
from __future__ import annotations

import json
import re
import struct
import zlib
from pathlib import Path

#: Exceptions that, raised while parsing, mean the file is malformed rather than a bug in infuse.
PARSE_ERRORS = (ValueError, IndexError, KeyError, TypeError, AttributeError, UnicodeDecodeError, struct.error,
                json.JSONDecodeError, zlib.error, EOFError, OverflowError)

_LINE_BREAKS = re.compile(r"\s*[\r\n]+\s*")


def one_line(text: str) -> str:
    """``text`` with its line breaks (e.g. a parser's message quoting the file) made single spaces."""
    return _LINE_BREAKS.sub(" ", text).strip()


class InfuseError(Exception):
    """Base of every error infuse raises on purpose."""

    exit_code = 1


class InputError(InfuseError):
    """A file or value is malformed: names the file, the place (line, node, field) and the problem."""

    exit_code = 2

    def __init__(self, file: str | Path | None, place: str | None, problem: str):
        self.file = str(file) if file is not None else None
        self.place = one_line(place) if place else place
        self.problem = one_line(problem)
        where = ":".join(p for p in (self.file, self.place) if p)
        super().__init__(f"{where}: {self.problem}" if where else self.problem)

    def naming(self, file: str | Path) -> "InputError":
        """This error, of the same type, naming ``file`` (for errors raised by checks that do not know
        the file, such as the core model's)."""
        named = type(self).__new__(type(self))
        named.__dict__.update(self.__dict__)
        InputError.__init__(named, file, self.place, self.problem)
        return named


class UsageError(InfuseError):
    """A command or API call was given arguments that do not fit together."""

    exit_code = 2


class UnusableInputError(InfuseError):
    """The input is well formed but cannot be used for the requested operation."""

    exit_code = 3

    def __init__(self, file: str | Path | None, problem: str):
        self.file = str(file) if file is not None else None
        self.problem = one_line(problem)
        super().__init__(f"{self.file}: {self.problem}" if self.file else self.problem)


class UnsupportedFormatError(UnusableInputError):
    """No installed reader or writer handles this file type."""


class MissingFeatureError(UnusableInputError):
    """An optional extra or system package is needed; the message says how to install it."""


class MissingJointsError(UnusableInputError):
    """A character lacks joints that a behaviour pack or controller drives; the message names them."""


class NotHumanoidError(UnusableInputError):
    """A skeleton is not a humanoid; ``reason`` says why."""

    def __init__(self, file: str | Path | None, reason: str):
        self.reason = reason
        super().__init__(file, f"not a humanoid: {reason}")


class BusyError(InfuseError):
    """A live service has too much waiting (its command queue is full); the request may be sent again later."""

    exit_code = 2


def _amount(value) -> str:
    return f"{value:,}" if isinstance(value, int) else f"{value:.6g}"


class LimitError(InputError):
    """A file asks for more than infuse allows (a count, size, nesting depth or duration); checked before
    anything is allocated or run. ``limit`` names the bound in :mod:`infuse.limits`."""

    def __init__(self, file: str | Path | None, place: str | None, what: str, asked, limit: str, bound):
        self.limit = limit
        super().__init__(file, place, f"{what} {_amount(asked)} is over the limit of {_amount(bound)} (infuse.limits.{limit})")


class ExternalReferenceError(InputError):
    """A file refers to another file outside its own folder (an absolute path, a ``..`` escape, a link
    out of the folder) or to something that is not a regular file; see :mod:`infuse.references`."""
