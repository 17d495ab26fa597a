"""A minimal progress bar: drawn on a terminal (stderr), silent when piped or when disabled."""

from __future__ import annotations

import os
import sys
import time

__all__ = ["Progress"]


class Progress:
    """Progress of ``total`` units of work, redrawn at most 10 times a second on stderr's terminal."""

    def __init__(self, total: float, label: str, *, enabled: bool = True, stream=None):
        self.stream = stream or sys.stderr
        self.total = float(total) if total else 1.0
        self.label = label
        self.enabled = bool(enabled) and hasattr(self.stream, "isatty") and self.stream.isatty() \
            and os.environ.get("TERM", "") != "dumb"
        self._last = 0.0
        self._t0 = time.perf_counter()

    def update(self, done: float) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < 0.1 and done < self.total:
            return
        self._last = now
        frac = min(max(done / self.total, 0.0), 1.0)
        width = 30
        fill = int(round(frac * width))
        self.stream.write(f"\r{self.label} [{'#' * fill}{'.' * (width - fill)}] {100 * frac:5.1f}% "
                          f"{now - self._t0:6.1f} s")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.update(self.total)
            self.stream.write("\n")
            self.stream.flush()
