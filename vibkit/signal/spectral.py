"""Spectra: amplitude spectrum, the study's power definition, Welch PSD with confidence, spectrogram, and a long
zero-padded power spectrum in rows of bounded memory.

All functions follow scipy.signal conventions: an array, ``fs`` [Hz], keyword-only options and
``axis=-1``.  Output units are stated relative to the input units ``[x]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal
import scipy.stats
from numpy.typing import ArrayLike

from ._checks import as_signal, check_fs, check_positive_int, check_window_length, fill_nan
from .estimate import expj

__all__ = [
    "amplitude_spectrum",
    "study_power_spectrum",
    "welch_psd",
    "WelchResult",
    "spectrogram",
    "welch_dof",
    "padded_power_rows",
]


def _window(window, n: int) -> np.ndarray:
    try:
        return scipy.signal.get_window(window, n, fftbins=True)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"Parameter window={window!r} is not a window scipy.signal.get_window knows: {exc}") from None


def amplitude_spectrum(
    x: ArrayLike,
    fs: float,
    *,
    window: str | tuple = "hann",
    nfft: int | None = None,
    detrend: str | bool = "constant",
    axis: int = -1,
    nan_policy: str = "raise",
) -> tuple[np.ndarray, np.ndarray]:
    """One-sided amplitude spectrum with window (coherent-gain) correction.

    A sine ``A sin(2 pi f t)`` whose frequency falls on a bin reads ``A`` at that bin.

    Parameters
    ----------
    x : array_like
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    window : str or tuple, optional
        Window accepted by :func:`scipy.signal.get_window`; ``"boxcar"`` for none.
    nfft : int, optional
        FFT length (zero padding); default the signal length.
    detrend : {"constant", "linear", False}, optional
        Trend removed before the window.
    axis : int, optional
        Time axis.
    nan_policy : {"raise", "interpolate"}, optional
        See :mod:`vibkit.signal._checks`.

    Returns
    -------
    f : ndarray
        Frequencies. [Hz]
    amplitude : ndarray
        Peak amplitude per bin. [x]

    Raises
    ------
    ValueError
        ``fs <= 0``, empty or all-NaN input, NaN under ``nan_policy="raise"``, ``nfft`` shorter
        than the signal.

    Notes
    -----
    ``A_k = c_k |X_k| / sum(w)`` with ``c_k = 2`` except at DC and Nyquist (``c_k = 1``).  With the
    boxcar window, Parseval reads ``mean(x**2) = A_0**2 + sum A_k**2 / 2 + A_{N/2}**2``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000) / 100.0
    >>> f, a = amplitude_spectrum(3.0 * np.sin(2 * np.pi * 5.0 * t), 100.0)
    >>> round(float(a[np.argmax(a)]), 6)
    3.0
    """
    fs = check_fs(fs)
    x = as_signal(x, axis=axis)
    x = fill_nan(x, nan_policy=nan_policy, axis=axis)
    x = np.moveaxis(x, axis, -1)
    n = x.shape[-1]
    if nfft is None:
        nfft = n
    nfft = check_positive_int(nfft, "nfft")
    if nfft < n:
        raise ValueError(f"Parameter nfft={nfft} is shorter than the signal ({n} samples); expected >= {n}.")
    if detrend:
        if detrend not in ("constant", "linear"):
            raise ValueError(f"Parameter detrend={detrend!r} must be 'constant', 'linear' or False.")
        x = scipy.signal.detrend(x, type=detrend, axis=-1)
    w = _window(window, n)
    spec = np.abs(np.fft.rfft(x * w, n=nfft, axis=-1)) / w.sum()
    spec[..., 1:] *= 2.0
    if nfft % 2 == 0:
        spec[..., -1] /= 2.0
    f = np.fft.rfftfreq(nfft, d=1.0 / fs)
    return f, np.moveaxis(spec, -1, axis)


def study_power_spectrum(y, fs, *, frequency_axis="study", axis=-1, nan_policy="raise"):
    """The study's "power" spectrum (its Table 14, MATLAB), for comparison with its figures.

    Parameters
    ----------
    y : array_like
        Signal. [y]
    fs : float
        Sampling frequency. [Hz]
    frequency_axis : {"study", "exact"}, optional
        ``"study"`` reproduces the study's axis ``f = linspace(0, fs/2, N)``; ``"exact"`` gives the
        true bin frequencies ``k fs / (2 N)`` of the ``2N``-point FFT.  They differ by the factor
        ``N / (N - 1)``, which the study's axis stretches.
    axis : int, optional
        Time axis.
    nan_policy : {"raise", "interpolate"}, optional
        See :mod:`vibkit.signal._checks`.

    Returns
    -------
    f : ndarray
        Frequencies. [Hz]
    power : ndarray
        ``|fft(y, 2N) / N|**2`` at the first ``N`` bins. [y**2]

    Notes
    -----
    Table 14: ``Y = fft(y, 2 N) / N``, ``Ym = abs(Y(1:N)).^2`` with ``N = length(t)``.  No window,
    no one-sided doubling: a sine of amplitude ``A`` on a bin reads ``A**2 / 4``, not the
    ``A**2 / 2`` of a power spectrum; use :func:`amplitude_spectrum` for calibrated amplitudes.

    References
    ----------
    The study (University of Seville, 2020), section 7.3.2, Table 14.
    """
    fs = check_fs(fs)
    y = as_signal(y, "y", axis=axis, min_samples=2)
    y = fill_nan(y, "y", nan_policy=nan_policy, axis=axis)
    if frequency_axis not in ("study", "exact"):
        raise ValueError(f"Parameter frequency_axis={frequency_axis!r} must be 'study' or 'exact'.")
    y = np.moveaxis(y, axis, -1)
    n = y.shape[-1]
    spec = np.fft.fft(y, n=2 * n, axis=-1)[..., :n] / n
    power = np.abs(spec) ** 2
    if frequency_axis == "study":
        f = np.linspace(0.0, fs / 2.0, n)
    else:
        f = np.arange(n) * fs / (2.0 * n)
    return f, np.moveaxis(power, -1, axis)


def welch_dof(window, nperseg: int, noverlap: int, nsegments: int) -> float:
    """Equivalent degrees of freedom of a Welch estimate (chi-square approximation).

    Notes
    -----
    ``nu = 2 K / (1 + 2 sum_{j=1}^{K-1} (1 - j/K) rho(j S)**2)`` with ``rho(m)`` the normalised
    window overlap correlation ``sum w_n w_{n+m} / sum w_n**2`` and ``S`` the hop
    (Percival & Walden 1993, eq. 292b).
    """
    w = _window(window, nperseg)
    step = nperseg - noverlap
    k = nsegments
    energy = np.sum(w * w)
    acc = 0.0
    for j in range(1, k):
        m = j * step
        if m >= nperseg:
            break
        rho = np.sum(w[:-m] * w[m:]) / energy
        acc += (1.0 - j / k) * rho * rho
    return 2.0 * k / (1.0 + 2.0 * acc)


@dataclass(frozen=True)
class WelchResult:
    """Welch PSD with chi-square confidence interval.

    Attributes
    ----------
    frequency_hz : ndarray
        Frequencies. [Hz]
    psd : ndarray
        One-sided power spectral density. [x**2/Hz]
    lower, upper : ndarray
        Confidence limits of the PSD at level ``confidence``. [x**2/Hz]
    dof : float
        Equivalent degrees of freedom.
    confidence : float
        Confidence level of ``lower``/``upper``.
    nperseg, noverlap, nsegments : int
        Segmentation used.
    """

    frequency_hz: np.ndarray
    psd: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    dof: float
    confidence: float
    nperseg: int
    noverlap: int
    nsegments: int

    def plot(self, ax=None, *, units: str = "x"):
        """The PSD on a log scale with its confidence band; ``units`` the signal's (the PSD's are units^2/Hz).

        Draws on ``ax`` (default a new figure's) and returns it. A 1-D result only (one PSD).
        """
        import matplotlib.pyplot as plt  # matplotlib only when a figure is asked for

        if np.ndim(self.psd) != 1:
            raise ValueError(f"plot draws one PSD; this result holds {np.shape(self.psd)[:-1]} of them")
        if ax is None:
            _, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
        f = self.frequency_hz
        ax.semilogy(f, self.psd, lw=0.8, color="C0", label=f"Welch PSD ({self.nsegments} segments)")
        ax.fill_between(
            f, self.lower, self.upper, color="C0", alpha=0.25, lw=0, label=f"{self.confidence:.0%} interval"
        )
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel(f"PSD [{units}^2/Hz]")
        ax.legend(loc="upper right", fontsize=8)
        return ax


def welch_psd(
    x: ArrayLike,
    fs: float,
    *,
    nperseg: int | None = None,
    noverlap: int | None = None,
    window: str | tuple = "hann",
    detrend: str | bool = "constant",
    confidence: float = 0.95,
    axis: int = -1,
    nan_policy: str = "raise",
) -> WelchResult:
    """Welch power spectral density with a chi-square confidence interval.

    Parameters
    ----------
    x : array_like
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    nperseg : int, optional
        Segment length; default ``min(n, 256)``.  Must not exceed the signal length.
    noverlap : int, optional
        Overlap; default ``nperseg // 2``.
    window, detrend : optional
        As :func:`scipy.signal.welch`.
    confidence : float, optional
        Level of the interval, in (0, 1).
    axis : int, optional
        Time axis.
    nan_policy : {"raise", "interpolate"}, optional
        See :mod:`vibkit.signal._checks`.

    Returns
    -------
    WelchResult

    Notes
    -----
    ``nu P / chi2_{nu}(1 - alpha/2) <= S <= nu P / chi2_{nu}(alpha/2)`` with ``nu`` from
    :func:`welch_dof`; the interval is for bins away from DC and Nyquist.  The integral of the PSD
    over frequency equals the variance of ``x``.

    References
    ----------
    P. D. Welch, IEEE Trans. Audio Electroacoust. 15 (1967) 70-73.
    D. B. Percival, A. T. Walden, Spectral Analysis for Physical Applications, CUP 1993.
    """
    fs, x, n, nperseg, noverlap = _segments(x, fs, nperseg, noverlap, nan_policy, axis)
    if not 0.0 < float(confidence) < 1.0:
        raise ValueError(f"Parameter confidence={confidence!r} must lie in (0, 1).")
    f, pxx = scipy.signal.welch(
        x, fs, window=window, nperseg=nperseg, noverlap=noverlap, detrend=detrend, axis=axis, scaling="density"
    )
    nseg = (n - noverlap) // (nperseg - noverlap)
    dof = welch_dof(window, nperseg, noverlap, nseg)
    alpha = 1.0 - float(confidence)
    lower = dof * pxx / scipy.stats.chi2.ppf(1.0 - alpha / 2.0, dof)
    upper = dof * pxx / scipy.stats.chi2.ppf(alpha / 2.0, dof)
    return WelchResult(f, pxx, lower, upper, float(dof), float(confidence), nperseg, int(noverlap), int(nseg))


def spectrogram(x, fs, *, nperseg=None, noverlap=None, window="hann", scaling="amplitude", axis=-1, nan_policy="raise"):
    """Short-time spectrum.

    Parameters
    ----------
    x : array_like
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    nperseg : int, optional
        Frame length; default ``min(n, 256)``.
    noverlap : int, optional
        Overlap; default ``nperseg // 2``.
    window : str or tuple, optional
        Frame window.
    scaling : {"amplitude", "density"}, optional
        ``"amplitude"``: peak amplitude as :func:`amplitude_spectrum` [x];
        ``"density"``: one-sided PSD [x**2/Hz].
    axis : int, optional
        Time axis.
    nan_policy : {"raise", "interpolate"}, optional
        See :mod:`vibkit.signal._checks`.

    Returns
    -------
    f : ndarray
        Frequencies. [Hz]
    t : ndarray
        Frame centres from the first sample. [s]
    sxx : ndarray
        Spectrogram, frequency then time as the last two axes.
    """
    fs, x, n, nperseg, noverlap = _segments(x, fs, nperseg, noverlap, nan_policy, axis)
    if scaling not in ("amplitude", "density"):
        raise ValueError(f"Parameter scaling={scaling!r} must be 'amplitude' or 'density'.")
    if scaling == "density":
        return scipy.signal.spectrogram(
            x, fs, window=window, nperseg=nperseg, noverlap=noverlap, axis=axis, scaling="density", mode="psd"
        )
    f, t, mag = scipy.signal.spectrogram(
        x, fs, window=window, nperseg=nperseg, noverlap=noverlap, axis=axis, mode="magnitude", scaling="spectrum"
    )
    # mode="magnitude" with scaling="spectrum" gives |X| / sum(w); make it one-sided peak amplitude.
    mag = np.array(mag)
    mag[..., 1:, :] *= 2.0
    if nperseg % 2 == 0:
        mag[..., -1, :] /= 2.0
    return f, t, mag


def _segments(x, fs, nperseg, noverlap, nan_policy, axis):
    """Checked (fs, x, n, nperseg, noverlap) shared by the segment-averaging spectra."""
    fs = check_fs(fs)
    x = as_signal(x, axis=axis, min_samples=2)
    x = fill_nan(x, nan_policy=nan_policy, axis=axis)
    n = x.shape[axis]
    if nperseg is None:
        nperseg = min(n, 256)
    nperseg = check_window_length(nperseg, n)
    if noverlap is None:
        noverlap = nperseg // 2
    if isinstance(noverlap, bool) or not isinstance(noverlap, (int, np.integer)) or not 0 <= noverlap < nperseg:
        raise ValueError(f"Parameter noverlap={noverlap!r} must be an integer in [0, nperseg={nperseg}).")
    return fs, x, n, nperseg, noverlap


def padded_power_rows(y, nfft: int, row_bins: int):
    """The power ``|rfft(y, nfft)|^2`` of bins ``0 .. nfft / 2`` by rows of the four-step FFT (``nfft = P M``,
    ``M = row_bins``; ``M`` dividing ``nfft``, ``y.size <= nfft``): for ``r = 0 .. P / 2``, the bins ``k = r + P m``
    are one ``M``-point FFT of ``sum_l y_l exp(-2 pi i l r / P)`` (``y_l`` the record's ``l``-th block of ``M``
    samples, zero padded) times ``exp(-2 pi i j r / nfft)`` (``j = 0 .. M - 1``): the DFT's sum split as
    ``j + M l``; the same row read backwards holds the bins ``k = P - r + P m`` (``y`` is real: bin ``nfft - k`` is
    bin ``k``'s conjugate).  Yields ``(s, power)`` with ``power[m]`` the bin ``s + P m``, for every residue ``s``
    of ``P`` and the bins up to ``nfft / 2``; memory is a few rows of ``M`` values, whatever ``nfft``."""
    y = np.asarray(y, dtype=float)
    nfft, row_bins = int(nfft), int(row_bins)
    if y.ndim != 1 or not (0 < row_bins < nfft and nfft % row_bins == 0 and y.size <= nfft):
        raise ValueError(
            f"padded_power_rows needs a 1-D record of at most nfft={nfft} samples and a row length dividing nfft "
            f"(row_bins={row_bins}, record {y.shape})"
        )
    return _power_rows(y, nfft, row_bins)


def _power_rows(y, nfft, row_bins):
    """The generator of :func:`padded_power_rows` (its arguments checked)."""
    n = y.size
    p_rows = nfft // row_bins
    blocks = [y[i : i + row_bins] for i in range(0, n, row_bins)]
    j = np.arange(row_bins, dtype=float)
    for r in range(p_rows // 2 + 1):
        acc = np.zeros(row_bins, dtype=complex)
        for ell, blk in enumerate(blocks):
            w = complex(np.cos(2.0 * np.pi * ell * r / p_rows), -np.sin(2.0 * np.pi * ell * r / p_rows))
            acc[: blk.size] += w * blk
        acc *= expj((-2.0 * np.pi * r / nfft) * j)
        c = np.fft.fft(acc)
        del acc
        pw = np.abs(c)
        del c
        np.square(pw, out=pw)
        yield r, pw[: (nfft // 2 - r) // p_rows + 1]
        if 0 < 2 * r < p_rows:  # bin P - r + P m is bin nfft - (P - r + P m) = r + P (M - 1 - m) conjugated
            s = p_rows - r
            yield s, pw[::-1][: (nfft // 2 - s) // p_rows + 1]
