"""A progress bar on stderr: the share and number of items done, the time left and elapsed, items
and clip-frames per second.

On a terminal it redraws one line (at most ten times a second); elsewhere (a log file, CI) it
prints a line every :data:`LOG_EVERY` seconds and a last one at the end.
"""
from __future__ import annotations

import shutil
import sys
import time

#: Seconds between lines when stderr is not a terminal.
LOG_EVERY = 10.0
WIDTH = 20


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    return f"{h}:{rest // 60:02d}:{rest % 60:02d}" if h else f"{rest // 60}:{rest % 60:02d}"


class Progress:
    """``update(items, frames)`` after each finished unit; ``close()`` at the end. ``total``
    counts (character, input) items; the rate is items per second over the whole run so far."""

    def __init__(self, total: int, stream=None, enabled: bool = True, label: str = "batch"):
        self.total, self.label = total, label
        self.stream = stream or sys.stderr
        self.enabled = enabled and total > 0
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.items = self.frames = 0
        self.start = time.perf_counter()
        self._last = -1e9

    def line(self) -> str:
        elapsed = max(time.perf_counter() - self.start, 1e-9)
        share = self.items / self.total if self.total else 1.0
        filled = int(WIDTH * share)
        rate = self.items / elapsed
        eta = (self.total - self.items) / rate if rate > 0 else float("nan")
        left = _clock(eta) if eta == eta else "?"
        return (f"{self.label} {100 * share:3.0f}% [{'#' * filled}{'.' * (WIDTH - filled)}] {self.items}/{self.total} "
                f"left {left} elapsed {_clock(elapsed)} {rate:.1f} items/s {self.frames / elapsed:,.0f} clip-frames/s")

    def update(self, items: int, frames: int) -> None:
        self.items += items
        self.frames += frames
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < (0.1 if self.tty else LOG_EVERY) and self.items < self.total:
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
