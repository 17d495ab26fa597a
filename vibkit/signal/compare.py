"""Spectrum comparison of a simulated and a measured signal that are not time-synchronous.

Each signal is referred to its own link-pass fundamental (order domain), so start times, record
lengths and sampling rates may differ.  The per-harmonic table gives frequency ratios and
amplitude differences with confidence intervals; the log-spectral distance and an agreement
score summarise it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats

from ._checks import as_signal, check_fs, check_positive_int, fill_nan
from .estimate import interpolated_dft
from .orders import order_spectrum, resample_to_angle
from .peaks import link_pass_estimate
from .spectral import spectrogram

__all__ = ["compare_spectra", "SpectrumComparison", "HarmonicComparison", "common_spectrograms"]

SCORE_RULE = (
    "score = mean over harmonics detected in either signal of "
    "exp(-((f_ratio - 1) / freq_tol)**2 / 2 - (amp_diff_db / amp_tol_db)**2 / 2); "
    "a harmonic missing from one signal scores 0; 1 is perfect agreement"
)


@dataclass(frozen=True)
class HarmonicComparison:
    """One row of the per-harmonic table (measured relative to simulated).

    Attributes
    ----------
    order : int
    frequency_sim_hz, frequency_meas_hz : float
        Harmonic frequencies, each fitted on its own signal. [Hz]
    frequency_ratio : float
        ``frequency_meas_hz / frequency_sim_hz``.
    frequency_ratio_ci : (float, float)
        Simultaneous confidence interval of the ratio (Cramer-Rao sigmas, normal, Bonferroni over
        the harmonics of the table).
    order_sim, order_meas : float
        Harmonic frequency over its own signal's fundamental: departs from ``order`` for a
        component that is not a true harmonic.
    amplitude_sim, amplitude_meas : float
        Peak amplitudes. [x]
    amplitude_diff_db : float
        ``20 log10(amplitude_meas / amplitude_sim)``. [dB]
    amplitude_diff_db_ci : (float, float)
        Its confidence interval. [dB]
    detected_sim, detected_meas : bool
    frequency_mismatch : bool
        ``frequency_ratio_ci`` excludes 1 (both detected).
    """

    order: int
    frequency_sim_hz: float
    frequency_meas_hz: float
    frequency_ratio: float
    frequency_ratio_ci: tuple
    order_sim: float
    order_meas: float
    amplitude_sim: float
    amplitude_meas: float
    amplitude_diff_db: float
    amplitude_diff_db_ci: tuple
    detected_sim: bool
    detected_meas: bool
    frequency_mismatch: bool


@dataclass(frozen=True)
class SpectrumComparison:
    """Result of :func:`compare_spectra`.

    Attributes
    ----------
    harmonics : list of HarmonicComparison
    fundamental_sim_hz, fundamental_meas_hz : float
        [Hz]
    log_spectral_distance_db : float
        RMS of ``20 log10(A_meas / A_sim)`` over the common order axis. [dB]
    score : float
        Agreement in [0, 1]; see ``rule``.
    rule : str
    orders : ndarray
        Common order axis.
    amplitude_sim, amplitude_meas : ndarray
        Order spectra on that axis. [x]
    confidence : float
    """

    harmonics: list
    fundamental_sim_hz: float
    fundamental_meas_hz: float
    log_spectral_distance_db: float
    score: float
    rule: str
    orders: np.ndarray
    amplitude_sim: np.ndarray
    amplitude_meas: np.ndarray
    confidence: float

    @property
    def any_frequency_mismatch(self) -> bool:
        """True if any harmonic's frequency ratio differs from 1 at the stated confidence."""
        return any(h.frequency_mismatch for h in self.harmonics)


def _per_harmonic(x, fs, est):
    """Each harmonic's own frequency (others subtracted), sigma, amplitude and its sigma."""
    n = x.size
    t = np.arange(n) / fs
    f0 = est.fundamental_hz
    fitted = [h.amplitude * np.cos(2 * np.pi * h.frequency_hz * t + h.phase_rad) for h in est.harmonics]
    total = np.sum(fitted, axis=0) + est.estimate.offset
    rows = []
    for k, h in enumerate(est.harmonics):
        xh = x - total + fitted[k]
        tone = interpolated_dft(xh, fs, f_guess=h.order * f0)
        amp_sd = est.noise_std * np.sqrt(2.0 / n)
        rows.append((tone.frequency_hz, tone.sigma_hz, tone.amplitudes[0], amp_sd, h.detected))
    return rows


def _order_axis_spectrum(x, fs, f0, spc):
    phase = 2.0 * np.pi * f0 * np.arange(x.size) / fs
    return order_spectrum(resample_to_angle(x, fs, phase, samples_per_cycle=spc))


def compare_spectra(
    x_sim,
    fs_sim,
    x_meas,
    fs_meas,
    *,
    band=(2.0, 6.0),
    n_harmonics=5,
    confidence=0.95,
    freq_tol=0.01,
    amp_tol_db=3.0,
    nan_policy="raise",
):
    """Compare a simulated and a measured signal in the order domain, harmonic by harmonic.

    Parameters
    ----------
    x_sim, x_meas : array_like, 1-D
        Simulated and measured signals, same quantity and units. [x]
    fs_sim, fs_meas : float
        Their sampling frequencies. [Hz]
    band : (float, float), optional
        Plausible link-pass range for both. [Hz]
    n_harmonics : int, optional
        Harmonics compared.
    confidence : float, optional
        Level of the intervals.
    freq_tol : float, optional
        Relative frequency difference scale of the score (see ``rule``).
    amp_tol_db : float, optional
        Amplitude difference scale of the score. [dB]
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    SpectrumComparison

    Notes
    -----
    Fundamental and harmonic amplitudes come from :func:`vibkit.signal.link_pass_estimate`
    (harmonic least squares) on each signal.  Each harmonic's own frequency is re-estimated with
    the other fitted harmonics subtracted, its sigma the Cramer-Rao bound; the ratio's interval is
    ``ratio (1 +- z sqrt((s_m/f_m)**2 + (s_s/f_s)**2))`` with ``z`` the Bonferroni-corrected normal
    quantile, so the family-wise false-mismatch rate is at most ``1 - confidence``.  Amplitude sigmas are
    ``noise_std sqrt(2/N)``.  The order spectra assume constant speed within each record (use
    :func:`vibkit.signal.track_phase` and :func:`vibkit.signal.order_spectrum` otherwise).
    """
    fs_sim = check_fs(fs_sim, "fs_sim")
    fs_meas = check_fs(fs_meas, "fs_meas")
    xs = fill_nan(as_signal(x_sim, "x_sim", min_samples=8), "x_sim", nan_policy=nan_policy)
    xm = fill_nan(as_signal(x_meas, "x_meas", min_samples=8), "x_meas", nan_policy=nan_policy)
    kmax = check_positive_int(n_harmonics, "n_harmonics")
    if not 0.0 < float(confidence) < 1.0:
        raise ValueError(f"Parameter confidence={confidence!r} must lie in (0, 1).")
    if not float(freq_tol) > 0 or not float(amp_tol_db) > 0:
        raise ValueError("Parameters freq_tol and amp_tol_db must be positive.")
    es = link_pass_estimate(xs, fs_sim, band=band, n_harmonics=kmax)
    em = link_pass_estimate(xm, fs_meas, band=band, n_harmonics=kmax)
    k = min(len(es.harmonics), len(em.harmonics))
    rs = _per_harmonic(xs, fs_sim, es)[:k]
    rm = _per_harmonic(xm, fs_meas, em)[:k]
    # Simultaneous (Bonferroni) intervals over the k harmonics: the chance that any row of a
    # matching pair is flagged stays below 1 - confidence.
    z = float(scipy.stats.norm.ppf(1.0 - (1.0 - float(confidence)) / (2.0 * k)))
    table = []
    scores = []
    for i in range(k):
        fs_h, ss_h, as_h, sas, ds = rs[i]
        fm_h, sm_h, am_h, sam, dm = rm[i]
        ratio = fm_h / fs_h
        rel = np.hypot(sm_h / fm_h, ss_h / fs_h)
        ci = (ratio * (1 - z * rel), ratio * (1 + z * rel))
        diff_db = 20 * np.log10(max(am_h, 1e-300) / max(as_h, 1e-300))
        sd_db = 20 / np.log(10) * np.hypot(sam / max(am_h, 1e-300), sas / max(as_h, 1e-300))
        mismatch = bool(ds and dm and not ci[0] <= 1.0 <= ci[1])
        table.append(
            HarmonicComparison(
                i + 1,
                float(fs_h),
                float(fm_h),
                float(ratio),
                (float(ci[0]), float(ci[1])),
                float(fs_h / es.fundamental_hz),
                float(fm_h / em.fundamental_hz),
                float(as_h),
                float(am_h),
                float(diff_db),
                (float(diff_db - z * sd_db), float(diff_db + z * sd_db)),
                bool(ds),
                bool(dm),
                mismatch,
            )
        )
        if ds or dm:
            if ds and dm:
                scores.append(np.exp(-0.5 * ((ratio - 1) / freq_tol) ** 2 - 0.5 * (diff_db / amp_tol_db) ** 2))
            else:
                scores.append(0.0)
    score = float(np.mean(scores)) if scores else 0.0
    spc = int(2 ** np.ceil(np.log2(2 * (k + 1) + 2)))
    os_, a_s = _order_axis_spectrum(xs, fs_sim, es.fundamental_hz, spc)
    om, a_m = _order_axis_spectrum(xm, fs_meas, em.fundamental_hz, spc)
    step = max(os_[1] - os_[0], om[1] - om[0])
    orders = np.arange(0.5, k + 0.5 + step / 2, step)
    ia = np.interp(orders, os_, a_s)
    ib = np.interp(orders, om, a_m)
    floor = 1e-12 * max(ia.max(), ib.max(), 1e-300)
    lsd = float(np.sqrt(np.mean((20 * np.log10((ib + floor) / (ia + floor))) ** 2)))
    return SpectrumComparison(
        table, es.fundamental_hz, em.fundamental_hz, lsd, score, SCORE_RULE, orders, ia, ib, float(confidence)
    )


def common_spectrograms(x_sim, fs_sim, x_meas, fs_meas, *, fmax, frame_s, overlap=0.5):
    """Spectrograms of two signals on one frequency axis and a time axis from each record's start.

    Parameters
    ----------
    x_sim, x_meas : array_like, 1-D
        Signals. [x]
    fs_sim, fs_meas : float
        Sampling frequencies. [Hz]
    fmax : float
        Highest frequency shown; must lie below both Nyquist frequencies. [Hz]
    frame_s : float
        Frame length, the same in seconds for both (same resolution). [s]
    overlap : float, optional
        Frame overlap fraction.

    Returns
    -------
    dict
        ``frequency_hz`` (common), ``time_sim_s``, ``time_meas_s``, ``amplitude_sim``,
        ``amplitude_meas`` (peak amplitude [x], frequency by time), ``db_range`` (common colour
        limits, 60 dB below the larger maximum).
    """
    fs_sim = check_fs(fs_sim, "fs_sim")
    fs_meas = check_fs(fs_meas, "fs_meas")
    fmax = float(fmax)
    if not 0 < fmax <= min(fs_sim, fs_meas) / 2:
        raise ValueError(f"Parameter fmax={fmax!r} must lie in (0, {min(fs_sim, fs_meas) / 2:g}] Hz (both Nyquists).")
    if not float(frame_s) > 0:
        raise ValueError(f"Parameter frame_s={frame_s!r} must be positive [s].")
    out = {}
    df = 1.0 / float(frame_s)
    fgrid = np.arange(0.0, fmax + df / 2, df / 2)
    for name, x, fs in (("sim", x_sim, fs_sim), ("meas", x_meas, fs_meas)):
        nper = int(round(float(frame_s) * fs))
        f, t, s = spectrogram(x, fs, nperseg=nper, noverlap=int(overlap * nper))
        out[f"time_{name}_s"] = t
        out[f"amplitude_{name}"] = np.stack([np.interp(fgrid, f, s[:, j]) for j in range(s.shape[1])], axis=1)
    out["frequency_hz"] = fgrid
    top = 20 * np.log10(max(out["amplitude_sim"].max(), out["amplitude_meas"].max(), 1e-300))
    out["db_range"] = (top - 60.0, top)
    return out
