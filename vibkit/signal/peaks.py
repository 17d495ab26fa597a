"""Fundamental of a harmonic family, octave-safe, and the one-call link-pass estimate.

The harmonic evidence of a candidate ``f`` adds, for every multiple ``h f`` up to ``f_top``,
``max(0, log(p_h / p_thr))`` where ``p_h`` is the spectral power near ``h f`` over the noise
floor and ``p_thr`` the detection threshold (6 dB over the median of the max-filtered noise,
about 9 dB over its mean).  A subharmonic ``f0 / m`` collects all the
evidence of ``f0`` as well, so after the maximum is found the search moves up to ``m`` times it
(m = 2, 3, 5) whenever that candidate scores within one unit of evidence.  ``2 f0`` therefore
wins over ``f0`` only if no odd harmonic of ``f0`` stands more than about 13 dB
(``threshold + 4.3 dB`` over the max-filtered noise median) above the mean noise: with that stated condition there is no octave error
within the band, even when a harmonic is stronger than the fundamental.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.ndimage
from numpy.typing import ArrayLike

from ._checks import (
    as_signal,
    check_band,
    check_fs,
    check_positive_int,
    decimate_for_band,
    decimated_noise_fraction,
    fill_nan,
)
from .estimate import FrequencyEstimate, harmonic_ls, interpolated_dft, interpolated_frequency
from .quantisation import quantisation_floor, quantisation_step

__all__ = ["find_fundamental", "Fundamental", "link_pass_estimate", "LinkPassEstimate", "Harmonic"]


@dataclass(frozen=True)
class Fundamental:
    """Result of :func:`find_fundamental`.

    Attributes
    ----------
    frequency_hz : float
        Fundamental, to within a fraction of a bin. [Hz]
    score : float
        Harmonic-sum score (log-likelihood-like, larger is better).
    harmonic_snr_db : ndarray
        Power over noise floor near each multiple ``h f`` (h = 1, 2, ...). [dB]
    bin_hz : float
        Bin width of the search spectrum (the record, or its Welch segments when longer than
        ``max(20 / band[0], 8)`` s). [Hz]
    """

    frequency_hz: float
    score: float
    harmonic_snr_db: np.ndarray
    bin_hz: float


_TIE = 1.0
_DYNAMIC_RANGE_DB = 80.0


#: values (segments x FFT length) :func:`_welch_sum` transforms in one call: 2 M values are 16 MB as floats
WELCH_BLOCK_VALUES = 1 << 21


def _welch_sum(x, nseg, step, count, w, nfft):
    """Sum over the ``count`` segments ``x[a : a + nseg]`` (``a = 0, step, ...``) of
    ``|rfft((seg - mean(seg)) * w, nfft)|^2``, the segments transformed a block of rows at a time (one FFT call per
    segment cost more in calls than in transforms: 7,200 segments for 8 h); the rows are added in the segments'
    order, so the sum is the one a loop over the segments gives, bit for bit."""
    p = np.zeros(nfft // 2 + 1)
    segs = np.lib.stride_tricks.sliding_window_view(x, nseg)[::step][:count]  # a view: no copy of the record
    rows = max(1, WELCH_BLOCK_VALUES // nfft)
    for i in range(0, count, rows):
        s = segs[i : i + rows]
        y = s - s.mean(axis=1, keepdims=True)
        y *= w
        q = np.abs(np.fft.rfft(y, nfft, axis=1))
        np.square(q, out=q)
        for r in q:
            p += r
    return p


def _score_table(x, fs, band, f_top, threshold_db, quantum=0.0, decimation=1.0):
    n = x.size
    # Long records: Welch-average segments of max(20 periods of band[0], 8 s); the search needs
    # no more resolution than that and the averaged noise floor is steadier.
    nseg = min(n, int(round(fs * max(20.0 / band[0], 8.0))))
    nfft = 1 << int(np.ceil(np.log2(4 * nseg)))
    w = np.hanning(nseg)
    step = max(1, nseg // 2)
    starts = range(0, n - nseg + 1, step)
    p = _welch_sum(x, nseg, step, len(starts), w, nfft)
    p /= len(starts)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    df = fs / nseg
    sel = (f >= band[0] / 2.0) & (f <= f_top)
    # Noise floor: median of the power (exponential noise: median = ln 2 x mean), but not below
    # _DYNAMIC_RANGE_DB under the strongest peak, so that noise-free (simulated) signals do not
    # turn window leakage and rounding into "detected" harmonics.
    floor = float(np.max(p[sel])) * 10.0 ** (-_DYNAMIC_RANGE_DB / 10.0)
    # ... nor below what the recorder's step can resolve (vibkit.signal.quantisation): the lines of a clean
    # quantised tone's rounding error are not harmonics
    broadband = float(np.median(p[sel])) / np.log(2.0)
    noise = max(
        broadband, floor, quantisation_floor(quantum, w, broadband, decimation=decimation), np.finfo(float).tiny
    )
    half = max(1, int(round(df / (f[1] - f[0]))))
    pmax = scipy.ndimage.maximum_filter1d(p, size=2 * half + 1, mode="nearest") / noise
    # Threshold relative to the median of the max-filtered noise (the max over +-1 bin lifts the
    # noise by about 3 dB): noise multiples then exceed it with probability below 0.2 %.
    thr = 10.0 ** (threshold_db / 10.0) * max(float(np.median(pmax[sel])), 1.0)
    return f, pmax, p / noise, df, thr


def interp_by_harmonic(hf, f, p):
    """``np.interp(hf, f, p)`` of a (candidates x harmonics) grid ``hf`` whose columns ascend: numpy's search starts
    from the previous point's bin, so the points are looked up a column (one harmonic of every candidate) at a time,
    in ascending order, and the result returned in ``hf``'s (C) order: the same values, each independent of the
    order asked in, at a third of the cost of row order (a jump across the spectrum at every point)."""
    return np.ascontiguousarray(np.interp(hf.T.ravel(), f, p).reshape(hf.T.shape).T)


def log_evidence(p, thr):
    """``np.maximum(np.log(np.maximum(p, 1e-300) / thr), 0.0)``, the log taken only where it is not 0: a ratio over
    1 (or NaN), a few percent of a search grid's points (the log of the whole grid was a third of a search's time);
    the same values bit for bit."""
    r = np.maximum(p, 1e-300)
    r /= thr
    ev = np.zeros_like(r)
    keep = ~(r <= 1.0)
    ev[keep] = np.log(r[keep])
    return ev


def _scores(cands, f, pmax, f_top, thr):
    """Harmonic evidence: sum over multiples up to ``f_top`` of ``max(0, log(p / thr))``."""
    cands = np.asarray(cands, dtype=float)
    hmax = int(f_top // cands.min())
    hf = cands[:, None] * np.arange(1, hmax + 1)[None, :]
    p = interp_by_harmonic(hf, f, pmax)
    ev = log_evidence(p, thr)
    ev[hf > f_top] = 0.0
    return ev.sum(axis=1)


def climb_from_subharmonic(cands, sc, df):
    """Index of the best candidate frequency once moved off a subharmonic.

    A subharmonic collects every harmonic of the truth: move up to m times the best candidate
    (m = 2, 3, 5) while that scores within ``_TIE`` (one e-fold of evidence) of it. ``df`` is the
    frequency resolution [Hz]: a candidate within df / 2 of m f counts as m f.
    """
    i = int(np.argmax(sc))
    moved = True
    while moved:
        moved = False
        for m in (2, 3, 5):
            near = np.flatnonzero(np.abs(cands - m * cands[i]) <= df / 2)
            if near.size:
                j = int(near[np.argmax(sc[near])])
                if sc[j] >= sc[i] - _TIE:
                    i, moved = j, True
                    break
    return i


def find_fundamental(x, fs, *, band, f_top=None, threshold_db=6.0, nan_policy="raise", quantum=None, decimation=1):
    """Fundamental of a harmonic family within a plausible band, without octave errors.

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    band : (float, float)
        Plausible range of the fundamental. [Hz]
    f_top : float, optional
        Highest frequency whose harmonics count; default ``min(10 band[1], 0.9 fs/2)``. [Hz]
    threshold_db : float, optional
        Detection threshold of a harmonic over the noise floor. [dB]
    nan_policy : {"raise", "interpolate"}, optional
    quantum : float, optional
        Quantisation step of the recorder in the units of ``x``: the noise floor is never taken below
        what it resolves (:func:`vibkit.signal.quantisation.quantisation_floor`).  Default: the step of
        ``x``'s own levels (:func:`vibkit.signal.quantisation.quantisation_step`; 0 for continuous data). [x]
    decimation : float, optional
        ``x`` was low-pass filtered and decimated this many times since it was recorded.

    Returns
    -------
    Fundamental

    Raises
    ------
    ValueError
        Band outside Nyquist, record shorter than three periods of ``band[0]``.

    Notes
    -----
    Octave-safe when at least one odd harmonic of the true fundamental exceeds the mean noise
    floor by about ``threshold_db + 7`` dB (see the module notes).
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=8)
    if x.ndim != 1:
        raise ValueError(f"Parameter x must be 1-D, got shape {x.shape}.")
    x = fill_nan(x, nan_policy=nan_policy)
    fmin, fmax = check_band(band, fs)
    if fmin <= 0:
        raise ValueError(f"Parameter band={band!r} must start above 0 Hz.")
    n = x.size
    if n / fs * fmin < 3.0:
        raise ValueError(
            f"Parameter x is {n / fs:.4g} s long; finding a fundamental down to {fmin:g} Hz needs at least "
            f"{3.0 / fmin:.4g} s (three periods)."
        )
    if f_top is None:
        f_top = min(10.0 * fmax, 0.9 * fs / 2.0)
    f_top = float(f_top)
    if not fmax <= f_top <= fs / 2.0:
        raise ValueError(f"Parameter f_top={f_top!r} must lie in [band[1], fs/2] = [{fmax:g}, {fs / 2:g}] Hz.")
    quantum = quantisation_step(x) if quantum is None else float(quantum)
    f, pmax, praw, df, thr = _score_table(x, fs, (fmin, fmax), f_top, threshold_db, quantum, decimation)
    h_max = max(1, int(f_top // fmin))
    step = df / (2.0 * h_max)
    cands = np.arange(fmin, fmax + step / 2, step)
    sc = _scores(cands, f, pmax, f_top, thr)
    i = climb_from_subharmonic(cands, sc, df)
    # The tolerant (max-filtered) score is flat within about a bin / h; refine on the raw
    # zero-padded spectrum over +-half a bin around the coarse best.
    c0 = cands[i]
    fine = np.linspace(max(fmin, c0 - df / 2), min(fmax, c0 + df / 2), 201)
    sf = _scores(fine, f, praw, f_top, thr)
    best = float(fine[int(np.argmax(sf))])
    sf = _scores(np.array([best]), f, pmax, f_top, thr)
    hf = best * np.arange(1, int(f_top // best) + 1)
    snr_db = 10.0 * np.log10(np.maximum(np.interp(hf, f, pmax), 1e-30))
    return Fundamental(best, float(np.max(sf)), snr_db, df)


@dataclass(frozen=True)
class Harmonic:
    """One harmonic of the link-pass family.

    Attributes
    ----------
    order : int
        Multiple of the fundamental (1 = link-pass).
    frequency_hz : float
        ``order * fundamental_hz``. [Hz]
    amplitude : float
        Fitted peak amplitude. [x]
    phase_rad : float
        Cosine phase at the first sample. [rad]
    detected : bool
        Amplitude above three standard deviations of its estimate (``noise_std sqrt(2/N)``).
    """

    order: int
    frequency_hz: float
    amplitude: float
    phase_rad: float
    detected: bool


@dataclass(frozen=True)
class LinkPassEstimate:
    """Result of :func:`link_pass_estimate`.

    Attributes
    ----------
    fundamental_hz : float
        Link-pass frequency. [Hz]
    fundamental_sigma_hz : float
        Its standard deviation (Cramer-Rao bound with fitted amplitudes and noise, the noise density as recorded:
        where the record was decimated for the fit, the part of the white noise its low-pass removed is restated).
        [Hz]
    harmonics : list of Harmonic
    noise_std : float
        Residual standard deviation of the analysed signal (after decimation to about five times
        the highest harmonic, so in-band noise only). [x]
    snr_db : float
        Harmonic power over that noise. [dB]
    method : str
    warnings : list of str
    estimate : FrequencyEstimate
        The underlying estimator result.
    decimation : int
        The factor the record was decimated by for the fit (1: fitted at its rate); the sigma is restated for it.
    """

    fundamental_hz: float
    fundamental_sigma_hz: float
    harmonics: list
    noise_std: float
    snr_db: float
    method: str
    warnings: list = field(default_factory=list)
    estimate: FrequencyEstimate | None = None
    decimation: int = 1


def link_pass_estimate(
    x: ArrayLike,
    fs: float,
    *,
    band: tuple[float, float] = (2.0, 6.0),
    n_harmonics: int = 5,
    method: str = "harmonic-ls",
    nan_policy: str = "raise",
    quantum: float | None = None,
    decimation: int = 1,
) -> LinkPassEstimate:
    """Find the link-pass fundamental in a band (octave-safe), estimate it with sigma, list harmonics.

    Parameters
    ----------
    x : array_like, 1-D
        Signal (displacement, velocity or acceleration). [x]
    fs : float
        Sampling frequency. [Hz]
    band : (float, float), optional
        Plausible link-pass range. [Hz]  Default (2, 6) Hz: 0.27-0.8 m/s with 0.133 m links.
    n_harmonics : int, optional
        Harmonics fitted (fewer if they would pass Nyquist, with a warning).
    method : {"harmonic-ls", "interpolated-dft"}, optional
        Precise harmonic least squares, or the fast single-tone estimator applied to the strongest
        harmonic (frequency and sigma divided by its order).
    nan_policy : {"raise", "interpolate"}, optional
    quantum, decimation : float, optional
        The recorder's quantisation step in the units of ``x`` (default: inferred from ``x``'s levels)
        and the decimation since recording, for the search's noise floor (:func:`find_fundamental`).

    Returns
    -------
    LinkPassEstimate

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(20000) / 2000.0
    >>> x = 0.3 * np.cos(2 * np.pi * 3.75 * t) + np.cos(2 * np.pi * 7.5 * t)
    >>> round(link_pass_estimate(x, 2000.0, band=(2.0, 6.0)).fundamental_hz, 6)
    3.75
    """
    if method not in ("harmonic-ls", "interpolated-dft"):
        raise ValueError(f"Parameter method={method!r} must be 'harmonic-ls' or 'interpolated-dft'.")
    fs = check_fs(fs)
    x = as_signal(x, min_samples=8)
    x = fill_nan(x, nan_policy=nan_policy)
    kmax = check_positive_int(n_harmonics, "n_harmonics")
    fund = find_fundamental(x, fs, band=band, quantum=quantum, decimation=decimation)
    warnings = []
    # Only the harmonics matter: decimate long, fast-sampled records.  The anti-alias low-pass keeps only part of
    # the decimated band's white noise, so a fit that reads its noise density from its residual states a sigma
    # sqrt(fraction) too small: restated below as the recorded rate's (the same fit without the decimation).
    fs_recorded = fs
    x, fs, q = decimate_for_band(x, fs, (kmax + 0.5) * fund.frequency_hz)
    restate = 1.0 / np.sqrt(decimated_noise_fraction(fs_recorded, q))
    k_fit = min(kmax, int((fs / 2.0 * 0.999) // fund.frequency_hz))
    if k_fit < kmax:
        warnings.append(f"only {k_fit} of n_harmonics={kmax} lie below Nyquist ({fs / 2:g} Hz)")
    if k_fit < 1:
        raise ValueError(f"Parameter band={band!r}: the fundamental found lies above Nyquist.")
    # Strongest harmonic among those fitted, for a start within a fraction of a bin.
    snr = fund.harmonic_snr_db[:k_fit]
    h_star = int(np.argmax(snr)) + 1
    if np.max(snr) < 10.0:
        warnings.append(f"strongest harmonic only {np.max(snr):.1f} dB above the noise floor")
    fh = h_star * fund.frequency_hz
    half = min(fund.bin_hz, fh / 2.0)
    ide_band = (fh - half, min(fh + half, fs / 2.0))
    # harmonic least squares needs the interpolated DFT's frequency alone (its tone fit is a least squares of the
    # record's length: a second of CPU and 300 MB for 8 h at 200 Hz)
    ide = interpolated_dft(x, fs, band=ide_band) if method == "interpolated-dft" else None
    ide_hz = ide.frequency_hz if ide is not None else interpolated_frequency(x, fs, band=ide_band)
    if abs(ide_hz - fh) > fund.bin_hz:
        ide_f = fh
        warnings.append("interpolated DFT left the harmonic's bin; kept the harmonic-sum value")
    else:
        ide_f = ide_hz
    f_start = ide_f / h_star
    if method == "harmonic-ls":
        est = harmonic_ls(x, fs, f_guess=f_start, n_harmonics=k_fit)
        f0, sig = est.frequency_hz, est.sigma_hz
        amps, phases = est.amplitudes, est.phases
    else:
        assert ide is not None  # the method asked for it above
        est = ide
        f0, sig = ide_f / h_star, ide.sigma_hz / h_star
        fit = harmonic_ls(x, fs, f_guess=f0, n_harmonics=k_fit, max_iter=1)
        amps, phases = fit.amplitudes, fit.phases
    warnings += list(est.warnings)
    sig *= restate
    n = np.size(x)
    amp_sd = restate * est.noise_std * np.sqrt(2.0 / n)
    harmonics = [
        Harmonic(k + 1, (k + 1) * f0, float(amps[k]), float(phases[k]), bool(amps[k] > 3.0 * amp_sd))
        for k in range(k_fit)
    ]
    if not harmonics[0].detected:
        warnings.append("the fundamental itself is not detected; the family was identified by its harmonics")
    return LinkPassEstimate(f0, float(sig), harmonics, est.noise_std, est.snr_db, method, warnings, est, q)
