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

Uncertainty: the total phase is the difference of two phase estimates, each with variance
``var(phi) = 4 sigma**2 B / (fs sum_h h**2 A_h**2)`` (``sigma`` the noise standard deviation, ``B`` the
tracking bandwidth, ``A_h`` the harmonic amplitudes), so
``sigma_f = sqrt(2 var(phi)) / (2 pi T)``.

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
        The spread that noise alone would give (no wander). [Hz]
    """

    frequency_hz: float
    sigma_hz: float
    span_s: float
    cycles: float
    spread_hz: float
    spread_bins: float
    bandwidth_hz: float
    noise_spread_hz: float


def mean_link_pass_frequency(x, fs, *, f0, amplitudes, noise_std, n_harmonics=3, max_deviation=0.05,
                             bandwidth_hz=None):
    """Mean link-pass frequency over a record from the total tracked phase.

    Parameters
    ----------
    x : array_like, 1-D
        Signal with a link-pass harmonic family; finite. [x]
    fs : float
        Sampling frequency. [Hz]  Decimate long, fast records first (only the harmonics matter).
    f0 : float
        Approximate mean fundamental (e.g. from the spectral estimate). [Hz]
    amplitudes : array_like
        Harmonic amplitudes ``A_1 .. A_K`` (from a harmonic fit), for the sigma. [x]
    noise_std : float
        Noise standard deviation at ``fs``, for the sigma. [x]
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
    dphi = float(tr.phase_rad[-1] - tr.phase_rad[0])
    f_mean = dphi / (2.0 * np.pi * span)
    a = np.asarray(amplitudes, dtype=float)[: len(tr.harmonics_used)]
    h = np.arange(1, a.size + 1)
    s2 = float(np.sum(h**2 * a**2))
    var_phi = 4.0 * float(noise_std) ** 2 * bw / (fs * s2) if s2 > 0 else math.inf
    sigma = math.sqrt(2.0 * var_phi) / (2.0 * np.pi * span)
    edge = min(int(fs / bw), n // 4)
    fi = tr.frequency_hz[edge:n - edge] if n - 2 * edge > 8 else tr.frequency_hz
    spread = float(np.std(fi))
    # spread that phase noise alone gives: flat phase noise over +-B has var(dphi/dt / 2 pi) = var(phi) B^2 / 3
    noise_spread = math.sqrt(var_phi / 3.0) * bw
    return MeanFrequency(float(f_mean), float(sigma), float(span), dphi / (2 * np.pi), spread, spread * span, bw,
                         float(noise_spread))
