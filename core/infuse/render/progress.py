"""A progress bar on stderr for long renders: frames done, rate and time left."""
from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Reports ``done/total`` frames, frames per second and an ETA.

    ``enabled=None`` shows it only when ``stream`` is a terminal. On a terminal the line is
    redrawn in place; elsewhere (a log file) a line is written at most once a second.
    """

    def __init__(self, total: int, label: str = "render", enabled: bool | None = None, stream: TextIO | None = None):
        self.total = max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = self.tty if enabled is None else bool(enabled)
        self.done = 0
        self.start = time.monotonic()
        self._last = float("-inf")

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def line(self) -> str:
        """The current report, e.g. ``render  45/120 frames [#####.....] 38%  22.1 fps  ETA 3s``."""
        elapsed = time.monotonic() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        width = 20
        filled = int(width * self.done / self.total)
        bar = "#" * filled + "." * (width - filled)
        eta_text = "--" if eta != eta else _seconds(eta)
        return (f"{self.label} {self.done:>{len(str(self.total))}}/{self.total} frames [{bar}] "
                f"{100 * self.done // self.total:3d}%  {rate:5.1f} fps  ETA {eta_text}")

    def advance(self, n: int = 1) -> None:
        self.done = min(self.done + n, self.total)
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last >= (0.1 if self.tty else 1.0) or self.done == self.total:
            self._last = now
            self.stream.write(("\r" + self.line() + "\x1b[K") if self.tty else self.line() + "\n")
            self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()


def _seconds(s: float) -> str:
    s = int(round(s))
    return f"{s // 60}m{s % 60:02d}s" if s >= 60 else f"{s}s"
