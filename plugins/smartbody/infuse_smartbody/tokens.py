"""A token stream over SmartBody text (``#`` comments, ``"strings"``, braces, words and numbers).

Every token keeps its line number so errors can say where they are.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from infuse.errors import InputError

# Order matters: a comment or string wins over a word; a lone quote is an unterminated string.
_TOKEN = re.compile(r'(#[^\n]*)|("[^"\n]*")|([{}])|([^\s{}"#]+)|(")|(\n)')


@dataclass(frozen=True)
class Token:
    text: str
    line: int
    quoted: bool = False


def tokenize(text: str, file: Path | str) -> list[Token]:
    """Split ``text`` into tokens with 1-based line numbers; comments are dropped."""
    tokens: list[Token] = []
    line = 1
    for m in _TOKEN.finditer(text):
        comment, string, brace, word, lone_quote, newline = m.groups()
        if newline:
            line += 1
        elif string:
            tokens.append(Token(string[1:-1], line, True))
        elif brace or word:
            tokens.append(Token(brace or word, line))
        elif lone_quote:
            raise InputError(file, f"line {line}", "unterminated string (a quote without its closing quote)")
    return tokens


class TokenStream:
    """Sequential access to tokens with typed reads that raise :class:`InputError` naming the line."""

    def __init__(self, tokens: list[Token], file: Path | str):
        self.tokens = tokens
        self.file = file
        self.pos = 0

    @property
    def finished(self) -> bool:
        return self.pos >= len(self.tokens)

    @property
    def line(self) -> int:
        """Line of the next token (or of the last one at the end)."""
        if not self.tokens:
            return 1
        return self.tokens[min(self.pos, len(self.tokens) - 1)].line

    def error(self, problem: str, line: int | None = None) -> InputError:
        return InputError(self.file, f"line {self.line if line is None else line}", problem)

    def peek(self) -> Token | None:
        return None if self.finished else self.tokens[self.pos]

    def upcoming(self) -> str | None:
        """The next token's text (not taken), or None at the end."""
        tok = self.peek()
        return None if tok is None else tok.text

    def next(self, what: str) -> Token:
        if self.finished:
            raise self.error(f"unexpected end of file, expected {what}")
        tok = self.tokens[self.pos]
        self.pos += 1
        return tok

    def word(self, what: str) -> str:
        return self.next(what).text

    def expect(self, keyword: str) -> None:
        tok = self.next(f"{keyword!r}")
        if tok.text != keyword:
            raise self.error(f"expected {keyword!r}, found {tok.text!r}", tok.line)

    def number(self, what: str) -> float:
        tok = self.next(what)
        try:
            value = float(tok.text)
        except ValueError:
            raise self.error(f"expected a number for {what}, found {tok.text!r}", tok.line) from None
        if not math.isfinite(value):
            raise self.error(f"{what} is not finite ({tok.text})", tok.line)
        return value

    def numbers(self, count: int, what: str) -> list[float]:
        return [self.number(what) for _ in range(count)]

    def integer(self, what: str) -> int:
        tok = self.next(what)
        try:
            value = int(tok.text)
        except ValueError:
            raise self.error(f"expected a whole number for {what}, found {tok.text!r}", tok.line) from None
        if value < 0:
            raise self.error(f"{what} must not be negative, found {value}", tok.line)
        return value
