"""Argument checks shared by the signal functions.

Every public function validates at its boundary and raises :class:`ValueError` naming the
parameter and what was expected.  NaN policy (one rule for the whole package):

* ``nan_policy="raise"`` (default): a NaN sample is an error naming the first bad index.
* ``nan_policy="interpolate"``: NaN samples are replaced by linear interpolation between the
  nearest finite neighbours (constant extrapolation at the ends).  The count is reported by
  :func:`fill_nan` so callers can record it.

An all-NaN or empty input is always an error; NaN never reaches an FFT.
"""

from __future__ import annotations

import functools

import numpy as np

NAN_POLICIES = ("raise", "interpolate")


def check_fs(fs, name: str = "fs") -> float:
    """Return ``fs`` as a positive finite float or raise ``ValueError``."""
    try:
        value = float(fs)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter {name}={fs!r} must be a positive number [Hz].") from None
    if not np.isfinite(value) or value <= 0.0:
        raise ValueError(f"Parameter {name}={fs!r} must be a positive finite number [Hz].")
    return value


def as_signal(x, name: str = "x", *, axis: int = -1, min_samples: int = 1) -> np.ndarray:
    """Return ``x`` as a float64 array with at least ``min_samples`` along ``axis``."""
    arr = np.asarray(x)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"Parameter {name} must be a real numeric array, got dtype {arr.dtype}.")
    arr = arr.astype(np.float64, copy=False)
    if arr.ndim == 0:
        raise ValueError(f"Parameter {name} must be an array with at least one dimension.")
    try:
        n = arr.shape[axis]
    except IndexError:
        raise ValueError(f"Parameter axis={axis} is out of range for {name} with shape {arr.shape}.") from None
    if n == 0 or arr.size == 0:
        raise ValueError(f"Parameter {name} is empty; expected at least {min_samples} samples.")
    if n < min_samples:
        raise ValueError(f"Parameter {name} has {n} samples along axis {axis}; expected at least {min_samples}.")
    if np.isinf(arr).any():
        raise ValueError(f"Parameter {name} contains infinite values.")
    finite = np.isfinite(arr)
    if not finite.any():
        raise ValueError(f"Parameter {name} is all NaN; nothing to analyse.")
    return arr


def fill_nan(x: np.ndarray, name: str = "x", *, nan_policy: str = "raise", axis: int = -1) -> np.ndarray:
    """Apply the package NaN policy along ``axis`` and return an array without NaN."""
    if nan_policy not in NAN_POLICIES:
        raise ValueError(f"Parameter nan_policy={nan_policy!r} must be one of {NAN_POLICIES}.")
    bad = np.isnan(x)
    if not bad.any():
        return x
    if nan_policy == "raise":
        first = np.unravel_index(int(np.argmax(bad)), x.shape)
        raise ValueError(
            f"Parameter {name} contains {int(bad.sum())} NaN samples (first at index {first}); "
            "pass nan_policy='interpolate' to fill them, or remove them."
        )
    moved = np.moveaxis(x, axis, -1)
    out = np.array(moved, dtype=np.float64, copy=True)
    flat = out.reshape(-1, out.shape[-1])
    idx = np.arange(flat.shape[-1])
    for row in flat:
        good = ~np.isnan(row)
        if not good.any():
            raise ValueError(f"Parameter {name} has a channel that is all NaN; nothing to interpolate.")
        if not good.all():
            row[~good] = np.interp(idx[~good], idx[good], row[good])
    return np.moveaxis(flat.reshape(out.shape), -1, axis)


def check_band(band, fs: float, name: str = "band") -> tuple[float, float]:
    """Return ``(fmin, fmax)`` with ``0 <= fmin < fmax <= fs/2`` or raise ``ValueError``."""
    try:
        fmin, fmax = (float(v) for v in band)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter {name}={band!r} must be a pair (fmin, fmax) [Hz].") from None
    nyq = fs / 2.0
    if not (np.isfinite(fmin) and np.isfinite(fmax)) or fmin < 0 or fmax <= fmin:
        raise ValueError(f"Parameter {name}={band!r} must satisfy 0 <= fmin < fmax [Hz].")
    if fmax > nyq:
        raise ValueError(f"Parameter {name}={band!r} reaches above the Nyquist frequency {nyq:g} Hz (fs={fs:g} Hz).")
    return fmin, fmax


def check_positive_int(value, name: str, *, minimum: int = 1) -> int:
    """Return ``value`` as an int ``>= minimum`` or raise ``ValueError``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"Parameter {name}={value!r} must be an integer >= {minimum}.")
    return int(value)


def check_window_length(nperseg: int, n: int, name: str = "nperseg") -> int:
    """Check that a window of ``nperseg`` samples fits in a record of ``n`` samples."""
    nperseg = check_positive_int(nperseg, name, minimum=2)
    if nperseg > n:
        raise ValueError(f"Parameter {name}={nperseg} is longer than the signal ({n} samples); expected <= {n}.")
    return nperseg


def check_resolution(n: int, fs: float, resolution_hz: float, name: str = "x") -> None:
    """Raise if a record of ``n`` samples cannot resolve ``resolution_hz``."""
    duration = n / fs
    if resolution_hz * duration < 1.0:
        raise ValueError(
            f"Parameter {name} is {duration:.4g} s long; a resolution of {resolution_hz:.4g} Hz needs at least "
            f"{1.0 / resolution_hz:.4g} s."
        )


@functools.lru_cache(maxsize=32)
def _decimation_sos(fs: float, q: int):
    """The anti-alias low-pass of :func:`decimate_for_band` (read-only second-order sections and their
    :func:`scipy.signal.sosfilt_zi`), designed once per rate and factor: its cutoff depends on nothing else, and every
    record of a fleet at one rate asks for the same one (the design cost as much as filtering a 30 s record)."""
    import scipy.signal

    return filter_with_zi(scipy.signal.butter(8, 0.8 * fs / (2.0 * q), btype="low", fs=fs, output="sos"))


def filter_with_zi(sos):
    """``(sos, zi)``, both read-only: second-order sections and their steady-state initial conditions
    (:func:`scipy.signal.sosfilt_zi`), for :func:`sosfiltfilt` (keep the pair in a cache of the filter's design:
    ``sosfilt_zi`` solves a small linear system per section, which scipy's own ``sosfiltfilt`` does on every call)."""
    import scipy.signal

    sos = np.array(sos, dtype=float)
    zi = scipy.signal.sosfilt_zi(sos)
    sos.flags.writeable = False
    zi.flags.writeable = False
    return sos, zi


def _even_ext(x, n):
    """scipy.signal's even extension of a 1-D ``x`` by ``n`` samples each side (the same values)."""
    return np.concatenate((x[n:0:-1], x, x[-2 : -(n + 2) : -1]))


def _odd_ext(x, n):
    """scipy.signal's odd extension of a 1-D ``x`` by ``n`` samples each side (the same operations)."""
    return np.concatenate((2 * x[0:1] - x[n:0:-1], x, 2 * x[-1:] - x[-2 : -(n + 2) : -1]))


@functools.cache
def _sosfilt_loop():
    """scipy's compiled second-order-section loop, the one :func:`scipy.signal.sosfilt` ends in (None where this
    scipy has it elsewhere: the public function then serves)."""
    try:
        from scipy.signal._sosfilt import _sosfilt as loop
    except ImportError:  # pragma: no cover - a scipy that moved it
        return None
    return loop


def _sosfilt(sos, x, zi):
    """``scipy.signal.sosfilt(sos, x, zi=zi)[0]`` of a 1-D float ``x`` with a writable float ``sos`` (sections x 6)
    and ``zi`` (sections x 2): the steps scipy takes for these (``x`` and ``zi`` copied into C order, its compiled
    loop run on them in place) without its checks and array-namespace dispatch, which cost twice the filtering of
    6,000 samples: the same numbers bit for bit."""
    loop = _sosfilt_loop()
    if loop is None:  # pragma: no cover - a scipy that moved it
        import scipy.signal

        return scipy.signal.sosfilt(sos, x, zi=zi)[0]
    y = np.array(x, dtype=float, order="C").reshape(1, -1)  # a copy: filtered in place
    z = np.array(zi, dtype=float, order="C").reshape(1, sos.shape[0], 2)
    try:
        loop(sos, y, z)
    except (TypeError, ValueError):  # pragma: no cover - a scipy whose private loop takes other arguments
        import scipy.signal

        return scipy.signal.sosfilt(sos, x, zi=zi)[0]
    return y.reshape(-1)


def sosfiltfilt(filt, x, *, padtype, padlen):
    """:func:`scipy.signal.sosfiltfilt` of a 1-D ``x`` (``padtype`` "even" or "odd", ``padlen < x.size``) with the
    filter's ``(sos, zi)`` from :func:`filter_with_zi`: scipy's steps (pad, forward from ``zi x[0]``, backward from
    ``zi y[-1]``, trim) without its ``sosfilt_zi`` per call, so the same numbers bit for bit."""
    sos, zi = filt
    sos = sos.copy()  # scipy's filter takes a writable one
    x = np.asarray(x, dtype=float)
    if not 0 <= padlen < x.size:
        raise ValueError(f"padlen={padlen} must lie in [0, {x.size}) for a record of {x.size} samples")
    ext = (_even_ext if padtype == "even" else _odd_ext)(x, padlen) if padlen > 0 else x
    zi = zi.reshape(sos.shape[0], 2)
    y = _sosfilt(sos, ext, zi * ext[:1])
    y = _sosfilt(sos, y[::-1], zi * y[-1:])
    y = y[::-1]
    return y[padlen:-padlen] if padlen > 0 else y


def decimate_for_band(x, fs: float, f_keep: float, *, oversample: float = 5.0):
    """Low-pass and decimate ``x`` so that ``fs / q >= oversample * f_keep``.

    Returns ``(y, fs / q, q)``; ``q = 1`` (no copy) when no reduction is possible.  The low-pass
    is a zero-phase 8th-order Butterworth at ``0.8 * fs / (2 q)``, flat to better than 1e-3 up
    to ``f_keep``.  In white noise the Cramer-Rao bound of a frequency is unchanged (noise
    variance and sample count both drop by ``q``), but a fit that reads the noise from its residual
    reads it low by :func:`decimated_noise_fraction` (the low-pass cuts part of the new band).
    """

    q = int(fs // (oversample * f_keep))
    if q < 2:
        return x, fs, 1
    cutoff = 0.8 * fs / (2.0 * q)
    padlen = min(x.size - 1, int(6.0 * fs / cutoff))
    if x.size > FILTER_BLOCK:
        return _decimated_by_blocks(_decimation_sos(float(fs), q), np.asarray(x, dtype=float), padlen, q), fs / q, q
    y = sosfiltfilt(_decimation_sos(float(fs), q), x, padtype="even", padlen=padlen)[::q]
    return np.ascontiguousarray(y), fs / q, q


#: a record longer than this is low-passed and decimated by :func:`_decimated_by_blocks` (samples)
FILTER_BLOCK = 1 << 20


def _decimated_by_blocks(filt, x, padlen, q):
    """``sosfiltfilt(filt, x, padtype="even", padlen=padlen)[::q]`` (:func:`sosfiltfilt`), the same numbers bit for
    bit, holding one forward-filtered copy of the record instead of three (its extension, the forward and the
    backward pass): each pass runs :data:`FILTER_BLOCK` samples at a time, its sections' state carried from block to
    block (the recursion the whole-record call runs, sample after sample), the backward pass keeping every ``q``-th
    sample only (a day at 200 Hz: 44 MB held instead of 132)."""
    import scipy.signal

    sos, zi = filt
    sos = sos.copy()  # scipy's filter takes a writable one
    zi = zi.reshape(sos.shape[0], 2)
    n = x.size
    n_ext = n + 2 * padlen
    # the even extension's three pieces, in order, without the extended copy
    pieces = [x[padlen:0:-1], x, x[-2 : -(padlen + 2) : -1]] if padlen > 0 else [x]
    fwd = np.empty(n_ext)
    z, at = zi * x[padlen if padlen > 0 else 0], 0
    for piece in pieces:
        for i in range(0, piece.size, FILTER_BLOCK):
            blk = piece[i : i + FILTER_BLOCK]
            fwd[at : at + blk.size], z = scipy.signal.sosfilt(sos, blk, zi=z)
            at += blk.size
    # backward over fwd reversed: its output's sample j is the result's sample n_ext - 1 - j; kept where that lies
    # in the record (after the padding) at a multiple of q
    out = np.empty((n + q - 1) // q)
    z = zi * fwd[-1:]
    for a in range(0, n_ext, FILTER_BLOCK):
        b = min(n_ext, a + FILTER_BLOCK)
        y, z = scipy.signal.sosfilt(sos, fwd[n_ext - 1 - a : (n_ext - 1 - b if b < n_ext else None) : -1], zi=z)
        idx = n_ext - 1 - np.arange(a, b) - padlen  # the result's index of each output sample
        keep = (idx >= 0) & (idx < n) & (idx % q == 0)
        out[idx[keep] // q] = y[keep]
    return out


@functools.lru_cache(maxsize=32)
def decimated_noise_fraction(fs: float, q: int) -> float:
    """What :func:`decimate_for_band` leaves of white noise, as a fraction of the decimated band: the variance of
    white noise after the zero-phase low-pass, over the variance of white noise of the same density filling
    ``0 .. fs / (2 q)`` (1 for ``q = 1``; about 0.79 otherwise: the low-pass cuts at 0.8 of the new Nyquist
    frequency).

    A fit that takes its noise density from its residual's variance (``var / (fs_new / 2)``) reads the density at
    the harmonics this fraction low after a decimation: its Cramer-Rao sigma is ``sqrt(fraction)`` too small, and
    ``sigma / sqrt(fraction)`` is the one white noise of the recorded density gives.
    """
    if q < 2:
        return 1.0
    import scipy.signal

    sos, _zi = _decimation_sos(float(fs), int(q))
    _w, h = scipy.signal.sosfreqz(sos, worN=1 << 14, fs=float(fs))
    return float(q * np.mean(np.abs(h) ** 4))  # |H|^2 twice (forward and backward), averaged over 0 .. fs/2
