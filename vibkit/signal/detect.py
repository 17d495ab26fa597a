"""Is there a link-pass harmonic family at all?  A detection test with a stated false-alarm probability,
and the flagging of samples that are not measurements.

Detection (:func:`detect_link_pass`)
-----------------------------------
The record (or its bursts) is cut into ``K >= 2`` non-overlapping segments of ``max(20 / band[0], 8)``
seconds (shorter for short records and bursts, down to three periods of ``band[0]``), each linearly detrended and Hann-windowed.  Their periodograms
are averaged and divided by a robust local noise floor (running median over +-``W`` bins, scaled by
the median-to-mean ratio of the averaged periodogram's law).  Under the null hypothesis (Gaussian
noise whose spectrum is smooth on the scale of ``W`` bins, no periodic component), a normalised
bin of the average of ``k`` segments is Gamma(``k``, 1/``k``) distributed (mean 1), bins two apart are
practically independent, and the *harmonic sum* ``T(f) = sum_h R(h f)`` over ``H`` harmonics
(nearest bins, at least 20 bins apart) is Gamma(``H k``, 1/``k``).

Picking the best ``f`` in the band from the same data would make ``T`` the maximum of many
correlated sums, whose law is not known in closed form.  The test therefore *splits* the segments
into two interleaved halves A and B: the candidate ``f_A`` is searched on A (octave-safe harmonic
sum, as :func:`vibkit.signal.find_fundamental`) and tested on B alone, and ``f_B`` the other way
round.  Each test is a single test with the exact Gamma law (B's segments are independent of A's),
run at ``p_fa / 2``; the family is declared present when either passes.  The false-alarm
probability is at most ``p_fa`` (union bound; the overlap is of order ``p_fa**2``).  The floor's own
estimation error (relative standard deviation ``s``, from the asymptotic variance of a sample
median) is integrated out: ``P(T > t) = E_d[Q(t / (1 + d))]``, ``d ~ N(0, s**2 / H)``.

Floors of clean records
-----------------------
The running median is an estimate of the noise; a record without noise has none, and the median then
sees what is left between the lines: the window's leakage and, for a quantised record, almost nothing
at all (the rounding error of a clean tone is a fixed function of its phase: lines, the tone's
harmonics aliased over the whole band).  Those lines then stand 40 dB over the "floor" and make
harmonic families of their own (a 2048-count tone at 3.5 Hz was found as a family at 3.14 Hz).  The
floor is therefore never below what the record can resolve: the white quantisation noise ``q**2 / 12``
per sample of the recorder's step ``q`` (inferred from the levels, or given), and the peak of one line
that carries all of the quantisation error that follows the signal, given the noise that the
broadband floor shows (:func:`vibkit.signal.quantisation.quantisation_floor`); and, as before, not
below 1e-12 of the strongest bin (floating-point rounding).  A record
whose noise exceeds half a step keeps its floor; raising a floor only lowers the statistic, so the
false-alarm probability stays at most ``p_fa``.

The harmonic-sum search scores each candidate on a spectrum max-filtered over +-1 bin, which gives
every candidate within a bin of a line the line's full credit; the candidate is then placed where its
harmonics with evidence are strongest in the spectrum itself (within +-1 bin), so that a lone clean
tone is reported at its own bin, not at the lowest candidate of the plateau (up to 1.4 bins low).

A family whose significant harmonics all share a common order ``g > 1`` (for instance a square wave
at 8 Hz seen from 8/3 Hz: orders 3, 9, 15) is a family at ``g f``; when ``g f`` lies outside the
band, no link-pass is found in the band.

Invalid samples are flagged by :func:`vibkit.signal.bursts.flag_invalid` (re-exported here).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.ndimage
import scipy.signal
import scipy.special
import scipy.stats

from ._checks import check_fs
from .bursts import ABSURD_FACTOR, FILL_THRESHOLD, InvalidSamples, flag_invalid
from .peaks import climb_from_subharmonic, interp_by_harmonic, log_evidence
from .quantisation import quantisation_floor, quantisation_step

__all__ = [
    "FILL_THRESHOLD",
    "ABSURD_FACTOR",
    "InvalidSamples",
    "flag_invalid",
    "LinkPassDetection",
    "detect_link_pass",
    "harmonic_sum_pvalue",
    "harmonic_sum_threshold",
]

#: running-median floor: +- max(_HALF_MIN bins, _HALF_PERIODS x band[0]) around each bin
_HALF_MIN = 10
#: shortest test segment, in periods of band[0] (the record must hold two)
MIN_SEGMENT_PERIODS = 3.0
_HALF_PERIODS = 1.0
#: test segments are this many periods of band[0] long ...
SEGMENT_PERIODS = 20.0
#: ... and at least this long [s]: twenty periods give bins a twentieth of the lowest fundamental wide,
#: eight seconds keep the bins narrow when the band starts high
MIN_SEGMENT_S = 8.0
#: shortest segment in samples, whatever the rate: below 16 samples (9 spectral bins) there is no spectrum to test
MIN_SEGMENT_SAMPLES = 16
#: segments of more values than this (a day at 200 Hz: 5.76 M) are detrended and transformed by blocks of rows of at
#: most this many (the record and three copies of it were held whole: 264 MB for a day)
DETECT_BLOCK_VALUES = 1 << 20
#: harmonics up to this many times the band's top count in the search: room for the default five harmonics
#: of any fundamental in the band (the pitch estimate decimates to keep the same span)
HARMONIC_SPAN = 10.0
#: ... and never above this fraction of the sampling frequency: a margin below Nyquist, where anti-alias
#: filters roll off
F_TOP_NYQUIST_FRACTION = 0.45
#: a harmonic gives evidence in the search only above this many times the max-filtered spectrum's median
#: (6 dB): a bin of normalised noise (exponential at worst, mean 1) passes with probability below e^-4, 2 %
SEARCH_EVIDENCE_FACTOR = 4.0
#: a segment whose detrended range is below this fraction of its level holds nothing but rounding
ROUNDING_LEVEL = 1e-9
#: no floor is below this fraction of the strongest bin: double-precision rounding of the squares (module
#: notes, "Floors of clean records")
ROUNDING_FLOOR = 1e-12
#: a single harmonic line is significant above its Gamma quantile raised by this many of the floor's
#: relative sigmas (the floor is an estimate; its error must not make lines)
LINE_FLOOR_SIGMAS = 3
#: a family at g f (orders sharing the factor g) is outside the band when g f exceeds the band's top by
#: more than this many bins (the rounding of f to the bin grid)
COMMON_ORDER_BINS = 0.5
#: fractional orders j/m checked for a fundamental below the band (f/2 and f/3: a gait's 2nd and 3rd)
SUBHARMONIC_DIVISORS = (2, 3)


# ------------------------------------------------------------------------------------------- the test


@functools.lru_cache(maxsize=256)
def _gamma_median(k):
    return float(scipy.stats.gamma.median(k, scale=1.0 / k))


@functools.lru_cache(maxsize=256)
def _floor_rel_sd(k, n_window):
    """Relative standard deviation of the running-median floor of a k-segment average."""
    law = scipy.stats.gamma(k, scale=1.0 / k)
    m = float(law.median())
    # Hann: |X|^2 of neighbouring bins correlate 0.44, two apart 0.03 -> about n / 1.94 independent
    n_eff = max(n_window / 1.94, 1.0)
    return 1.0 / (2.0 * float(law.pdf(m)) * math.sqrt(n_eff)) / m


_GH_X, _GH_W = np.polynomial.hermite_e.hermegauss(24)
_GH_W = _GH_W / _GH_W.sum()


def harmonic_sum_pvalue(t, n_harmonics, k, floor_rel_sd=0.0):
    """P(T > t) for the normalised harmonic sum of ``n_harmonics`` bins of a ``k``-segment average.

    Parameters
    ----------
    t : float or ndarray
        Observed sum (each bin normalised to mean 1 under the null).
    n_harmonics : int
    k : int
        Segments averaged.
    floor_rel_sd : float, optional
        Relative standard deviation of each bin's noise-floor estimate; integrated out.

    Returns
    -------
    float or ndarray
    """
    t = np.asarray(t, dtype=float)
    a = n_harmonics * k
    s = float(floor_rel_sd) / math.sqrt(n_harmonics)
    if s <= 0:
        return scipy.special.gammaincc(a, t * k)
    d = np.clip(s * _GH_X, -0.9, None)
    q = scipy.special.gammaincc(a, np.multiply.outer(t, k / (1.0 + d)))
    return q @ _GH_W


def harmonic_sum_threshold(p_fa, n_harmonics, k, floor_rel_sd=0.0):
    """Threshold ``t`` with :func:`harmonic_sum_pvalue` ``(t) = p_fa``."""
    return _threshold(float(p_fa), int(n_harmonics), int(k), float(floor_rel_sd))


@functools.lru_cache(maxsize=256)
def _threshold(p_fa, n_harmonics, k, floor_rel_sd):
    import scipy.optimize

    lo = 0.0
    hi = float(scipy.stats.gamma.isf(p_fa, n_harmonics * k, scale=1.0 / k)) * (1 + 10 * floor_rel_sd) + 1.0
    while harmonic_sum_pvalue(hi, n_harmonics, k, floor_rel_sd) > p_fa:
        hi *= 2.0
    return float(
        scipy.optimize.brentq(
            lambda v: float(harmonic_sum_pvalue(v, n_harmonics, k, floor_rel_sd)) - p_fa, lo, hi, xtol=1e-10
        )
    )


@dataclass(frozen=True)
class LinkPassDetection:
    """Result of :func:`detect_link_pass`.

    Attributes
    ----------
    detected : bool
        A harmonic family with its fundamental in the band is present (at false-alarm probability
        ``p_fa``).
    status : str
        ``"ok"`` or ``"no link-pass found"``.
    reason : str
        One sentence: why.
    frequency_hz : float
        The family's fundamental (a rough value, to a fraction of a bin; NaN when nothing usable). [Hz]
    p_value : float
        Smallest p-value of the two split tests times 2 (Bonferroni), at most 1.
    p_fa : float
        Stated false-alarm probability.
    statistic : float
        Larger harmonic sum of the two tests (mean ``n_harmonics`` under the null).
    threshold : float
        Its threshold at ``p_fa / 2`` for the test that gave ``statistic``.
    n_segments : int
    segment_s : float
        [s]
    n_harmonics : int
        Harmonics summed in the test.
    significant_orders : tuple of int
        Harmonic orders individually significant on all segments (at ``p_fa`` over the orders).
    """

    detected: bool
    status: str
    reason: str
    frequency_hz: float
    p_value: float
    p_fa: float
    statistic: float
    threshold: float
    n_segments: int
    segment_s: float
    n_harmonics: int
    significant_orders: tuple = ()
    extra: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {
            "detected": self.detected,
            "status": self.status,
            "reason": self.reason,
            "frequency_hz": self.frequency_hz,
            "p_value": self.p_value,
            "p_fa": self.p_fa,
            "statistic": self.statistic,
            "threshold": self.threshold,
            "n_segments": self.n_segments,
            "segment_s": self.segment_s,
            "n_harmonics": self.n_harmonics,
            "significant_orders": list(self.significant_orders),
            **self.extra,
        }


def _segments(pieces, fs, fmin):
    """Cut pieces into equal non-overlapping segments.

    Returns ``(segs, nseg, split)``: a (K, nseg) array (None when too short) and whether there are
    at least two segments of ``MIN_SEGMENT_PERIODS`` for the split-half test (else one segment per
    piece of the longest piece's length, for the Bonferroni test).
    """
    target = int(round(fs * max(SEGMENT_PERIODS / fmin, MIN_SEGMENT_S)))
    lens = sorted((p.size for p in pieces), reverse=True)
    shortest = max(MIN_SEGMENT_SAMPLES, int(math.ceil(MIN_SEGMENT_PERIODS * fs / fmin)))
    nseg = target
    if sum(n // nseg for n in lens) < 2:
        nseg = min(target, max(lens[0] // 2, lens[1] if len(lens) > 1 else 0))
    split = nseg >= shortest
    if not split:
        nseg = lens[0]
        if nseg < shortest:
            return None, nseg, False
    rows = [p[i * nseg : (i + 1) * nseg] for p in pieces for i in range(p.size // nseg)]
    return np.array(rows, dtype=float), nseg, split


def _search(r, f, df, fmin, fmax, f_top):
    """Octave-safe harmonic-sum search on a normalised spectrum ``r`` (mean 1 noise)."""
    pmax = scipy.ndimage.maximum_filter1d(r, size=3, mode="nearest")
    sel = (f >= fmin / 2) & (f <= f_top)
    thr = SEARCH_EVIDENCE_FACTOR * max(float(np.median(pmax[sel])), 1.0)
    h_max = max(1, int(f_top // fmin))
    cands = np.arange(fmin, fmax + df / (4 * h_max), df / (2.0 * h_max))
    hf = cands[:, None] * np.arange(1, h_max + 1)[None, :]
    p = interp_by_harmonic(hf, f, pmax)
    ev = log_evidence(p, thr)
    ev[hf > f_top] = 0.0
    sc = ev.sum(axis=1)
    i = climb_from_subharmonic(cands, sc, df)
    # the max filter gives every candidate within a bin of a line the line's full credit: place the family
    # where its harmonics with evidence are strongest in the spectrum itself
    near = np.flatnonzero(np.abs(cands - cands[i]) <= df)
    use = ev[i] > 0
    if near.size > 1 and use.any():
        lines = np.interp(hf[near][:, use].ravel(), f, r).reshape(near.size, -1).sum(axis=1)
        j = int(near[np.argmax(lines)])
        return float(cands[j]), float(sc[i])
    return float(cands[i]), float(sc[i])


def _normalised(pw, half, quant, w, mask=None, clip=None):
    """Average of periodograms ``pw`` (K, bins) over its own floor (mean 1 under the null); the bins of
    ``mask`` set to 1 (excluded lines), none above ``clip``."""
    p = pw.mean(axis=0)
    return _masked(p / _floor(p, pw.shape[0], half, quant, w), mask, clip)


def _masked(r, mask, clip):
    if mask is not None:
        r = np.where(mask, 1.0, r)
    return r if clip is None else np.minimum(r, clip)


def _harmonic_bins(f0, df, n_harm, nbins):
    k = np.rint(f0 * np.arange(1, n_harm + 1) / df).astype(int)
    return k[(k >= 1) & (k < nbins - 1)]


def _floor(p, k, half, quant, w):
    """Noise floor of ``p`` (the average of ``k`` Hann periodograms with window ``w``): the running median,
    but never below what the record can resolve (module notes, "Floors of clean records").
    ``quant = (q, m)``: quantisation step of the analysed samples, decimated ``m`` times since recorded."""
    med = scipy.ndimage.median_filter(p, size=2 * half + 1, mode="reflect") / _gamma_median(k)
    bound = max(
        quantisation_floor(quant[0], w, float(np.median(med)), decimation=quant[1]),
        ROUNDING_FLOOR * float(np.max(p)) + np.finfo(float).tiny,
    )
    return np.maximum(med, bound)


def detect_link_pass(
    x,
    fs,
    *,
    band,
    n_harmonics=5,
    p_fa=1e-3,
    f_top=None,
    quantum=None,
    decimation=1,
    exclude=None,
    family_checks=True,
    clip=None,
):
    """Decide whether a harmonic family with its fundamental in ``band`` is present.

    Parameters
    ----------
    x : array_like or list of array_like
        One record, or several bursts at the same sampling frequency; finite values only. [x]
    fs : float
        Sampling frequency. [Hz]
    band : (float, float)
        Plausible range of the fundamental. [Hz]
    n_harmonics : int, optional
        Harmonics summed in the test (those below ``f_top``).
    p_fa : float, optional
        False-alarm probability of the test (Gaussian noise with a smooth spectrum).
    f_top : float, optional
        Highest frequency whose harmonics count in the search; default ``min(10 band[1], 0.45 fs)``. [Hz]
    quantum : float, optional
        Quantisation step of the recorder in the units of ``x``; the floor is never below what it can
        resolve (module notes).  Default: the step of ``x``'s own levels
        (:func:`vibkit.signal.quantisation.quantisation_step`; 0 for continuous data). [x]
    decimation : float, optional
        ``x`` was low-pass filtered and decimated this many times since it was recorded.
    exclude : (float, float), optional
        ``(step, half_width)``: the bins within ``half_width`` bins of every multiple of ``step`` [Hz] take
        the noise's mean (1) in every normalised spectrum. For lines the caller knows are there and are not the
        family sought (a chain's link-pass lines under a roller's knock); lowering no bin's chance to
        exceed, it keeps the false-alarm probability at most ``p_fa``.
    clip : float, optional
        No normalised bin counts more than this in the tested sums (the noise's mean is 1): a few strong
        lines that are not the family (mains hum, a motor's) cannot make one; lowering every sum, it keeps
        the false-alarm probability at most ``p_fa``. The search for the candidate is not clipped.
    family_checks : bool, optional
        Refuse a family whose significant orders share a factor or that has lines at f/2 or f/3 (its
        fundamental would lie outside the band). False for a family known to live in its high orders
        (a roller's knock, whose spectrum rises as f^2).

    Returns
    -------
    LinkPassDetection

    Raises
    ------
    ValueError
        Bad arguments, or a record shorter than three periods of ``band[0]``.

    Notes
    -----
    See the module notes for the statistic and its null distribution.  The false-alarm rate is
    verified by Monte Carlo in the tests and in ``benchmarks/bench_pitch.py``.
    """
    fs = check_fs(fs)
    pieces = _checked_pieces(x)
    fmin, fmax = (float(v) for v in band)
    if not 0 < fmin < fmax < fs / 2:
        raise ValueError(f"Parameter band={band!r} must satisfy 0 < low < high < fs/2 = {fs / 2:g} Hz.")
    if not 0 < float(p_fa) < 0.5:
        raise ValueError(f"Parameter p_fa={p_fa!r} must lie in (0, 0.5).")
    p_fa = float(p_fa)
    f_top = min(HARMONIC_SPAN * fmax, F_TOP_NYQUIST_FRACTION * fs) if f_top is None else float(f_top)
    f_top = max(f_top, fmax)
    sp = _spectra(pieces, fs, fmin, fmax, f_top, p_fa, quantum, decimation)
    if isinstance(sp, LinkPassDetection):
        return sp
    if exclude is not None:
        step, bins = (float(v) for v in exclude)
        if not (step > 0 and bins >= 0):
            raise ValueError(f"Parameter exclude={exclude!r} must be (step > 0 [Hz], half_width >= 0 [bins]).")
        width = (bins + 1e-9) * sp.df
        off = np.abs(sp.f - step * np.round(sp.f / step))
        sp = dataclasses.replace(sp, mask=(off <= width) & (sp.f >= step - width))
    if clip is not None:
        if not float(clip) > 1.0:
            raise ValueError(f"Parameter clip={clip!r} must exceed 1 (the noise's mean).")
        sp = dataclasses.replace(sp, clip=float(clip))
    n_h = max(1, min(int(n_harmonics), int(f_top // fmax)))
    tests = _split_half_tests(sp, n_h) if sp.split else _bonferroni_test(sp, n_h)
    if not tests:
        return _nothing(sp, "no harmonic of the band lies below the analysed frequency range")
    pv, t, thr, fc, hh = min(tests, key=lambda v: v[0])
    p_value = min(1.0, 2.0 * pv)
    detected = pv < p_fa / 2.0
    f_best, sig, lim = _refined(sp, fc, detected)
    base = dict(
        p_value=p_value,
        p_fa=p_fa,
        statistic=t,
        threshold=thr,
        n_segments=sp.k,
        segment_s=sp.seg_s,
        n_harmonics=hh,
        significant_orders=sig,
        extra={"test": "split-half" if sp.split else "bonferroni (one segment per piece)"},
    )
    if not detected:
        return LinkPassDetection(
            False,
            "no link-pass found",
            f"no harmonic family in {fmin:.4g}-{fmax:.4g} Hz: harmonic sum {t:.3g} under the "
            f"threshold {thr:.3g} (p = {p_value:.2g}, false-alarm probability {p_fa:g})",
            float("nan"),
            **base,
        )
    if family_checks:
        refused, f_best = _common_order(sp, f_best, sig, base)
        if refused is not None:
            return refused
        refused = _subharmonic(sp, f_best, lim, base)
        if refused is not None:
            return refused
    return LinkPassDetection(
        True,
        "ok",
        f"harmonic family at {f_best:.4g} Hz: harmonic sum {t:.3g} over the "
        f"threshold {thr:.3g} (p = {p_value:.2g}, false-alarm probability {p_fa:g})",
        float(f_best),
        **base,
    )


def _checked_pieces(x):
    """``x`` as a list of non-empty finite 1-D float arrays, or ValueError."""
    if isinstance(x, (list, tuple)):
        pieces = [np.asarray(p, dtype=float) for p in x]
    else:
        pieces = [np.asarray(x, dtype=float)]
    pieces = [p for p in pieces if p.size]
    if not pieces or any(p.ndim != 1 for p in pieces):
        raise ValueError("Parameter x must be a 1-D array or a list of 1-D arrays.")
    if any(not np.isfinite(p).all() for p in pieces):
        raise ValueError("Parameter x holds non-finite values; flag and repair them first (flag_invalid).")
    return pieces


@dataclass(frozen=True)
class _Spectra:
    """What every step of :func:`detect_link_pass` reads: the segments' Hann periodograms ``pw`` (K, bins) at
    frequencies ``f`` (bin width ``df``), their average ``p_all`` over its floor ``floor`` (running median
    over +-``half`` bins, never below the quantisation ``quant = (q, m)`` with window ``w``), the floor's
    relative sigma ``s_rel``, and the test set-up (split-half or one segment per piece)."""

    pw: np.ndarray
    f: np.ndarray
    df: float
    p_all: np.ndarray
    floor: np.ndarray
    half: int
    quant: tuple
    w: np.ndarray
    k: int
    seg_s: float
    s_rel: float
    split: bool
    fmin: float
    fmax: float
    f_top: float
    p_fa: float
    mask: np.ndarray | None = None
    clip: float | None = None

    @property
    def r_all(self):
        """The average periodogram over its floor (mean 1 under the null), excluded bins at 1."""
        return _masked(self.p_all / self.floor, self.mask, None)


def _nothing(sp, reason, f=float("nan"), extra=None):
    """No family: ``reason``."""
    return LinkPassDetection(
        False, "no link-pass found", reason, f, 1.0, sp.p_fa, 0.0, float("nan"), sp.k, sp.seg_s, 0, (), extra or {}
    )


def _spectra(pieces, fs, fmin, fmax, f_top, p_fa, quantum, decimation):
    """The segments' periodograms and floors (:class:`_Spectra`), or a LinkPassDetection when the record
    holds no variation at all.  Raises ValueError when it is too short for two segments."""
    segs, nseg, split = _segments(pieces, fs, fmin)
    if segs is None:
        longest = max(p.size for p in pieces) / fs
        raise ValueError(
            f"the record is too short to test for a link-pass family down to {fmin:.4g} Hz: two "
            f"segments of {MIN_SEGMENT_PERIODS:g} periods ({2 * MIN_SEGMENT_PERIODS / fmin:.3g} s) are "
            f"needed, the longest piece has {longest:.3g} s"
        )
    k_all, seg_s = segs.shape[0], nseg / fs
    blank = _Spectra(*(None,) * 8, k_all, seg_s, 0.0, split, fmin, fmax, f_top, p_fa)
    # scale first: huge or tiny values must not overflow or underflow in the squares
    # by blocks of segments, in place (each segment's line is its own; :data:`DETECT_BLOCK_VALUES`)
    rows = max(1, DETECT_BLOCK_VALUES // nseg) if segs.size > DETECT_BLOCK_VALUES else k_all
    blocks = [slice(i, i + rows) for i in range(0, k_all, rows)]
    level = max(float(np.max(np.abs(segs[blk]))) for blk in blocks)
    if not level > 0:
        return _nothing(blank, "the record is constant (every sample equal, or all zeros): no vibration at all")
    for blk in blocks:
        segs[blk] = scipy.signal.detrend(segs[blk] / level, axis=1, type="linear")
    scale = max(float(np.max(np.abs(segs[blk]))) for blk in blocks)
    if not scale > ROUNDING_LEVEL:
        # what is left after the straight lines is rounding: nothing was measured
        return _nothing(
            blank, "the record is constant (or a straight line) within each segment, to rounding: no vibration"
        )
    if quantum is None:
        quantum = quantisation_step(np.concatenate(pieces))
    w = scipy.signal.windows.hann(nseg, sym=False)
    quant = (float(quantum) / (level * scale), float(decimation))
    pw = np.empty((k_all, nseg // 2 + 1))
    for blk in blocks:
        y = segs[blk] / scale
        y *= w
        pw[blk] = np.abs(np.fft.rfft(y, axis=1)) ** 2
    f = np.fft.rfftfreq(nseg, 1.0 / fs)
    df = fs / nseg
    p_all = pw.mean(axis=0)
    if not float(np.max(p_all[1:])) > 0:
        return _nothing(blank, "the record has no variation")
    half = max(_HALF_MIN, int(round(_HALF_PERIODS * fmin / df)))
    floor = _floor(p_all, k_all, half, quant, w)
    s_rel = _floor_rel_sd(k_all, 2 * half + 1)
    return _Spectra(pw, f, df, p_all, floor, half, quant, w, k_all, seg_s, s_rel, split, fmin, fmax, f_top, p_fa)


def _bonferroni_test(sp, n_h):
    """One segment per piece: no independent half to test on.  Bonferroni over every distinct tuple of
    harmonic bins that a fundamental in the band can use (few: the bins are wide).  A list of at most one
    ``(p, statistic, threshold, f, harmonics)``."""
    r, df, f = _masked(sp.r_all, None, sp.clip), sp.df, sp.f
    cands = np.arange(sp.fmin, sp.fmax + df / (4 * n_h), df / (2.0 * n_h))
    kk = np.rint(np.outer(cands, np.arange(1, n_h + 1)) / df).astype(int)
    kk = kk[np.all((kk >= 1) & (kk < f.size - 1), axis=1)]
    if not kk.size:
        return []
    tuples = np.unique(kk, axis=0)
    sums = r[tuples].sum(axis=1)
    i = int(np.argmax(sums))
    m_tests = tuples.shape[0]
    t = float(sums[i])
    pv = min(1.0, m_tests * float(harmonic_sum_pvalue(t, n_h, sp.k, sp.s_rel))) / 2.0
    thr = harmonic_sum_threshold(sp.p_fa / m_tests, n_h, sp.k, sp.s_rel)
    return [(pv, t, thr, float(tuples[i, 0] * df), n_h)]


def _split_half_tests(sp, n_h):
    """The split-half tests: the candidate searched on one half of the segments, tested on the other, both
    ways round; a list of ``(p, statistic, threshold, f, harmonics)``."""
    ia, ib = np.arange(0, sp.k, 2), np.arange(1, sp.k, 2)
    # each half normalised by its own floor: a transient (a step, an impulse) that lies in one half
    # only raises that half's whole spectrum, which a floor shared with the other half would read
    # as excess power at every harmonic; each half's floor computed once, for its search and its test
    r_half = [_normalised(sp.pw[idx], sp.half, sp.quant, sp.w, sp.mask) for idx in (ia, ib)]
    tests = []
    for r_s, r_test, test_idx in ((r_half[0], r_half[1], ib), (r_half[1], r_half[0], ia)):
        # the candidate searched on the full spectrum, tested on the clipped one
        r_t = _masked(r_test, None, sp.clip)
        fc, _ = _search(r_s, sp.f, sp.df, sp.fmin, sp.fmax, sp.f_top)
        kb = _harmonic_bins(fc, sp.df, n_h, sp.f.size)
        hh = kb.size
        if hh == 0:
            continue
        t = float(r_t[kb].sum())
        kt = test_idx.size
        s_t = _floor_rel_sd(kt, 2 * sp.half + 1)
        pv = float(harmonic_sum_pvalue(t, hh, kt, s_t))
        thr = harmonic_sum_threshold(sp.p_fa / 2.0, hh, kt, s_t)
        tests.append((pv, t, thr, fc, hh))
    return tests


def _refined(sp, fc, detected):
    """The frequency refined on all segments (the tested candidate ``fc`` kept when they disagree), the
    harmonic orders individually significant there, and the significance level of one line."""
    r_all, f, df = sp.r_all, sp.f, sp.df
    f_best, _ = _search(r_all, f, df, sp.fmin, sp.fmax, sp.f_top)
    if detected and abs(f_best - fc) > df:
        # the two halves and the whole disagree (low SNR): keep the tested candidate
        f_best = fc
    h_top = max(1, int(sp.f_top // f_best))
    kb = _harmonic_bins(f_best, df, h_top, f.size)
    orders = np.arange(1, kb.size + 1)
    # one line at p_fa over the orders, its level raised by the floor's error (LINE_FLOOR_SIGMAS sigmas)
    lim = float(scipy.special.gammainccinv(sp.k, sp.p_fa / max(kb.size, 1))) / sp.k * (1 + LINE_FLOOR_SIGMAS * sp.s_rel)
    near = np.maximum(r_all[kb], np.maximum(r_all[np.maximum(kb - 1, 0)], r_all[np.minimum(kb + 1, f.size - 1)]))
    return f_best, tuple(int(o) for o in orders[near > lim]), lim


def _above_band(sig, f_best, fg, sp):
    """Why a family whose significant lines are all multiples of ``fg`` above the band is no link pass, in the
    lines' own frequencies (not as orders of a fundamental the family does not have)."""
    band = f"{sp.fmin:.2f}-{sp.fmax:.2f} Hz"
    if len(sig) == 1:
        return (
            f"a periodic signal is present, but its one significant line, at {fg:.4g} Hz, lies above the band "
            f"{band}: a tone, not a link pass in the band"
        )
    lines = ", ".join(f"{o * f_best:.4g}" for o in sig[:6]) + (" ..." if len(sig) > 6 else "")
    return (
        f"a periodic signal is present, but its significant lines ({lines} Hz) are all multiples of {fg:.4g} Hz, "
        f"a fundamental above the band {band}"
    )


def _common_order(sp, f_best, sig, base):
    """A family whose significant orders share a factor ``g > 1`` is a family at ``g f``: ``(refusal, f)``
    with the refusal when ``g f`` lies above the band (``base`` updated with the reduced orders)."""
    g = 0
    for o in sig:
        g = math.gcd(g, o)
    if g <= 1:
        return None, f_best
    fg = g * f_best
    if fg > sp.fmax * (1 + COMMON_ORDER_BINS * sp.df / sp.fmax):
        return LinkPassDetection(
            False,
            "no link-pass found",
            _above_band(sig, f_best, fg, sp),
            float(fg),
            **base,
        ), f_best
    base["significant_orders"] = tuple(o // g for o in sig)
    return None, fg


def _subharmonic(sp, f_best, lim, base):
    """A refusal when the family has a line at a fractional order j/m (:data:`SUBHARMONIC_DIVISORS`: f/2,
    3f/2, f/3 ...) at least as strong as its line at f: its fundamental is f/m, below the band (a gait at
    1.6-2.2 Hz seen from its 2nd or 3rd harmonic; a modulated tone whose lines fall on a comb of f/2)."""
    r_all, df, fmin = sp.r_all, sp.df, sp.fmin
    k1 = int(round(f_best / df))
    p_one = float(np.max(r_all[max(k1 - 1, 0) : k1 + 2]))
    # the family's own lines (f, 2f, ... within a bin): a fractional line must be another line, not the leakage
    # of one of these into the next bin (a 3 s record's two 1.5 s segments, 0.67 Hz bins: a 3.9 Hz tone read at
    # 3.15 Hz had its own bin at 4.0 Hz counted as the line at 3f/2, and was refused as a 1.58 Hz gait)
    own = {
        k + d for j in range(1, int(sp.f_top // f_best) + 1) for k in (int(round(j * f_best / df)),) for d in (-1, 0, 1)
    }

    def line(k):
        bins = [b for b in (k - 1, k, k + 1) if 0 <= b < sp.f.size and b not in own]
        return float(np.max(r_all[bins])) if bins else 0.0

    for m in SUBHARMONIC_DIVISORS:
        if f_best / m >= fmin or f_best / m < 2 * df:
            continue
        ks = [int(round(j * f_best / m / df)) for j in range(1, 3 * m) if j % m and j * f_best / m < sp.f_top]
        p_sub = [line(k) if 1 <= k < sp.f.size - 1 else 0.0 for k in ks]
        # a significant fractional line as strong as the line at f; for thirds the line at f/3 itself must be
        # there too (a structural mode near 4f/3 of a chain is not a subharmonic family; a carrier at exactly
        # 3f/2 between two sidebands at f and 2f is)
        if p_sub and max(p_sub) > lim and max(p_sub) >= p_one and (m == 2 or p_sub[0] > lim):
            base["extra"]["subharmonic"] = m
            return LinkPassDetection(
                False,
                "no link-pass found",
                f"a periodic signal is present, but its line at {f_best / m:.4g} Hz (f/{m}) is as "
                f"strong as the one at {f_best:.4g} Hz: its fundamental is {f_best / m:.4g} Hz, "
                f"below the band {fmin:.4g}-{sp.fmax:.4g} Hz (a gait, a sway, not a link pass)",
                float(f_best / m),
                **base,
            )
    return None
