"""The part of a recording a command analyses: ``--segment START:END``, in the file's own time [s].

:func:`parse_segment` reads the text; :func:`segment_of_recording` checks it against the recording's span (the
first sample's time to the last one's plus one sampling interval) and :func:`cut_recording` keeps the samples in
it.  A segment that starts before the recording, ends after it or is longer than it is an error naming the
recording's span: a segment is never cut to fit, since a number read over another stretch of a recording than
the one asked for is not the number asked for.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SegmentError", "cut_recording", "parse_segment", "recording_span", "segment_of_recording"]


class SegmentError(ValueError):
    """A segment that is not inside the recording (the message names the recording's span)."""


def parse_segment(text) -> tuple[float, float]:
    """``"START:END"`` [s] -> ``(start, end)``; raises ValueError naming the text."""
    try:
        a, b = (float(v) for v in str(text).split(":"))
    except ValueError:
        raise ValueError(f"segment {text!r}: expected START:END in seconds, e.g. 2.5:14") from None
    if not (math.isfinite(a) and math.isfinite(b) and 0 <= a < b):
        raise ValueError(f"segment {text!r}: expected 0 <= START < END [s]")
    return a, b


def recording_span(recording) -> tuple[float, float]:
    """``(first, end)`` [s] of a recording in its own time: the first sample's time, and the last one's plus the
    median sampling interval (a 40 s record at 200 Hz spans 0-40 s)."""
    t = np.asarray(recording["time"].values, dtype=float)
    t = t[np.isfinite(t)]
    if not t.size:
        raise SegmentError(f"{_name(recording)}: the recording has no sample times")
    step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    return float(t[0]), float(t[-1]) + max(step, 0.0)


def segment_of_recording(recording, segment) -> tuple[float, float] | None:
    """``segment`` (``(start, end)`` [s] or ``"START:END"``) checked against the recording's span; None stays None.

    Raises
    ------
    SegmentError
        The segment starts before the recording or ends after it (the message names the span).
    ValueError
        The text is not ``START:END``.
    """
    if segment is None:
        return None
    a, b = parse_segment(segment) if isinstance(segment, str) else (float(segment[0]), float(segment[1]))
    if not (math.isfinite(a) and math.isfinite(b) and a < b):
        raise ValueError(f"segment {a:g}:{b:g} s: expected START < END [s]")
    first, end = recording_span(recording)
    tol = 1e-9 * max(1.0, abs(first), abs(end))
    if a < first - tol or b > end + tol:
        raise SegmentError(
            f"segment {a:g}:{b:g} s is not inside {_name(recording)}, which spans {first:.6g}-{end:.6g} s in its "
            "own time: give a --segment START:END within it"
        )
    return a, b


def cut_recording(recording, segment):
    """The recording's samples with ``start <= time < end`` (its time, attributes and channels as read), and a
    line in its history; the recording itself when ``segment`` is None.  Raises as :func:`segment_of_recording`,
    and a :class:`SegmentError` for a segment that holds fewer than two samples."""
    seg = segment_of_recording(recording, segment)
    if seg is None:
        return recording
    a, b = seg
    t = np.asarray(recording["time"].values, dtype=float)
    keep = np.flatnonzero((t >= a) & (t < b))
    if keep.size < 2:
        raise SegmentError(
            f"segment {a:g}:{b:g} s of {_name(recording)} holds {keep.size} sample(s); give a longer one"
        )
    out = recording.isel(time=keep)
    out.attrs = dict(recording.attrs)
    out.attrs["segment_s"] = f"{a:g}:{b:g}"
    out.attrs["history"] = (
        str(recording.attrs.get("history", "")) + f"segment {a:g}:{b:g} s kept ({keep.size} samples)\n"
    )
    return out


def _name(recording) -> str:
    return str(getattr(recording, "attrs", {}).get("source_file", "") or "the recording")
