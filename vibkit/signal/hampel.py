"""Hampel identifier and filter with MATLAB's semantics, outlier events, false-alarm calibration.

MATLAB ``[y, j, xmedian, xsigma] = hampel(x, k, nsigma)``: for every sample ``i`` the window is
``x[i-k : i+k+1]`` truncated at the ends of the record (never padded); ``xmedian`` is the median of
the window, ``xsigma = 1.4826 * median(|window - xmedian|)``; sample ``i`` is an outlier when
``|x[i] - xmedian[i]| > nsigma * xsigma[i]`` and is then replaced by ``xmedian[i]``.

NaN policy: NaN samples are ignored inside windows (medians of the finite samples only).  A NaN
sample is never an outlier; it stays NaN in ``filtered`` unless ``fill_nan=True``, which replaces
it by its window median.  A window without finite samples gives NaN median and sigma.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ._checks import as_signal, check_fs, check_positive_int

__all__ = [
    "hampel",
    "HampelResult",
    "hampel_events",
    "OutlierEvent",
    "hampel_false_alarm_rate",
    "hampel_n_sigma_for_rate",
    "MAD_SCALE",
]

MAD_SCALE = 1.4826
"""Scale making the MAD a consistent estimator of a Gaussian standard deviation (MATLAB's value)."""

NUMPY_MAX_ELEMENTS = 4_000_000
"""A record without NaN whose samples times window length is at most this is filtered by numpy (the windows held at
once: 32 MB), the same numbers to the last bit; a longer or gapped one by the compiled kernel (about 0.5 CPU-s to
load numba and the kernel, then linear in the samples)."""


class HampelResult(NamedTuple):
    """Result of :func:`hampel`, in MATLAB's output order.

    Attributes
    ----------
    filtered : ndarray
        Signal with outliers replaced by their window median. [x]
    is_outlier : ndarray of bool
        Outlier mask.
    median : ndarray
        Window medians. [x]
    sigma : ndarray
        Window standard deviations estimated as 1.4826 MAD. [x]
    """

    filtered: np.ndarray
    is_outlier: np.ndarray
    median: np.ndarray
    sigma: np.ndarray


def _resolve_n_sigma(half_window, n_sigma, false_alarm_rate):
    if false_alarm_rate is not None:
        if n_sigma is not None:
            raise ValueError("Give either n_sigma or false_alarm_rate, not both.")
        return hampel_n_sigma_for_rate(half_window, false_alarm_rate)
    if n_sigma is None:
        n_sigma = 3.0
    try:
        n_sigma = float(n_sigma)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter n_sigma={n_sigma!r} must be a non-negative number.") from None
    if not np.isfinite(n_sigma) or n_sigma < 0:
        raise ValueError(f"Parameter n_sigma={n_sigma!r} must be a non-negative finite number.")
    return n_sigma


def hampel(
    x: ArrayLike,
    half_window: int = 3,
    n_sigma: float | None = None,
    *,
    false_alarm_rate: float | None = None,
    fill_nan: bool = False,
    axis: int = -1,
) -> HampelResult:
    """Hampel filter exactly as MATLAB's ``hampel(x, k, nsigma)``.

    Parameters
    ----------
    x : array_like
        Signal. [x]
    half_window : int, optional
        ``k``: the window holds ``2k + 1`` samples, truncated at the ends.  MATLAB default 3.
    n_sigma : float, optional
        Threshold in estimated standard deviations.  MATLAB default 3.  On Gaussian noise the
        real per-sample false-alarm rate is much higher than the asymptotic ``2 Phi(-n_sigma)``
        because median and MAD come from only ``2k + 1`` samples: see
        :func:`hampel_false_alarm_rate` (e.g. about 4.8 % for ``k = 3``, ``n_sigma = 3``).
    false_alarm_rate : float, optional
        Instead of ``n_sigma``: the per-sample probability of flagging Gaussian white noise;
        ``n_sigma`` is then set by :func:`hampel_n_sigma_for_rate`.
    fill_nan : bool, optional
        Replace NaN samples by their window median in ``filtered``.
    axis : int, optional
        Time axis.

    Returns
    -------
    HampelResult
        ``(filtered, is_outlier, median, sigma)``.

    Raises
    ------
    ValueError
        Empty or all-NaN input, ``half_window`` not a positive integer or longer than the signal,
        negative ``n_sigma``, both ``n_sigma`` and ``false_alarm_rate``.

    Notes
    -----
    Runs in ``O(n k)`` with a sorted sliding window (numba), exact to the last bit against the
    direct definition (``numpy.median`` on each truncated window); a short record without NaN
    (:data:`NUMPY_MAX_ELEMENTS`) with that definition itself, on all windows at once (numpy).

    References
    ----------
    F. R. Hampel, J. Amer. Statist. Assoc. 69 (1974) 383-393.
    MathWorks, ``hampel`` (Signal Processing Toolbox) documentation.

    Examples
    --------
    >>> import numpy as np
    >>> y, j, _, _ = hampel(np.array([1.0, 1.1, 0.9, 10.0, 1.0, 1.05, 0.95]), 2, 3)
    >>> j.nonzero()[0].tolist()
    [3]
    """
    x = as_signal(x, axis=axis)
    k = check_positive_int(half_window, "half_window")
    n = x.shape[axis]
    if 2 * k + 1 > n:
        raise ValueError(
            f"Parameter half_window={k} gives a window of {2 * k + 1} samples, longer than the signal "
            f"({n} samples); expected half_window <= {(n - 1) // 2}."
        )
    ns = _resolve_n_sigma(k, n_sigma, false_alarm_rate)
    moved = np.ascontiguousarray(np.moveaxis(x, axis, -1))
    flat = moved.reshape(-1, n)
    y = np.empty_like(flat)
    mask = np.empty(flat.shape, dtype=np.bool_)
    med = np.empty_like(flat)
    sig = np.empty_like(flat)
    for r in range(flat.shape[0]):
        if n * (2 * k + 1) <= NUMPY_MAX_ELEMENTS and not np.isnan(flat[r]).any():
            _hampel_numpy(flat[r], k, ns, y[r], mask[r], med[r], sig[r])
            continue
        # Independent chunks (each primes its own window) run on numba's threads for long records; numba is
        # imported here, on the first filter that needs it, not with the package (a command that never filters a
        # long or gapped record never loads it)
        import numba

        from .kernels import _hampel_core

        n_chunks = 1 if n < 200_000 else 4 * numba.get_num_threads()
        _hampel_core(flat[r], k, ns, MAD_SCALE, bool(fill_nan), y[r], mask[r], med[r], sig[r], n_chunks)
    shape = moved.shape

    def back(a):
        return np.moveaxis(a.reshape(shape), -1, axis)

    return HampelResult(back(y), back(mask), back(med), back(sig))


def _hampel_numpy(x, k, n_sigma, y, outlier, med_out, sig_out):
    """The compiled filter's numbers for a record without NaN, by numpy: the median and the MAD of every window at
    once (the definition itself: ``numpy.median`` of each window truncated at the ends), for records short enough
    (:data:`NUMPY_MAX_ELEMENTS`) that loading the compiled kernel would cost more than the work."""
    n = x.shape[0]
    if n > 2 * k:  # the whole windows, samples k .. n - k - 1
        win = np.lib.stride_tricks.sliding_window_view(x, 2 * k + 1)
        m = _middle_of_rows(win.copy(), k)
        med_out[k : n - k] = m
        sig_out[k : n - k] = MAD_SCALE * _middle_of_rows(np.abs(win - m[:, None]), k)
    ends = np.array([*range(min(k, n)), *range(max(k, n - k), n)], dtype=np.intp)  # the windows the ends truncate
    if ends.size:
        med_out[ends], sig_out[ends] = _truncated_windows(x, ends, k)
    np.greater(np.abs(x - med_out), n_sigma * sig_out, out=outlier)
    y[:] = np.where(outlier, med_out, x)


def _middle_of_rows(rows, k):
    """``numpy.median`` of each row of ``rows`` (2k + 1 values, no NaN; reordered in place): its (k + 1)-th smallest
    value, which is what ``numpy.median`` returns for an odd count (the mean of that one value), found by one
    partition (``numpy.median`` partitions for the largest value too, to find NaN: three times the work)."""
    rows.partition(k, axis=1)
    return rows[:, k].copy()


def _middle(rows, lengths):
    """``numpy.median`` of each row's first ``lengths`` values, the rows sorted (the rest +inf): its middle value,
    or the mean of its two middle values, as ``numpy.median`` computes them."""
    at = np.arange(rows.shape[0])
    lo, hi = rows[at, (lengths - 1) // 2], rows[at, lengths // 2]
    return np.where(lengths % 2 == 1, lo, (lo + hi) / 2)


def _truncated_windows(x, ends, k):
    """(median, MAD sigma) of the windows ``x[max(0, i - k) : i + k + 1]`` of the samples ``ends``, which the
    record's ends truncate, all at once: each window a row padded with +inf and sorted, so that its order
    statistics are those ``numpy.median`` partitions for.  ``x`` finite (:func:`hampel` refuses infinite samples
    and sends a record with NaN to the compiled kernel)."""
    start = np.maximum(ends - k, 0)
    lengths = np.minimum(ends + k + 1, x.size) - start
    cols = np.arange(int(lengths.max()))
    inside = cols < lengths[:, None]
    win = np.where(inside, x[np.minimum(start[:, None] + cols, x.size - 1)], np.inf)
    med = _middle(np.sort(win, axis=1), lengths)
    dev = np.where(inside, np.abs(win - med[:, None]), np.inf)
    return med, MAD_SCALE * _middle(np.sort(dev, axis=1), lengths)


@dataclass(frozen=True)
class OutlierEvent:
    """One run of consecutive outlier samples (a spike), as found by :func:`hampel_events`.

    Attributes
    ----------
    index : int
        Sample of the largest deviation in the run.
    time_s : float
        Its time. [s]
    value : float
        Its value. [x]
    deviation : float
        ``value - median`` at that sample (signed size of the spike). [x]
    size_sigma : float
        ``|deviation| / sigma``: how many local standard deviations (inf when sigma is 0).
    start, stop : int
        First and one-past-last sample of the run.
    duration_s : float
        ``(stop - start) / fs``. [s]
    """

    index: int
    time_s: float
    value: float
    deviation: float
    size_sigma: float
    start: int
    stop: int
    duration_s: float


def hampel_events(x, fs, *, half_window=3, n_sigma=None, false_alarm_rate=None, t0=0.0, max_gap=0):
    """Outliers of a 1-D signal as events: in field data a spike may be a damaged link, not noise.

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    half_window, n_sigma, false_alarm_rate :
        As :func:`hampel`.
    t0 : float, optional
        Time of the first sample. [s]
    max_gap : int, optional
        Outlier samples separated by at most ``max_gap`` clean samples belong to one event.

    Returns
    -------
    list of OutlierEvent
        In time order.
    """
    fs = check_fs(fs)
    x = as_signal(x)
    if x.ndim != 1:
        raise ValueError(f"Parameter x must be 1-D for hampel_events, got shape {x.shape}.")
    if isinstance(max_gap, bool) or not isinstance(max_gap, (int, np.integer)) or max_gap < 0:
        raise ValueError(f"Parameter max_gap={max_gap!r} must be a non-negative integer.")
    res = hampel(x, half_window, n_sigma, false_alarm_rate=false_alarm_rate)
    idx = np.flatnonzero(res.is_outlier)
    events = []
    if idx.size == 0:
        return events
    breaks = np.flatnonzero(np.diff(idx) > max_gap + 1)
    starts = np.concatenate(([0], breaks + 1))
    stops = np.concatenate((breaks + 1, [idx.size]))
    dev_all = x - res.median
    for a, b in zip(starts, stops):
        run = idx[a:b]
        i = int(run[np.argmax(np.abs(dev_all[run]))])
        dev = float(dev_all[i])
        s = float(res.sigma[i])
        size = abs(dev) / s if s > 0 else float("inf")
        start, stop = int(run[0]), int(run[-1]) + 1
        events.append(OutlierEvent(i, float(t0) + i / fs, float(x[i]), dev, size, start, stop, (stop - start) / fs))
    return events


_MC_SEED = 20240531


@lru_cache(maxsize=64)
def _interior_statistic(k: int, n_windows: int) -> np.ndarray:
    """Sorted ``|x_c - median| / (1.4826 MAD)`` of the centre sample of Gaussian windows."""
    rng = np.random.default_rng(_MC_SEED + k)
    out = np.empty(n_windows)
    chunk = max(1, 2_000_000 // (2 * k + 1))
    for a in range(0, n_windows, chunk):
        b = min(n_windows, a + chunk)
        w = rng.standard_normal((b - a, 2 * k + 1))
        med = np.median(w, axis=1)
        mad = np.median(np.abs(w - med[:, None]), axis=1)
        out[a:b] = np.abs(w[:, k] - med) / (MAD_SCALE * mad)
    out.sort()
    return out


def _n_windows(rate: float) -> int:
    return int(min(4_000_000, max(400_000, 400.0 / rate)))


_RB_DRAWS = 200_000  # draws of a window's 2k other samples for the conditional (Rao-Blackwell) estimate


@lru_cache(maxsize=64)
def _window_others(k: int):
    """Medians and MADs that the 2k non-centre samples of Gaussian windows leave to a far centre.

    Returns (m_hi, d_hi, m_lo, d_lo), one value per draw: with the others sorted o_1 <= ... <= o_2k,
    a centre above o_{k+1} has the window median m_hi = o_{k+1}, and one far enough from it the MAD
    d_hi = the (k+1)-th smallest |o_i - m_hi|; likewise below o_k with m_lo = o_k.
    """
    rng = np.random.default_rng(_MC_SEED + 7919 * k)
    out = np.empty((4, _RB_DRAWS))
    chunk = max(1, 4_000_000 // (2 * k))
    for a in range(0, _RB_DRAWS, chunk):
        b = min(_RB_DRAWS, a + chunk)
        o = np.sort(rng.standard_normal((b - a, 2 * k)), axis=1)
        for row, col in ((0, k), (2, k - 1)):
            m = o[:, col]
            out[row, a:b] = m
            out[row + 1, a:b] = np.partition(np.abs(o - m[:, None]), k, axis=1)[:, k]
    return out


def _tail_probability(k: int, n_sigma: float) -> float:
    """P(|x_c - median| > n_sigma 1.4826 MAD) for the centre of a Gaussian window, n_sigma > 1/1.4826.

    Exact given the other 2k samples: beyond that threshold the centre is outside the window's
    middle and its own deviation is above the MAD, so median and MAD are the others' (see
    :func:`_window_others`) and the probability is that of a normal sample beyond
    m_hi + n_sigma 1.4826 d_hi or below m_lo - n_sigma 1.4826 d_lo; averaging that conditional
    probability over the others (Rao-Blackwellisation) needs far fewer draws than counting
    exceedances (200,000 draws give about 0.3 % relative error at a rate of 1e-4).
    """
    from scipy.special import ndtr

    m_hi, d_hi, m_lo, d_lo = _window_others(k)
    c = n_sigma * MAD_SCALE
    return float(np.mean(ndtr(-(m_hi + c * d_hi)) + ndtr(m_lo - c * d_lo)))


def hampel_false_alarm_rate(half_window, n_sigma):
    """Per-sample probability that :func:`hampel` flags Gaussian white noise (interior samples).

    Parameters
    ----------
    half_window : int
        ``k`` of the window.
    n_sigma : float
        Threshold.

    Returns
    -------
    float
        False-alarm probability: for ``n_sigma > 1 / 1.4826`` the mean over 200,000 draws (fixed
        seed) of the exact probability given a window's other samples (:func:`_tail_probability`);
        below, a plain Monte Carlo count over 400,000 windows.

    Notes
    -----
    The centre sample belongs to its own window and median and MAD come from ``2k + 1`` samples,
    so the rate exceeds the asymptotic ``2 Phi(-n_sigma)`` (0.27 % at 3 sigma): about 4.8 % for
    ``k = 3``, 2.8 % for ``k = 5`` and 1.4 % for ``k = 10`` at ``n_sigma = 3``.  Samples within ``k`` of the ends use
    shorter windows and have other rates.
    """
    k = check_positive_int(half_window, "half_window")
    ns = _resolve_n_sigma(k, n_sigma, None)
    if ns * MAD_SCALE > 1.0:
        return _tail_probability(k, ns)
    stat = _interior_statistic(k, _n_windows(1e-3))
    return float(1.0 - np.searchsorted(stat, ns, side="right") / stat.size)


def hampel_n_sigma_for_rate(half_window, false_alarm_rate):
    """Threshold ``n_sigma`` at which :func:`hampel` flags Gaussian white noise at a given rate.

    Parameters
    ----------
    half_window : int
        ``k`` of the window.
    false_alarm_rate : float
        Per-sample probability, in ``[1e-4, 0.5]``.

    Returns
    -------
    float
        ``n_sigma``: the ``1 - rate`` quantile of the interior statistic
        ``|x_c - median| / (1.4826 MAD)``, found by bisection on :func:`hampel_false_alarm_rate`'s
        tail probability (milliseconds to a second, whatever the rate).
    """
    k = check_positive_int(half_window, "half_window")
    try:
        rate = float(false_alarm_rate)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter false_alarm_rate={false_alarm_rate!r} must be a number in [1e-4, 0.5].") from None
    if not 1e-4 <= rate <= 0.5:
        raise ValueError(f"Parameter false_alarm_rate={false_alarm_rate!r} must lie in [1e-4, 0.5].")
    return _n_sigma_for_rate(k, rate)


#: the file, in the kernel cache's folder, that keeps the thresholds found (by window, rate and what they depend on)
THRESHOLD_CACHE = "hampel-thresholds.json"


def _threshold_cache_path():
    """Where found thresholds are kept: the folder numba caches vibkit's kernels in (``$NUMBA_CACHE_DIR``, which
    :mod:`vibkit.runtime.kernel_cache` sets when it chooses one), else this package's ``__pycache__``, where numba
    keeps them by default."""
    folder = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "__pycache__"
    )
    return os.path.join(folder, THRESHOLD_CACHE)


def _threshold_key(k, rate):
    # everything the threshold depends on: the window, the rate, the draws (seed, count) and numpy's generator
    return f"k={k} rate={rate!r} seed={_MC_SEED} draws={_RB_DRAWS} windows={_n_windows(rate)} numpy={np.__version__}"


def _stored_thresholds(path):
    try:
        with open(path, encoding="utf-8") as fh:
            stored = json.load(fh)
    except (OSError, ValueError):
        return {}
    return stored if isinstance(stored, dict) else {}


def _store_threshold(path, key, value):
    """Add one threshold to the file, written whole to a temporary file and renamed (a reader never sees half a
    file); a folder that cannot be written keeps nothing, and the next run finds the threshold again."""
    stored = _stored_thresholds(path)
    stored[key] = value
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=THRESHOLD_CACHE, suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(stored, fh, indent=0, sort_keys=True)
        os.replace(tmp, path)
    except OSError:
        return


@lru_cache(maxsize=256)
def _n_sigma_for_rate(k: int, rate: float) -> float:
    """:func:`hampel_n_sigma_for_rate` once per (half window, rate): the calibration depends on nothing else (a
    report filters every burst at the same window and rate). Kept in memory and in a file beside the compiled
    kernels: at 0.1 s and 2,050 Hz (k = 205) it costs about 4 CPU seconds, every run, for one number."""
    path = _threshold_cache_path()
    key = _threshold_key(k, rate)
    found = _stored_thresholds(path).get(key)
    if isinstance(found, float) and math.isfinite(found) and found > 0:
        return found  # JSON keeps a float's repr: the very number found before
    value = _find_n_sigma(k, rate)
    _store_threshold(path, key, value)
    return value


def _find_n_sigma(k: int, rate: float) -> float:
    """The threshold at which the interior statistic's tail probability is ``rate`` (bisection, 61 evaluations)."""
    if _tail_probability(k, 1.0001 / MAD_SCALE) > rate:
        # the usual case: the threshold lies in the range where the tail probability is exact given
        # the other samples; bisect the monotone tail probability (in log n_sigma)
        lo, hi = math.log(1.0001 / MAD_SCALE), math.log(100.0)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if _tail_probability(k, math.exp(mid)) > rate:
                lo = mid
            else:
                hi = mid
        return float(math.exp(0.5 * (lo + hi)))
    stat = _interior_statistic(k, _n_windows(rate))
    return float(np.quantile(stat, 1.0 - rate))
