"""Time stamps as found: order, gaps (bursts), jitter, and the resampling policy.

A recording's time stamps are checked, never silently changed:

* time going backwards and repeated stamps are errors (with the file line)
  unless the caller asks for a repair (sort, drop repeats), which is recorded;
* a step longer than ``gap_factor`` median periods starts a new segment
  (a burst); segments are numbered, never bridged;
* the jitter of the steps inside segments is measured and reported;
* samples are resampled only when asked (``resample="linear"``), per segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError

__all__ = ["TimeDiagnosis", "check_order", "diagnose", "resample_linear", "held_update_rate", "quantum"]


@dataclass(frozen=True)
class TimeDiagnosis:
    """What the time stamps of a recording look like.

    Attributes
    ----------
    period_s : float
        Mean step between samples inside segments (their total duration over
        their number of steps). [s]
    jitter_rms : float
        RMS deviation of the steps inside segments from ``period_s``, as a
        fraction of ``period_s``. [1]
    jitter_max : float
        Largest such deviation, as a fraction of ``period_s``. [1]
    segment : numpy.ndarray
        int32 burst number of each sample (0, 1, 2 ...).
    gaps_s : numpy.ndarray
        Length of each gap between segments. [s]
    """

    period_s: float
    jitter_rms: float
    jitter_max: float
    segment: np.ndarray
    gaps_s: np.ndarray

    @property
    def n_segments(self) -> int:
        return int(self.segment[-1]) + 1 if self.segment.size else 0


def check_order(t, lines, *, path, column, repair):
    """Refuse (or, if asked, repair) time going backwards and repeated stamps.

    Parameters
    ----------
    t : numpy.ndarray
        Time of each sample. [s]
    lines : numpy.ndarray or None
        File line of each sample (for messages), or None.
    path : str
        File name for messages.
    column : str
        Time column name for messages.
    repair : bool
        False: raise :class:`RecordingError` at the first offending line.
        True: first undo clock jumps (time-of-day stamps going back by 24 h at
        midnight, local time going back by 1 h at a daylight-saving change:
        a backward step within ``max(2 s, 10 periods)`` of -24 h or -1 h adds
        that much to the samples after it, keeping their order); then sort by
        time (stable) and keep the first of repeated stamps.

    Returns
    -------
    keep : numpy.ndarray
        Indices of the samples to keep, in time order.
    notes : list of str
        Decisions taken, for the history.
    t : numpy.ndarray
        The times, with clock jumps undone when repairing (index them with
        ``keep``). [s]

    Raises
    ------
    RecordingError
        Time not finite, going backwards or repeated (``repair=False``).
    """
    t = np.asarray(t, dtype=float)
    n = t.size
    line_of = (lambda i: None) if lines is None else (lambda i: int(lines[i]))
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        i = bad[0]
        raise RecordingError(path, line_of(i), f"time in column '{column}' is not a finite number")
    back, dup = _backward_and_repeated(t)
    if not back.size and dup.size == 1 and dup[0] == 0 and n > 2:
        # one repeated stamp on the first two rows: phyphox writes its first sample twice at t = 0
        return (
            np.arange(1, n),
            [
                f"the first two rows share the time stamp {t[0]:.9g} s in column '{column}' "
                "(a known phyphox artefact at the start); the first row"
                + ("" if lines is None else f" (line {line_of(0)})")
                + " dropped"
            ],
            t,
        )
    if not repair:
        if back.size and (not dup.size or back[0] < dup[0]):
            i = back[0] + 1
            jump = _clock_jump(np.diff(t), back[0])
            hint = "" if jump is None else f"; a clock {jump[1]}?"
            raise RecordingError(
                path,
                line_of(i),
                f"time goes backwards in column '{column}': {t[i]:.9g} s after {t[i - 1]:.9g} s "
                f"(expected increasing time{hint}; pass {spell('repair_time', True)} to repair)",
            )
        if dup.size:
            i = dup[0] + 1
            raise RecordingError(
                path,
                line_of(i),
                f"time stamp {t[i]:.9g} s in column '{column}' repeats the previous row "
                f"(expected increasing time; pass {spell('repair_time', True)} to drop repeats)",
            )
        return np.arange(n), [], t
    notes = []
    dt = np.diff(t)
    if back.size:
        t = t.copy()
        for i in back:
            jump = _clock_jump(np.diff(t[i : i + 2]), 0, reference=dt)
            if jump is not None:
                t[i + 1 :] += jump[0]
                notes.append(
                    f"time repaired: the clock went back by {jump[0]:g} s at line {line_of(i + 1)} "
                    f"({jump[1]}); {jump[0]:g} s added to the rest, order kept"
                )
        dt = np.diff(t)
        back = np.flatnonzero(dt < 0)
        if not back.size and not np.any(dt == 0):
            return np.arange(n), notes, t
    order = np.argsort(t, kind="stable")
    if back.size:
        notes.append(f"time repaired: {back.size} backward step(s) in column '{column}', rows sorted by time")
    ts = t[order]
    first = np.r_[True, np.diff(ts) > 0]
    if not first.all():
        notes.append(f"time repaired: {int((~first).sum())} repeated stamp(s) dropped, first kept")
    return order[first], notes, t


#: samples whose steps are worked out at a time by the checks of long records (bounded temporaries)
_BLOCK = 1 << 20


def _backward_and_repeated(t):
    """(indices i of the steps t[i+1] - t[i] < 0, of those == 0), step by step in blocks of :data:`_BLOCK`."""
    back, dup = [], []
    for i in range(0, max(t.size - 1, 0), _BLOCK):
        dt = np.diff(t[i : i + _BLOCK + 1])
        back.append(np.flatnonzero(dt < 0) + i)
        dup.append(np.flatnonzero(dt == 0) + i)
    if not back:
        return np.empty(0, dtype=np.intp), np.empty(0, dtype=np.intp)
    return np.concatenate(back), np.concatenate(dup)


def _count_changes(v):
    """How many steps v[i+1] != v[i] (NaN != NaN counts), in blocks of :data:`_BLOCK`."""
    return sum(int(np.count_nonzero(np.diff(v[i : i + _BLOCK + 1]))) for i in range(0, max(v.size - 1, 0), _BLOCK))


def _clock_jump(dt, i, reference=None):
    """(seconds to add, what) when step i goes back by about a day or an hour, else None."""
    ref = dt if reference is None else reference
    pos = ref[ref > 0]
    period = float(np.median(pos)) if pos.size else 0.0
    tol = max(2.0, 10 * period)
    for size, what in ((86400.0, "crossing midnight"), (3600.0, "set back by an hour (daylight saving)")):
        if abs(dt[i] + size) <= tol:
            return size, what
    return None


def diagnose(t, *, gap_factor=5.0) -> TimeDiagnosis:
    """Split time stamps into segments at gaps and measure their jitter.

    Parameters
    ----------
    t : numpy.ndarray
        Strictly increasing times, at least two. [s]
    gap_factor : float
        A step longer than ``gap_factor`` median steps is a gap between bursts.

    Returns
    -------
    TimeDiagnosis

    Notes
    -----
    With steps :math:`\\Delta t_i` inside segments and their mean
    :math:`T`, the jitter is :math:`\\sqrt{\\overline{(\\Delta t_i - T)^2}} / T`.
    """
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    t0 = float(np.median(dt, overwrite_input=True))  # no copy of a day of steps: they are taken again
    np.subtract(t[1:], t[:-1], out=dt)
    gap = dt > gap_factor * t0
    segment = np.zeros(t.size, dtype=np.int32)
    if gap.any():
        inside = dt[~gap]
        np.cumsum(gap, dtype=np.int32, out=segment[1:])
    else:  # one segment: no copies (long recordings)
        inside = dt
    gaps_s = dt[gap].astype(float)
    period = float(np.mean(inside))  # = segment durations / steps: immune to rounding of the stamps
    dev = inside  # in place from here (the steps are no longer needed): a day at 2 kHz is 170 M steps
    dev -= period
    dev /= period
    jitter_max = float(max(abs(dev.max()), abs(dev.min())))
    jitter_rms = float(np.sqrt(np.dot(dev, dev) / dev.size))
    return TimeDiagnosis(period, jitter_rms, jitter_max, segment, gaps_s)


def held_update_rate(t, values, *, held_fraction=0.3):
    """The true update rate of a channel whose values are held (repeated) between updates. [Hz]

    Multi-sensor phone exports (Physics Toolbox) write a row whenever any sensor
    updates and repeat the other sensors' last values: a channel then changes less
    often than the rows come.  An update is a row whose value differs from the
    row before; a channel is *held* when more than ``held_fraction`` of its steps
    repeat the previous value.

    Parameters
    ----------
    t : numpy.ndarray
        Strictly increasing times. [s]
    values : numpy.ndarray
        The channel's values at ``t``.
    held_fraction : float
        Fraction of repeated steps above which the channel counts as held.

    Returns
    -------
    float or None
        Number of updates over the time from the first to the last update [Hz];
        None when the channel is not held, or constant.
    """
    v = np.asarray(values, dtype=float)
    if v.size < 3 or quantum(v) is not None:  # a quantised signal repeats values it was never held at
        return None
    n_change = _count_changes(v)  # counted first: most channels change on every row (no temporaries)
    if n_change < 2 or 1 - n_change / (v.size - 1) <= held_fraction:
        return None
    change = np.flatnonzero(np.diff(v) != 0) + 1  # rows that bring a new value (NaN != NaN: counted)
    if change.size < 2 or 1 - change.size / (v.size - 1) <= held_fraction:
        return None
    return float((change.size - 1) / (t[change[-1]] - t[change[0]]))


def quantum(values, *, tolerance=1e-3):
    """The quantisation step of a channel whose repeated values come from its resolution, not from holds.

    A sensor read at a coarse resolution (PASCO SPARKvue exports at 0.1 m/s^2) repeats a value while the
    signal moves less than one step; a channel held between updates (multi-sensor phone exports) jumps by
    whatever the signal did meanwhile.  The channel is quantised when every change is a whole multiple of
    the smallest change ``q`` (within ``tolerance`` of ``q``) and at least half the changes are one
    step (+-q): a held channel's changes are neither.

    Returns
    -------
    float or None
        ``q`` in the channel's units, or None when the repeats are not quantisation (or nothing repeats).
    """
    v = np.asarray(values, dtype=float)
    finite = np.isfinite(v)
    if finite.all():
        del finite
        # changes counted first: most channels change on every row, and need no copies to say so
        if _count_changes(v) > 0.95 * (v.size - 1):
            return None
        d = np.diff(v)
    else:
        d = np.diff(v[finite])
    nz = np.abs(d[d != 0])
    if nz.size < 8 or nz.size > 0.95 * d.size:
        return None
    q = float(nz.min())
    if not q > 1e-12 * float(nz.max()):  # a step twelve decades under the largest change is no resolution
        return None
    k = nz / q
    if np.max(np.abs(k - np.round(k))) > tolerance or np.mean(np.round(k) == 1) < 0.5:
        return None
    return q


def resample_linear(t, columns, segment, fs):
    """Resample each segment onto a uniform grid by linear interpolation.

    Parameters
    ----------
    t : numpy.ndarray
        Strictly increasing times. [s]
    columns : dict of str to numpy.ndarray
        Values at ``t``; NaN samples are left out of the interpolation.
    segment : numpy.ndarray
        Segment number of each sample.
    fs : float
        Target sample rate. [Hz]

    Returns
    -------
    t_new : numpy.ndarray
        ``t_start + k / fs`` inside each segment. [s]
    columns_new : dict of str to numpy.ndarray
    segment_new : numpy.ndarray
        int32 segment number of each new sample.
    """
    ts, segs = [], []
    out = {k: [] for k in columns}
    for s in np.unique(segment):
        m = segment == s
        tt = t[m]
        n = int(np.floor((tt[-1] - tt[0]) * fs * (1 + 1e-12))) + 1
        grid = tt[0] + np.arange(n) / fs
        ts.append(grid)
        segs.append(np.full(n, s, dtype=np.int32))
        for k, v in columns.items():
            vv = v[m]
            ok = np.isfinite(vv)
            out[k].append(np.interp(grid, tt[ok], vv[ok]) if ok.sum() >= 1 else np.full(n, np.nan))
    return np.concatenate(ts), {k: np.concatenate(v) for k, v in out.items()}, np.concatenate(segs)
