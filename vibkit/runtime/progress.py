"""Progress on stderr: a bar on a terminal; when stderr is not a terminal (a log, cron, a service),
one line every few seconds once the work has lasted that long, so short runs stay quiet and long
ones are never silent.
"""

from __future__ import annotations

import os
import sys
import time

__all__ = ["Progress", "LINE_INTERVAL_S"]

#: seconds between progress lines when stderr is not a terminal (``VIBKIT_PROGRESS_INTERVAL`` overrides)
LINE_INTERVAL_S = 5.0


def _interval() -> float:
    try:
        v = float(os.environ.get("VIBKIT_PROGRESS_INTERVAL", LINE_INTERVAL_S))
    except ValueError:
        return LINE_INTERVAL_S
    return v if v > 0 else LINE_INTERVAL_S


class Progress:
    """Progress of ``total`` units of work on stderr.

    On a terminal: a bar redrawn at most 10 times a second.  Otherwise (``enabled`` and stderr not a
    terminal): a line ``label: 42.0 % after 10 s`` every :data:`LINE_INTERVAL_S` seconds, the first
    one after that long.  Nothing at all when ``enabled`` is false.
    """

    def __init__(self, total: float, label: str, *, enabled: bool = True, stream=None, note: str = ""):
        self.stream = stream or sys.stderr
        self.total = float(total) if total else 1.0
        self.label = label
        tty = hasattr(self.stream, "isatty") and self.stream.isatty() and os.environ.get("TERM", "") != "dumb"
        self.enabled = bool(enabled) and tty
        self.lines = bool(enabled) and not tty
        self.interval = _interval()
        self._last = 0.0
        self._t0 = time.perf_counter()
        self._next_line = self._t0 + self.interval
        self._lines_written = 0
        # a note on what the first moments hold (compiling kernels): on a terminal at once, in a log with the
        # first line
        self.note = note
        if self.enabled and note:
            self._write(f"{label}: {note}\n")

    def update(self, done: float) -> None:
        if self.lines:
            now = time.perf_counter()
            if now >= self._next_line:
                frac = min(max(done / self.total, 0.0), 1.0)
                self._next_line = now + self.interval
                self._lines_written += 1
                note = f" ({self.note})" if self.note and self._lines_written == 1 else ""
                if not self._write(f"{self.label}: {100 * frac:.1f} % after {now - self._t0:.0f} s{note}\n"):
                    self.lines = False
            return
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < 0.1 and done < self.total:
            return
        self._last = now
        frac = min(max(done / self.total, 0.0), 1.0)
        width = 30
        fill = int(round(frac * width))
        self.stream.write(
            f"\r{self.label} [{'#' * fill}{'.' * (width - fill)}] {100 * frac:5.1f}% {now - self._t0:6.1f} s"
        )
        self.stream.flush()

    def _write(self, text) -> bool:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # a closed or broken stderr must not stop the work
            return False
        return True

    def close(self) -> None:
        if self.lines:
            if self._lines_written:
                try:
                    self.stream.write(f"{self.label}: done after {time.perf_counter() - self._t0:.0f} s\n")
                    self.stream.flush()
                except (OSError, ValueError):
                    pass
            self.lines = False
            return
        if self.enabled:
            self.update(self.total)
            self.stream.write("\n")
            self.stream.flush()
            self.enabled = False
