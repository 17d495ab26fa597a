"""Bursts: the uniformly sampled pieces a recording is made of, and how they are cut.

A recording (:func:`vibkit.read_recording`) numbers its bursts in a ``segment`` variable when its time
stamps have gaps (:func:`vibkit.io.timebase.diagnose` cuts them there); without one it is a single
burst.  Bursts are analysed one by one and never bridged.  This module is the one place that splits a
recording into bursts:

* :func:`segment_numbers` reads the burst number of each sample;
* :func:`split_segments` splits a Dataset or DataArray into its bursts (xarray objects, as they are);
* :func:`uniform_bursts` splits one channel into :class:`Burst` arrays ready for a spectrum: invalid
  samples repaired or cut out, irregular time stamps resampled;
* :func:`dropped_samples` counts the invalid samples that :func:`uniform_bursts` cut out;
* :func:`flag_invalid` says which samples are not measurements.

Invalid samples (:func:`flag_invalid`)
--------------------------------------
Non-finite values, fill values (``|x| >= 1e30``, which covers netCDF's default 9.96921e36) and
*absurd* values (further from the median than ``1e3`` times the median absolute deviation scaled to a
Gaussian sigma, or ``1e6`` times when the MAD is zero) are not measurements.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ABSURD_FACTOR",
    "FILL_THRESHOLD",
    "JITTER_RESAMPLE",
    "MAX_GAP_S",
    "Burst",
    "InvalidSamples",
    "dropped_samples",
    "flag_invalid",
    "segment_numbers",
    "split_segments",
    "uniform_bursts",
]

#: jitter (max |dt - mean dt| over mean dt) above which a burst is resampled to a uniform grid: 1 % is
#: what phone clocks and loggers with jitter exceed, while time stamps rounded to a microsecond stay below
JITTER_RESAMPLE = 0.01
#: longest run of invalid samples interpolated; longer runs split the burst [s]
MAX_GAP_S = 0.1
#: values at or above this magnitude are fill values, never data (netCDF's default fill is 9.96921e36)
FILL_THRESHOLD = 1e30
#: a sample further from the median than this many robust sigmas is absurd (not a measurement)
ABSURD_FACTOR = 1e3
#: the median absolute deviation of Gaussian samples times this is their standard deviation (1 / Phi^-1(3/4))
MAD_TO_SIGMA = 1.4826
#: when more than half the samples equal the median (MAD 0: a quantised or clipped record), a sample is absurd
#: beyond this many median non-zero deviations
ABSURD_FACTOR_NO_MAD = 1e6


@dataclass(frozen=True)
class Burst:
    """One uniformly sampled piece of a recording.

    Attributes
    ----------
    segment : int
    t0 : float
        Time of the first sample. [s]
    fs : float
        Sampling frequency. [Hz]
    x : ndarray
        Samples. [channel units]
    resampled : bool
        True when the time stamps were irregular and the burst was resampled linearly.
    invalid : dict
        Invalid samples found in this burst's span and repaired by interpolation (counts by kind:
        ``non_finite``, ``fill_value``, ``absurd``, ``total``); see :func:`uniform_bursts`.
    """

    segment: int
    t0: float
    fs: float
    x: np.ndarray
    resampled: bool
    invalid: dict = field(default_factory=dict)


def segment_numbers(obj):
    """Burst number of each sample of a Dataset or DataArray (its ``segment`` variable or coordinate), or None
    when it has none (one continuous burst)."""
    names = obj.variables if hasattr(obj, "data_vars") else getattr(obj, "coords", {})
    return np.asarray(obj["segment"].values) if "segment" in names else None


def split_segments(obj, segment=None):
    """Split a Dataset or DataArray into its bursts.

    Parameters
    ----------
    obj : xarray.Dataset or xarray.DataArray
        With dimension ``time``; a ``segment`` variable/coordinate numbers the bursts.
    segment : array_like, optional
        Segment numbers per sample, overriding the one in ``obj``.

    Returns
    -------
    list of (int, same type as obj)
        One entry per burst in ascending order; the whole object as segment 0 when continuous.
    """
    if segment is None:
        segment = segment_numbers(obj)
    if segment is None:
        return [(0, obj)]
    seg = np.asarray(segment)
    if seg.shape != (obj.sizes["time"],):
        raise ValueError(
            f"Parameter segment must have one value per time sample ({obj.sizes['time']}), got {seg.shape}."
        )
    return [(int(s), obj.isel(time=np.flatnonzero(seg == s))) for s in np.unique(seg)]


def uniform_bursts(recording, channel, *, min_samples=16, max_gap_s=None):
    """Split a recording's channel into bursts, each uniformly sampled.

    A burst whose time steps depart from their mean by more than 1 % (:data:`JITTER_RESAMPLE`: phone
    clocks, loggers with jitter) is resampled linearly onto a uniform grid at its mean step; time stamps
    rounded to a microsecond are kept as they are.

    Parameters
    ----------
    recording : xarray.Dataset
        A recording (see :func:`vibkit.read_recording`).
    channel : str
        Data variable along ``time``.
    min_samples : int
        Bursts shorter than this are dropped.
    max_gap_s : float, optional
        Invalid samples (:func:`flag_invalid`: non-finite, fill values
        ``|x| >= 1e30``, absurd values) are replaced by linear interpolation when they run over at
        most this time; a longer run, or one at an end of a burst, is cut out and splits the burst
        (never bridged). [s]  Default :data:`MAX_GAP_S`.

    Returns
    -------
    list of Burst
    """
    max_gap_s = MAX_GAP_S if max_gap_s is None else float(max_gap_s)
    t = np.asarray(recording["time"].values, dtype=float)
    x = np.asarray(recording[channel].values, dtype=float)
    seg = segment_numbers(recording)
    out = []
    bad_all = flag_invalid(x) if x.size else None
    for s, piece in _pieces(seg, bad_all, t, max_gap_s, min_samples):
        burst = _uniform_piece(int(s), t[piece], x[piece].copy(), bad_all.mask[piece], min_samples)
        if burst is not None:
            out.append(burst)
    if not out:
        if bad_all is not None and bad_all.count == x.size:
            raise ValueError(
                f"channel {channel!r}: every sample is invalid ({bad_all.non_finite} non-finite, "
                f"{bad_all.fill_value} fill values |x| >= {FILL_THRESHOLD:g}, {bad_all.absurd} absurd)"
            )
        raise ValueError(f"channel {channel!r}: no burst with at least {min_samples} valid samples")
    return out


def _pieces(seg, bad_all, t, max_gap_s, min_samples):
    """``(segment, piece)`` of :func:`uniform_bursts`: per segment, its indices cut at long runs of invalid samples
    (:func:`_split_at_gaps`).  A record of one segment without an invalid sample is one piece, the slice of every
    sample (views of the columns, not index arrays and gathered copies of the record's length: a day at 200 Hz
    held 3 more copies of its 44 MB)."""
    if seg is None and bad_all is not None and not bad_all.count:
        if t.size >= min_samples:
            yield 0, slice(0, t.size)
        return
    if seg is None:
        seg = np.zeros(t.size, dtype=int)
    for s in np.unique(seg):
        idx = np.flatnonzero(seg == s)
        if idx.size < min_samples:
            continue
        for piece in _split_at_gaps(idx, bad_all.mask, t, max_gap_s):
            yield s, piece


#: samples whose time steps :func:`_uniform_piece` checks at a time (no step array of the record's length)
STEP_BLOCK = 1 << 20


def _uniform_piece(segment, ts, xs, bad, min_samples):
    """One piece of a burst as a :class:`Burst` (invalid samples interpolated, resampled when irregular), or
    None when it is too short, wholly invalid or has no time span."""
    if bad.all() or ts.size < min_samples:
        return None
    counts = {}
    if bad.any():
        counts = {
            "non_finite": int(np.sum(bad & ~np.isfinite(xs))),
            "fill_value": int(np.sum(bad & np.isfinite(xs) & (np.abs(xs) >= FILL_THRESHOLD))),
            "total": int(bad.sum()),
        }
        counts["absurd"] = counts["total"] - counts["non_finite"] - counts["fill_value"]
        ok = ~bad
        xs[bad] = np.interp(ts[bad], ts[ok], xs[ok])
    span = ts[-1] - ts[0]
    if not span > 0:
        return None
    dt = span / (ts.size - 1)
    # the largest step's departure, a block of steps at a time (the same maximum as over the whole)
    dev = max(
        float(np.max(np.abs(np.diff(ts[i : i + STEP_BLOCK + 1]) - dt))) for i in range(0, ts.size - 1, STEP_BLOCK)
    )
    jitter = dev / dt
    if jitter > JITTER_RESAMPLE:
        grid = ts[0] + dt * np.arange(ts.size)
        xs = np.interp(grid, ts, xs)
    return Burst(segment, float(ts[0]), 1.0 / dt, xs, jitter > JITTER_RESAMPLE, counts)


def _split_at_gaps(idx, bad, t, max_gap_s):
    """Indices ``idx`` cut where invalid samples run longer than ``max_gap_s`` (the run dropped)."""
    b = bad[idx]
    if not b.any():
        return [idx]
    n = idx.size
    edges = np.diff(np.concatenate(([0], b.view(np.int8), [0])))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)  # runs b[i:j]
    pieces, start = [], 0
    for i, j in zip(starts, stops):
        t_lo = t[idx[i - 1]] if i > 0 else t[idx[i]]
        t_hi = t[idx[j]] if j < n else t[idx[j - 1]]
        if t_hi - t_lo > max_gap_s or i == 0 or j == n:
            # a long gap, or invalid samples at an end (nothing to interpolate towards): cut them out
            if i > start:
                pieces.append(idx[start:i])
            start = j
    if start < n:
        pieces.append(idx[start:])
    return pieces


def dropped_samples(recording, channel, bursts):
    """Samples of the channel in no burst of ``bursts`` (:func:`uniform_bursts`) because they were invalid
    and cut out."""
    values = np.asarray(recording[channel].values)
    interpolated = sum(b.invalid.get("total", 0) for b in bursts)
    if not interpolated and sum(b.x.size for b in bursts) == values.size:
        return 0  # every sample in a burst, none interpolated: none was invalid (no second pass over the record)
    mask = flag_invalid(np.asarray(values, dtype=float)).mask
    return max(0, int(mask.sum()) - interpolated) if values.size else 0


@dataclass(frozen=True)
class InvalidSamples:
    """Samples that are not measurements (see :func:`flag_invalid`).

    Attributes
    ----------
    mask : ndarray of bool
        True where a sample is invalid.
    non_finite, fill_value, absurd : int
        Counts by kind (disjoint).
    """

    mask: np.ndarray
    non_finite: int
    fill_value: int
    absurd: int

    @property
    def count(self) -> int:
        """Total number of invalid samples."""
        return self.non_finite + self.fill_value + self.absurd

    def as_dict(self) -> dict:
        return {
            "non_finite": self.non_finite,
            "fill_value": self.fill_value,
            "absurd": self.absurd,
            "total": self.count,
        }


def flag_invalid(x, *, fill_threshold=FILL_THRESHOLD, absurd_factor=ABSURD_FACTOR) -> InvalidSamples:
    """Flag non-finite, fill-value and absurd samples.

    Parameters
    ----------
    x : array_like, 1-D
        Samples. [x]
    fill_threshold : float, optional
        ``|x| >=`` this is a fill value. [x]
    absurd_factor : float, optional
        ``|x - median| > absurd_factor * 1.4826 MAD`` is absurd (with ``1e6`` instead of
        ``absurd_factor`` and the median of the non-zero deviations when the MAD is 0).

    Returns
    -------
    InvalidSamples
    """
    x = np.asarray(x, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        nonfin = ~np.isfinite(x)
        fill = ~nonfin & (np.abs(x) >= float(fill_threshold))
    bad = nonfin | fill
    absurd = np.zeros_like(bad)
    good = x[~bad] if bad.any() else x  # every sample valid (the common case): no copy of the record
    if good.size >= 3:
        med = float(np.median(good))
        dev = good - med
        np.abs(dev, out=dev)
        mad = float(np.median(dev))
        if mad > 0:
            lim = float(absurd_factor) * MAD_TO_SIGMA * mad
        else:
            nz = dev[dev > 0]
            lim = ABSURD_FACTOR_NO_MAD * float(np.median(nz)) if nz.size else math.inf
        with np.errstate(invalid="ignore", over="ignore"):
            absurd[~bad] = dev > lim
    return InvalidSamples(bad | absurd, int(nonfin.sum()), int(fill.sum()), int(absurd.sum()))
