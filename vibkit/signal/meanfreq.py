"""The mean link-pass frequency over a record from the tracked phase, for chains whose speed wanders.

When the chain's speed wanders (load changes), each harmonic of the link-pass frequency is
frequency-modulated; for harmonic ``h`` the modulation index is ``h df / f_m`` (``df`` the frequency
excursion, ``f_m`` the wander rate), so the spectral sidebands of the higher harmonics can outgrow
their carriers and a spectral estimator (peak or harmonic least squares) is pulled towards a sideband.
The quantity the pitch needs is the *mean* link-pass frequency: the number of links that passed
divided by the time, ``(phi(T) - phi(0)) / (2 pi T)``, with ``phi`` the unwrapped link-pass phase.
:func:`mean_link_pass_frequency` tracks that phase (:func:`vibkit.signal.track_phase`: a spectrogram
ridge, then demodulation of each harmonic, combined with weights ``h**2 A_h**2``) and returns the
total phase over the time.

The tracker's filters are not trusted at the ends of the record: the phase there is corrected by a
least-squares fit of the harmonic family around the tracked phase over the first and last six
whole periods (``_end_phase``), whose covariance gives the two end-phase variances, and
``sigma_f = sqrt(var(phi_0) + var(phi_T)) / (2 pi T)``.

Stationarity: the tracked instantaneous frequency's spread (standard deviation over the record,
ends excluded) times the record length says how many spectral bins the line wanders over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._checks import as_signal, check_fs, check_positive_int
from .orders import track_phase

__all__ = ["MeanFrequency", "mean_link_pass_frequency"]

_BW_DIV = 20.0


@dataclass(frozen=True)
class MeanFrequency:
    """Result of :func:`mean_link_pass_frequency`.

    Attributes
    ----------
    frequency_hz : float
        Mean link-pass frequency: total unwrapped phase / (2 pi x span). [Hz]
    sigma_hz : float
        Its standard deviation (end-phase noise). [Hz]
    span_s : float
        Time between the first and last sample. [s]
    cycles : float
        Link passes counted over the span.
    spread_hz : float
        Standard deviation of the tracked instantaneous frequency (ends excluded). [Hz]
    spread_bins : float
        ``spread_hz x span_s``: how many spectral bins the line wanders over.
    bandwidth_hz : float
        Tracking bandwidth. [Hz]
    noise_spread_hz : float
        The spread that noise alone would give (no wander), from the noise around the tracked
        family. [Hz]
    """

    frequency_hz: float
    sigma_hz: float
    span_s: float
    cycles: float
    spread_hz: float
    spread_bins: float
    bandwidth_hz: float
    noise_spread_hz: float


END_PERIODS = 6
#: harmonics fitted at the ends at most (whole periods keep the others nearly orthogonal)
END_HARMONICS = 6


def _least_squares(mat, xs):
    """Normal-equation fit of xs on the columns of mat: (coefficients, (mat^T mat)^-1, residual),
    or None when the columns are degenerate."""
    g = mat.T @ mat
    try:
        coef = np.linalg.solve(g, mat.T @ xs)
        ginv = np.linalg.inv(g)
    except np.linalg.LinAlgError:
        return None
    return coef, ginv, xs - mat @ coef


#: rows of the record-wide fit :func:`_harmonic_phases` builds at a time (its sums accumulate over blocks: the
#: whole matrix was 2k + 1 columns of the record's length)
FIT_BLOCK_ROWS = 1 << 14


def _harmonic_phases(xs, ph, k):
    """Least squares ``c + sum_h a_h cos(h ph) + b_h sin(h ph)``: per-harmonic phase of the signal
    relative to ``h ph`` [rad], its variance [rad^2] and the amplitude.

    The normal equations are summed over blocks of :data:`FIT_BLOCK_ROWS` rows (memory independent of the
    record's length); a record of one block does exactly what the whole-matrix fit did.
    """
    n = xs.size
    blocks = [(i, min(n, i + FIT_BLOCK_ROWS)) for i in range(0, n, FIT_BLOCK_ROWS)]

    def design(i, j):
        cols = [np.ones(j - i)]
        for h in range(1, k + 1):
            cols += [np.cos(h * ph[i:j]), np.sin(h * ph[i:j])]
        return np.column_stack(cols)

    if len(blocks) == 1:
        mat = design(0, n)
        fit = _least_squares(mat, xs)
        if fit is None:
            return None
        coef, ginv, r = fit
        rr = float(r @ r)
    else:
        g, rhs = np.zeros((2 * k + 1, 2 * k + 1)), np.zeros(2 * k + 1)
        for i, j in blocks:
            mat = design(i, j)
            g += mat.T @ mat
            rhs += mat.T @ xs[i:j]
        try:
            coef = np.linalg.solve(g, rhs)
            ginv = np.linalg.inv(g)
        except np.linalg.LinAlgError:
            return None
        # numpy's pairwise sum per block (BLAS's threaded dot costs milliseconds a call on a busy machine)
        rr = sum(float(np.sum((xs[i:j] - design(i, j) @ coef) ** 2)) for i, j in blocks)
    s2 = rr / max(n - (2 * k + 1), 1)
    a, b = coef[1::2], coef[2::2]
    r2 = a * a + b * b
    var = 0.5 * (np.diag(ginv)[1::2] + np.diag(ginv)[2::2]) * s2 / np.maximum(r2, 1e-300)
    return -np.arctan2(b, a), var, np.sqrt(r2), s2


def _end_phase(x, phase, fs, k, ref, amp, *, start):
    """Correction of the tracked phase at one end of the record, and its variance. [rad], [rad^2]

    Over the first (last) ``END_PERIODS`` whole periods of the tracked phase, ``x`` is fitted with
    ``c + sum_h (a_h + a'_h u) cos(h phase) + (b_h + b'_h u) sin(h phase)`` (``u`` the time from the
    end): the tracked phase is right up to a slowly varying error, whose value at the end is, for
    every harmonic, its phase ``-atan2(b_h, a_h)`` there minus its record-wide value ``ref``, over
    ``h`` (combined with weights ``h^2 A_h^2``, ``A_h`` the record-wide amplitudes ``amp``).  The tracker's filters are not trusted at the ends;
    this fit is.
    """
    cyc = (phase - phase[0]) if start else (phase[-1] - phase)[::-1]
    m = int(np.searchsorted(cyc, 2 * np.pi * END_PERIODS))
    m = max(16, min(m, x.size // 3))
    sl = slice(0, m) if start else slice(x.size - m, x.size)
    xs, ph = x[sl], phase[sl]
    u = (np.arange(m) - (0 if start else m - 1)) / fs
    cols = [np.ones(m)]
    for h in range(1, k + 1):
        c, s_ = np.cos(h * ph), np.sin(h * ph)
        cols += [c, s_, u * c, u * s_]
    mat = np.column_stack(cols)
    fit = _least_squares(mat, xs)
    if fit is None:
        return 0.0, math.inf
    coef, ginv, r = fit
    s2 = float(r @ r) / max(m - mat.shape[1], 1)
    num, wsum = 0.0, 0.0
    for h in range(1, k + 1):
        i = 1 + 4 * (h - 1)
        a, b = coef[i], coef[i + 1]
        r2 = a * a + b * b
        # the record-wide amplitude, not the local one: a harmonic that is only noise gets no weight
        var_h = 0.5 * (ginv[i, i] + ginv[i + 1, i + 1]) * s2 / max(amp[h - 1] ** 2, 1e-300) / h**2
        if not (r2 > 0 and np.isfinite(var_h) and var_h > 0):
            continue
        d = float(np.angle(np.exp(1j * (-np.arctan2(b, a) - ref[h - 1])))) / h
        num += d / var_h
        wsum += 1.0 / var_h
    if wsum == 0:
        return 0.0, math.inf
    return num / wsum, 1.0 / wsum


def mean_link_pass_frequency(x, fs, *, f0, amplitudes=None, n_harmonics=3, max_deviation=0.05, bandwidth_hz=None):
    """Mean link-pass frequency over a record from the total tracked phase.

    Parameters
    ----------
    x : array_like, 1-D
        Signal with a link-pass harmonic family; finite. [x]
    fs : float
        Sampling frequency. [Hz]  Decimate long, fast records first (only the harmonics matter).
    f0 : float
        Approximate mean fundamental (e.g. from the spectral estimate). [Hz]
    amplitudes : array_like, optional
        Harmonic amplitudes ``A_1 .. A_K`` of a spectral fit: only their number ``K`` is used, as the
        number of harmonics fitted (at most ``END_HARMONICS``). [x]
    n_harmonics : int, optional
        Harmonics combined in the phase.
    max_deviation : float, optional
        Largest relative departure of the instantaneous frequency from ``f0``.
    bandwidth_hz : float, optional
        Tracking bandwidth; default ``f0 / 20``. [Hz]

    Returns
    -------
    MeanFrequency
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=16)
    kmax = check_positive_int(n_harmonics, "n_harmonics")
    f0 = float(f0)
    if not (math.isfinite(f0) and 0 < f0 < fs / 2):
        raise ValueError(f"Parameter f0={f0!r} must lie in (0, fs/2) Hz.")
    bw = f0 / _BW_DIV if bandwidth_hz is None else float(bandwidth_hz)
    band = (f0 * (1 - max_deviation / 2), min(f0 * (1 + max_deviation / 2), 0.49 * fs))
    tr = track_phase(x, fs, band=band, n_harmonics=kmax, bandwidth_hz=bw, max_deviation=max_deviation)
    n = x.size
    span = (n - 1) / fs
    n_amp = END_HARMONICS if amplitudes is None else np.size(amplitudes)
    k_fit = max(1, min(END_HARMONICS, n_amp, int((0.45 * fs) // (f0 * (1 + max_deviation)))))
    glob = _harmonic_phases(x, tr.phase_rad, k_fit)
    if glob is None:
        raise ValueError("the harmonic family could not be fitted around the tracked phase")
    d0, v0 = _end_phase(x, tr.phase_rad, fs, k_fit, glob[0], glob[2], start=True)
    d1, v1 = _end_phase(x, tr.phase_rad, fs, k_fit, glob[0], glob[2], start=False)
    dphi = float(tr.phase_rad[-1] + d1 - tr.phase_rad[0] - d0)
    f_mean = dphi / (2.0 * np.pi * span)
    sigma = math.sqrt(v0 + v1) / (2.0 * np.pi * span)
    # noise around the *tracked* family (a fixed-frequency fit's residual holds the wander itself)
    a, noise_var = glob[2], glob[3]
    h = np.arange(1, a.size + 1)
    s2 = float(np.sum(h**2 * a**2))
    var_phi = 4.0 * noise_var * bw / (fs * s2) if s2 > 0 else math.inf
    edge = min(int(fs / bw), n // 4)
    fi = tr.frequency_hz[edge : n - edge] if n - 2 * edge > 8 else tr.frequency_hz
    spread = float(np.std(fi))
    # spread that phase noise alone gives: flat phase noise over +-B has var(dphi/dt / 2 pi) = var(phi) B^2 / 3
    noise_spread = math.sqrt(var_phi / 3.0) * bw
    return MeanFrequency(
        float(f_mean), float(sigma), float(span), dphi / (2 * np.pi), spread, spread * span, bw, float(noise_spread)
    )
