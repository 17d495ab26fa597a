"""One steady spectral line seen by several channels at once: detection with a stated false-alarm bound,
frequency with a sigma that holds.

A phone on an escalator step (or in the hand of someone standing on one) records the chain's link pass as
one narrow line, often without harmonics, on some of its accelerometer and gyroscope axes and not on others.
:func:`steady_line` looks for it in all the channels together.

Statistic
---------
Each channel is linearly detrended, Hann-windowed over the whole record and transformed (zero-padded
``pad`` times).  Its periodogram is divided by a running median over +-``floor_halfwidth_hz`` and by
``ln 2`` (the median of an exponential law), so that a bin of Gaussian noise with a spectrum smooth on
that scale is Exp(1) distributed (mean 1).  The channels' normalised periodograms are averaged:
``T(f) = mean_c R_c(f)``.  A steady line adds ``N A_c**2 / (4 S_c)`` to its channels' bins (``N``
samples, amplitude ``A_c``, one-sided noise density ``S_c``): the whole record integrates coherently,
which a Welch average of short segments does not.

False alarms
------------
The axes of one sensor see the same handling noise, so the channels are not independent.  Under the null
(Gaussian noise with a spectrum smooth over the floor's width) the channels' whitened transforms at one
frequency are complex Gaussian with the channels' coherence matrix ``G`` (estimated from 4 s segments near
the line, the line's own bins left out); the sum ``C T(f)`` is then distributed as ``sum_i g_i E_i``,
``E_i`` independent Exp(1) and ``g_i`` the eigenvalues of ``G``, whose tail is a mixture of exponentials.  The
floor's own estimation error is integrated out by its exact law: a bin that stands over the median of its
``2 h + 1``-bin window leaves the median to the ``h + 1``-th smallest of the ``2 h`` others, an order statistic of
exponentials whose Laplace transform is a finite product (Renyi's representation), so ``E[exp(-a floor)]`` and
with it the mixture's tail are exact.  The window's bins are correlated (a Hann window's neighbours share 4/9 of
their power): its law is taken as that of :data:`FLOOR_CORRELATION` times fewer independent bins, times two thirds
of the channels' effective number for their mean.  Over the band's ``M = (f_hi - f_lo) * duration`` independent
frequencies the chance that noise alone reaches ``T`` anywhere is at most ``M`` times that (union bound), times
:data:`GRID_FACTOR` for the maximum taken over the zero-padded grid.  Both constants are measured against a Monte
Carlo of Gaussian noise (``benchmarks/bench_steadyline_null.py``: the bound holds at 8-30 s and is 1.7-5 times the
measured rate at 12-13 dB; the Gaussian law of the floor's error it replaces stated 2-80 times it, 2-3.5 dB of
threshold on one channel at 10-20 s).  A line that only one or two axes of six carry is diluted in the mean, so the
strongest single channel is tested as well (at most ``C`` times one channel's tail per frequency), and the two
tests share ``p_fa`` (Bonferroni).
The line is *detected* when the smaller p-value, doubled, is under ``p_fa``.  The bound assumes Gaussian
noise, which handling transients are not: :mod:`vibkit.diagnose.rides` therefore tests only where the
walking band is quiet, and the false-alarm rate on real walks is measured
(``benchmarks/bench_phone_rides.py``).

A line must also be *steady*: present in each of ``parts`` equal parts of the record, near the same
frequency.  Each part's frequency is sought within +-``steady_tolerance`` of the whole record's; a part
whose level there is under ``part_min_db`` fails the record.

Frequency and its sigma
-----------------------
The frequency is the maximum of ``sum_c |X_c(f)|**2 / S_c(f)`` (the noise-weighted periodogram,
the maximum-likelihood estimate of one common frequency in channels with independent coloured noise),
refined on the discrete-time Fourier transform (a grid closing in on the maximum, then a parabola).  Its formal sigma is the
Cramer-Rao bound of a tone, combined over the channels (``1 / sigma**2 = sum_c 1 / sigma_c**2``) with each
channel's signal-to-noise ratio read from its normalised periodogram.  A real ride's line is not a
stationary tone (the chain speeds up and slows down with its load; stepping on and off), so the stated
sigma is the formal one scaled by ``sqrt(max(1, Birge ratio))`` of the parts' frequencies against their
own formal sigmas, and never less than the parts' standard error: the record's own scatter wherever it
is larger than the formal bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage, signal

from ._checks import check_fs

__all__ = ["SteadyLine", "steady_line", "line_level", "normalised_spectrum"]

#: Hann window: peak-to-floor ratio of a tone relative to a rectangular window (coherent gain**2 / ENBW
#: factor, 0.25 / 0.375)
_HANN_GAIN = 2.0 / 3.0


@dataclass(frozen=True)
class SteadyLine:
    """What :func:`steady_line` found.

    Attributes
    ----------
    detected : bool
        A steady line stands over the noise with false-alarm probability under ``p_fa``.
    frequency_hz, sigma_hz : float
        The line's frequency and its stated standard uncertainty [Hz] (NaN when nothing stands out).
    formal_sigma_hz : float
        The Cramer-Rao bound alone [Hz].
    level_db : float
        ``T`` at the line: the channels' mean normalised periodogram, dB over the floor.
    threshold_db : float
        The level that the false-alarm bound ``p_fa`` requires [dB].
    p_value : float
        The bound on the chance that noise alone reaches ``level_db`` somewhere in the band.
    channel_levels_db : tuple of float
        Each channel's normalised periodogram at the line [dB].
    parts_hz, parts_sigma_hz : tuple of float
        The frequency found in each part of the record, and its formal sigma [Hz].
    birge_ratio : float
        The parts' scatter against their formal sigmas (chi-square over degrees of freedom).
    duration_s : float
        Length of the record analysed [s].
    band : tuple of float
        The band searched [Hz].
    reason : str
        Why the line is not detected ("" when it is).
    failed_part : int
        The part (0-based) that does not show the line, -1 where none failed.
    """

    detected: bool
    frequency_hz: float
    sigma_hz: float
    formal_sigma_hz: float
    level_db: float
    threshold_db: float
    p_value: float
    channel_levels_db: tuple = field(default=())
    parts_hz: tuple = field(default=())
    parts_sigma_hz: tuple = field(default=())
    birge_ratio: float = float("nan")
    duration_s: float = float("nan")
    band: tuple = (float("nan"), float("nan"))
    reason: str = ""
    failed_part: int = -1  # the part (0-based) that does not show the line, -1 where none failed

    @property
    def strongest_channel(self) -> int:
        """Index of the channel with the most evidence for the line (its highest level)."""
        return int(np.argmax(self.channel_levels_db)) if self.channel_levels_db else -1


def _detrend(x):
    """Each channel less its least-squares line."""
    n = x.shape[-1]
    t = np.arange(n) - (n - 1) / 2.0
    x = x - x.mean(axis=-1, keepdims=True)
    return x - np.outer(x @ t / (t @ t), t)


def _spectra(x, fs, pad, floor_halfwidth_hz):
    """(frequencies [Hz], complex spectra C x F, floors C x F, normalised periodograms C x F).

    The floor is the running median of the unpadded bins (every ``pad``-th, independent under the null),
    interpolated onto the padded ones."""
    x = _detrend(x)
    n = x.shape[-1]
    nfft = 1 << int(math.ceil(math.log2(n * pad)))
    step = max(nfft // n, 1)
    z = np.fft.rfft(x * np.hanning(n), nfft, axis=-1)
    p = np.abs(z) ** 2
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    half = max(int(round(floor_halfwidth_hz / (f[1] * step))), 2)
    coarse = ndimage.median_filter(p[:, ::step], size=(1, 2 * half + 1), mode="nearest") / math.log(2.0)
    floor = np.stack([np.interp(f, f[::step], row) for row in coarse])
    floor = np.maximum(floor, np.finfo(float).tiny + 1e-300 * p.max(initial=0.0))
    return f, z, floor, p / floor


def _coherence(x, fs, f0, halfwidth_hz, exclude_hz):
    """The channels' spectral coherence matrix near ``f0`` (each channel whitened by its own level), from 4 s
    Hann segments at the bins within +-``halfwidth_hz`` of ``f0`` but farther than ``exclude_hz`` from it."""
    c, n = x.shape
    nseg = min(n, max(int(round(4.0 * fs)), 16))
    f, _, z = signal.stft(
        x, fs, window="hann", nperseg=nseg, noverlap=nseg // 2, detrend="linear", boundary=None, padded=False
    )
    sel = (np.abs(f - f0) <= halfwidth_hz) & (np.abs(f - f0) > exclude_hz)
    if not np.any(sel):
        return np.eye(c)
    zs = z[:, sel, :]
    zs = zs / np.sqrt(np.mean(np.abs(zs) ** 2, axis=2, keepdims=True) + 1e-300)
    v = zs.reshape(c, -1)
    g = (v @ v.conj().T).real / v.shape[1]
    d = np.sqrt(np.clip(np.diag(g), 1e-300, None))
    return g / np.outer(d, d)


def _mixture(eig):
    """(rates ``lam``, weights ``w``) with ``P(sum_i eig_i E_i > s) = sum_i w_i exp(-s / lam_i)``, ``E_i`` independent
    Exp(1): the sum of the channels' whitened periodograms when their noise has the coherence matrix whose eigenvalues
    are ``eig``.  Eigenvalues closer than 3 % are spread upward (larger eigenvalues only lengthen the tail: the
    probability stays a bound)."""
    lam = np.sort(np.clip(np.asarray(eig, dtype=float), 1e-3, None))[::-1]
    for i in range(lam.size - 2, -1, -1):
        lam[i] = max(lam[i], 1.03 * lam[i + 1])
    ratio = lam[:, None] / (lam[:, None] - lam[None, :] + np.eye(lam.size))
    np.fill_diagonal(ratio, 1.0)
    return lam, np.prod(ratio, axis=1)


def _refine(x, fs, f0, df, weights):
    """The maximum of the weighted DTFT power of the Hann-windowed channels within +-df of f0: three rounds of
    17 frequencies each, closing in on the best, then a parabola through the last three."""
    n = x.shape[-1]
    xw = _detrend(x) * np.hanning(n)
    t = np.arange(n) / fs
    lo, hi = f0 - df, f0 + df
    for _ in range(4):
        grid = np.linspace(lo, hi, 17)
        pw = weights @ (np.abs(xw @ np.exp(-2j * np.pi * np.outer(t, grid))) ** 2)
        k = int(np.argmax(pw))
        if 0 < k < grid.size - 1:
            y0, y1, y2 = pw[k - 1 : k + 2]
            den = y0 - 2 * y1 + y2
            best = grid[k] + (0.5 * (y0 - y2) / den * (grid[1] - grid[0]) if den < 0 else 0.0)
        else:
            best = grid[k]
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    return float(best)


def _formal_sigma(excess, n, fs):
    """Cramer-Rao sigma [Hz] of one tone whose Hann periodogram stands ``excess`` (ratio - 1) over the floor,
    combined over the channels.  Rectangular-window peak-to-floor ``rho = N SNR / 2`` (SNR = A**2 / (2
    sigma**2) per sample), so ``var f = 6 fs**2 / ((2 pi)**2 N**3 SNR) = 3 fs**2 / ((2 pi)**2 N**2 rho)``."""
    rho = np.asarray(excess, dtype=float) / _HANN_GAIN
    rho = rho[rho > 0]
    if rho.size == 0:
        return float("inf")
    info = np.sum(rho) * (2.0 * np.pi * n / fs) ** 2 / 3.0
    return float(1.0 / math.sqrt(info))


def _estimate(x, fs, f_near, search_hz, pad, floor_halfwidth_hz):
    """(frequency [Hz], formal sigma [Hz], T at it, per-channel normalised levels) near ``f_near``."""
    f, z, floor, r = _spectra(x, fs, pad, floor_halfwidth_hz)
    t = r.mean(axis=0)
    sel = np.flatnonzero(np.abs(f - f_near) <= search_hz)
    if sel.size == 0:
        sel = np.array([int(np.argmin(np.abs(f - f_near)))])
    j = sel[int(np.argmax(t[sel]))]
    weights = 1.0 / floor[:, j]
    fr = _refine(x, fs, f[j], 1.5 * f[1], weights)
    levels = r[:, j]
    sigma = _formal_sigma(levels - 1.0, x.shape[-1], fs)
    return fr, sigma, float(t[j]), levels


def steady_line(
    x,
    fs,
    *,
    band,
    p_fa=1e-3,
    parts=3,
    pad=4,
    floor_halfwidth_hz=1.0,
    steady_tolerance=0.02,
    part_min_db=1.5,
) -> SteadyLine:
    """Find one steady spectral line common to the channels of ``x`` (see the module's notes).

    Parameters
    ----------
    x : array_like, shape (C, N) or (N,)
        The channels, sampled uniformly at ``fs`` (any units; each channel is normalised by its own floor).
    fs : float
        Sample rate [Hz].
    band : (float, float)
        Where the line may be [Hz].
    p_fa : float
        Bound on the false-alarm probability of the whole search (default 1e-3).
    parts : int
        The record is cut into this many equal parts; the line must be present in each (default 3).
    pad : int
        Zero-padding factor of the transforms (default 4).
    floor_halfwidth_hz : float
        Half-width of the running median that estimates the noise floor [Hz] (default 1).
    steady_tolerance : float
        Relative distance from the record's frequency within which each part's line is sought (default 2 %: a
        passenger slows the chain by 1-2 %).
    part_min_db : float
        Level a part's line must reach at that frequency [dB over its floor] (default 1.5).

    Returns
    -------
    SteadyLine
    """
    fs = check_fs(fs)
    x = np.atleast_2d(np.asarray(x, dtype=float))
    if not np.all(np.isfinite(x)):
        raise ValueError("x holds NaN or infinite samples; expected finite samples (cut or fill them first)")
    lo, hi = float(band[0]), float(band[1])
    if not 0 < lo < hi < fs / 2:
        raise ValueError(f"band ({lo:g}, {hi:g}) Hz: expected 0 < low < high < fs/2 = {fs / 2:g} Hz")
    c, n = x.shape
    duration = n / fs
    if duration * lo < 6 or n < 16:
        raise ValueError(
            f"x spans {duration:.3g} s: too short to resolve a line at {lo:g} Hz (expected at least {6 / lo:.3g} s)"
        )
    f, z, floor, r = _spectra(x, fs, pad, floor_halfwidth_hz)
    t = r.mean(axis=0)
    inband = np.flatnonzero((f >= lo) & (f <= hi))
    j = inband[int(np.argmax(t[inband]))]
    m = GRID_FACTOR * max((hi - lo) * duration, 1.0)
    half = _floor_half(n, fs, pad, floor_halfwidth_hz)
    eig = np.linalg.eigvalsh(_coherence(x, fs, f[j], floor_halfwidth_hz, 0.25))
    h_mean = _floor_law(half, eig)
    p_mean = min(1.0, m * _tail_floored(c * float(t[j]), eig, h_mean))
    # a line on one or two axes of six is diluted in the mean: the strongest single channel is tested too (each
    # channel's bin Exp(1) over its own floor, C of them: at most C times one's tail per frequency), and the two
    # tests share p_fa (Bonferroni)
    p_one = p_mean
    if c > 1:
        rmax = r[:, inband].max(axis=0)
        k = inband[int(np.argmax(rmax))]
        h_one = _floor_law(half, [1.0])
        p_one = min(1.0, m * c * _tail_floored(float(r[:, k].max()), [1.0], h_one))
        if p_one < p_mean:
            j = k
        p_value = min(1.0, 2.0 * min(p_mean, p_one))
        threshold = _level_for(p_fa / (2.0 * m), eig, h_mean) / c
    else:
        p_value = p_mean
        threshold = _level_for(p_fa / m, eig, h_mean) / c
    level = float(t[j])
    fr = _refine(x, fs, f[j], 1.5 * f[1], 1.0 / floor[:, j])
    levels = r[:, j]
    formal = _formal_sigma(levels - 1.0, n, fs)
    common = dict(
        formal_sigma_hz=formal,
        level_db=_db(level),
        threshold_db=_db(threshold),
        p_value=p_value,
        channel_levels_db=tuple(_db(v) for v in levels),
        duration_s=duration,
        band=(lo, hi),
    )
    if p_value >= p_fa:
        return SteadyLine(False, float("nan"), float("nan"), reason=_weak(common), **common)
    edges = np.linspace(0, n, parts + 1).astype(int)
    fk: list[float] = []
    sk: list[float] = []
    for a, b in zip(edges[:-1], edges[1:]):
        seg = x[:, a:b]
        if (b - a) / fs * fr < 3:
            break
        fp, sp, tp, _ = _estimate(seg, fs, fr, steady_tolerance * fr, pad, floor_halfwidth_hz)
        if 10 * math.log10(max(tp, 1e-300)) < part_min_db:
            why = (
                f"a line at {fr:.3f} Hz stands {common['level_db']:.1f} dB over the floor, but part "
                f"{len(fk) + 1} of {parts} ({a / fs:.1f}-{b / fs:.1f} s) shows it only {_db(tp):.1f} dB "
                f"(under {part_min_db:g} dB): not steady (a transient or a sweep, not a chain)"
            )
            return SteadyLine(False, fr, float("nan"), parts_hz=tuple(fk), reason=why, failed_part=len(fk), **common)
        fk.append(fp)
        sk.append(sp)
    fk_a, sk_a = np.asarray(fk), np.asarray(sk)
    if fk_a.size >= 2:
        wts = 1.0 / sk_a**2
        mean = float(np.sum(wts * fk_a) / np.sum(wts))
        birge = float(np.sum(wts * (fk_a - mean) ** 2) / (fk_a.size - 1))
        se = float(np.std(fk_a, ddof=1) / math.sqrt(fk_a.size))
    else:
        birge, se = float("nan"), 0.0
    sigma = max(formal * math.sqrt(max(1.0, birge if np.isfinite(birge) else 1.0)), se)
    return SteadyLine(
        True,
        fr,
        sigma,
        parts_hz=tuple(fk),
        parts_sigma_hz=tuple(sk),
        birge_ratio=birge,
        **common,
    )


#: The floor's running median spans correlated bins (a Hann window's neighbours share 4/9 of their power): its law is
#: that of the median of this many times fewer independent ones (measured: ``benchmarks/bench_steadyline_null.py``)
FLOOR_CORRELATION = 1.5
#: The band's maximum is taken over the zero-padded grid, between the independent frequencies as well: it exceeds a
#: level up to this many times as often as ``M`` independent frequencies would (measured: 1.2-1.7 at 11-14 dB)
GRID_FACTOR = 2.0


def _floor_half(n, fs, pad, floor_halfwidth_hz):
    """The running median's half-width in the unpadded bins of :func:`_spectra` (its window: ``2 half + 1`` bins)."""
    nfft = 1 << int(math.ceil(math.log2(n * pad)))
    step = max(nfft // n, 1)
    return max(int(round(floor_halfwidth_hz / (fs / nfft * step))), 2)


def _floor_law(half, eig):
    """The floor's law as that of the median of ``2 h + 1`` independent Exp(1) bins: ``h``, the running median's
    half-width divided by :data:`FLOOR_CORRELATION` and, for the channels' mean, multiplied by two thirds of their
    effective number ``(sum eig)**2 / sum eig**2`` (their floors' errors are independent, not one common factor: the
    full effective number understates the band maximum's rate at 7 dB on six independent channels 1.7-3-fold, two thirds
    of it overstate it 2-4-fold, measured against a Monte Carlo of Gaussian noise)."""
    eig = np.clip(np.asarray(eig, dtype=float), 0.0, None)
    c_eff = float(np.sum(eig) ** 2 / max(np.sum(eig**2), 1e-300))
    return max(int(half * max(c_eff / 1.5, 1.0) / FLOOR_CORRELATION), 2)


def _laplace_floor(a, h):
    """``E[exp(-a D)]``, ``D`` the floor over the truth: the ``h + 1``-th smallest of the ``2 h`` other bins of a
    ``2 h + 1``-bin window over ``ln 2`` (a bin that stands over the median leaves it to the others).  By Renyi's
    representation that order statistic is ``sum_{i=1}^{h+1} E_i / (2 h - i + 1)``, so the transform is the product
    ``prod_i d_i / (d_i + a / ln 2)``, ``d_i = 2 h - i + 1``."""
    a = np.atleast_1d(np.asarray(a, dtype=float)) / math.log(2.0)
    d = 2.0 * h - np.arange(h + 1)
    return np.exp(np.sum(np.log(d[None, :] / (d[None, :] + a[:, None])), axis=1))


def _tail_floored(s, eig, h):
    """``P(S > s)`` for the sum ``S`` of the channels' normalised bins (:func:`_mixture`) with the floor's
    estimation error integrated out exactly: ``E_D[P(S' > s D)]`` for the floor's law of :func:`_floor_law` (``h``).
    The tail is a mixture of exponentials, so the expectation is the same mixture of :func:`_laplace_floor`; a floor
    estimated low raises every normalised bin."""
    lam, w = _mixture(eig)
    lt = _laplace_floor(float(s) / lam, h)
    return float(np.clip(max(float(lt @ w), float(lt[0])), 0.0, 1.0))


def _level_for(p, eig, h):
    """The sum ``s`` at which :func:`_tail_floored` falls to ``p`` (bisection)."""
    lo, hi = 0.0, 10.0
    while _tail_floored(hi, eig, h) > p:
        hi *= 2
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _tail_floored(mid, eig, h) > p else (lo, mid)
    return hi


def _db(ratio):
    """A power ratio in dB; a channel that holds no signal at all (a constant) reads -300 dB, not an error."""
    return 10.0 * math.log10(max(float(ratio), 1e-30))


def _weak(common):
    return (
        f"no steady line in {common['band'][0]:.3g}-{common['band'][1]:.3g} Hz: the strongest stands "
        f"{common['level_db']:.1f} dB over the floor on the axes together ({max(common['channel_levels_db']):.1f} dB on "
        f"the best axis), under the {common['threshold_db']:.1f} dB that the false-alarm bound requires ("
        + (
            f"p <= {common['p_value']:.2g}"
            if common["p_value"] < 0.5
            else "noise alone gives a line this strong as often as not"
        )
        + ")"
    )


def normalised_spectrum(x, fs, *, pad=4, floor_halfwidth_hz=1.0):
    """(frequencies [Hz], the channels' mean periodogram over its running-median floor): the statistic ``T`` of
    :func:`steady_line`, for a plot."""
    fs = check_fs(fs)
    f, _, _, r = _spectra(np.atleast_2d(np.asarray(x, dtype=float)), fs, pad, floor_halfwidth_hz)
    return f, r.mean(axis=0)


def line_level(x, fs, freq, *, window_s=6.0, hop_s=1.0, tolerance=0.01, pad=4, floor_halfwidth_hz=1.0):
    """The level of a line near ``freq`` in sliding windows: (window centres [s from the first sample],
    level [dB over the floor], the channels' mean normalised periodogram's maximum within +-tolerance)."""
    fs = check_fs(fs)
    x = np.atleast_2d(np.asarray(x, dtype=float))
    n = x.shape[-1]
    w = int(round(window_s * fs))
    h = max(int(round(hop_s * fs)), 1)
    if n < w:
        return np.empty(0), np.empty(0)
    centres, levels = [], []
    for a in range(0, n - w + 1, h):
        f, _, _, r = _spectra(x[:, a : a + w], fs, pad, floor_halfwidth_hz)
        t = r.mean(axis=0)
        sel = np.abs(f - freq) <= max(tolerance * freq, f[1])
        centres.append((a + w / 2) / fs)
        levels.append(10 * math.log10(max(float(t[sel].max()), 1e-300)))
    return np.asarray(centres), np.asarray(levels)
