"""A progress line on stderr for long work (renders, scene realization, batches).

It reads ``label  45% [#########...........] 54/120 left 0:03 elapsed 0:02 22.1 frames/s``: the
share done, a bar, the count, the time left and elapsed, and the rate of units per second over the
whole run (plus the rate of any other quantity counted alongside, e.g. clip-frames). On a terminal
it redraws one line, cut to the terminal's width, at most ten times a second; elsewhere (a log
file, CI) it prints a line every :data:`LOG_EVERY` seconds and a last one when the work is done.
"""
from __future__ import annotations

import shutil
import sys
import time
from typing import Sequence, TextIO

#: Seconds between lines when the stream is not a terminal.
LOG_EVERY = 10.0
#: Seconds between redraws on a terminal.
REDRAW_EVERY = 0.1
WIDTH = 20


def clock(seconds: float) -> str:
    """``m:ss``, or ``h:mm:ss`` from an hour on."""
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    return f"{h}:{rest // 60:02d}:{rest % 60:02d}" if h else f"{rest // 60}:{rest % 60:02d}"


class Progress:
    """``advance(n, *also)`` after each finished piece of work; ``close()`` (or a ``with`` block) at the end.

    - ``total``: units to do; ``label``: what is being done; ``unit``: the units' name.
    - ``enabled``: ``None`` shows the line only when ``stream`` (default stderr) is a terminal.
    - ``also``: names of other quantities counted alongside (``advance(n, 300)`` adds 300 to the
      first), each shown as a rate, e.g. ``("clip-frames",)``.
    """

    def __init__(self, total: int, label: str = "", enabled: bool | None = None, stream: TextIO | None = None, *,
                 unit: str = "frames", also: Sequence[str] = (), log_every: float = LOG_EVERY):
        self.total = max(int(total), 0)
        self.label, self.unit, self.also = label, unit, tuple(also)
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = (self.tty if enabled is None else bool(enabled)) and self.total > 0
        self.log_every = log_every
        self.done = 0
        self.counts = [0.0] * len(self.also)
        self.start = time.perf_counter()
        self._last = float("-inf")

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def line(self) -> str:
        elapsed = max(time.perf_counter() - self.start, 1e-9)
        share = self.done / self.total if self.total else 1.0
        filled = int(WIDTH * share)
        rate = self.done / elapsed
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        left = clock(eta) if eta == eta else "?"
        text = (f"{self.label} {100 * share:3.0f}% [{'#' * filled}{'.' * (WIDTH - filled)}] {self.done}/{self.total} "
                f"left {left} elapsed {clock(elapsed)} {rate:.1f} {self.unit}/s")
        return text + "".join(f" {count / elapsed:,.0f} {name}/s" for name, count in zip(self.also, self.counts))

    def advance(self, n: int = 1, *also: float) -> None:
        self.done = min(self.done + int(n), self.total)
        for k, value in enumerate(also):
            self.counts[k] += value
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < (REDRAW_EVERY if self.tty else self.log_every) and self.done < self.total:
            return
        self._last = now
        if self.tty:  # one line that fits, or redrawing it would scroll
            self.stream.write("\r" + self.line()[: shutil.get_terminal_size().columns - 1] + "\x1b[K")
        else:
            self.stream.write(self.line() + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
