"""Link pitch from a recording: link-pass fundamental, pitch = speed / frequency, elongation.

A roller chain passing a point at speed ``v`` [m/s] with links of pitch ``L`` [m] excites the
link-pass frequency ``f = v / L`` and its harmonics.  :func:`estimate_pitch` finds ``f`` in the
band that a plausible range of pitches allows (octave-safe, :func:`vibkit.signal.link_pass_estimate`),
estimates it below the bin width with its Cramer-Rao standard deviation, burst by burst when the
recording is made of bursts (combined by inverse-variance weighting), and propagates the
uncertainty of ``f`` and of ``v`` to ``L``:

    (sigma_L / L)^2 = (sigma_f / f)^2 + (sigma_v / v)^2

The speed must be measured independently of the chain (a tachometer wheel on the handrail or step,
a timed step count).  A speed derived from the motor's rpm and the *nominal* sprocket returns the
nominal pitch by construction: one sprocket turn always moves Z links whatever their length, so the
link-pass frequency is Z times the shaft frequency and ``v_nominal / f = L_nominal``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..signal.detect import FILL_THRESHOLD, flag_invalid
from ..signal.quantisation import quantisation_step
from .decision import (CATALOGUE_PITCHES_M, DEFAULT_LIMITS_PERCENT, STATUS_IMPLAUSIBLE, STATUS_INCONCLUSIVE,
                       STATUS_NOT_FOUND, STATUS_OK, Decision, check_limits, decide, elongation_verdict,
                       nearest_catalogue)

__all__ = [
    "CATALOGUE_PITCHES_M",
    "DEFAULT_LIMITS_PERCENT",
    "DEFAULT_PITCH_RANGE_M",
    "Burst",
    "Hypothesis",
    "PitchEstimate",
    "STATUS_IMPLAUSIBLE",
    "STATUS_INCONCLUSIVE",
    "STATUS_NOT_FOUND",
    "STATUS_OK",
    "elongation_verdict",
    "estimate_pitch",
    "pick_channel",
    "uniform_bursts",
]

#: plausible link pitches [m]; the link-pass search band is speed / this range
DEFAULT_PITCH_RANGE_M = (0.08, 0.2)
#: step length of the reference escalator (3 links) [m]
STEP_LENGTH_M = 0.4
#: jitter (max |dt - mean dt| over mean dt) above which a burst is resampled to a uniform grid
JITTER_RESAMPLE = 0.01
#: longest run of invalid samples interpolated; longer runs split the burst [s]
MAX_GAP_S = 0.1
#: false-alarm probability of the link-pass detection test
DEFAULT_P_FA = 1e-3
#: samples (from the start) whose levels give the recorder's quantisation step
QUANTUM_SAMPLES = 1 << 20


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


def pick_channel(recording, channel=None) -> str:
    """Name of the channel to analyse: ``channel`` (vibkit's name or the file's header), else the first
    that is not a sample counter (see :func:`vibkit.io.resolve_channel`).

    Raises
    ------
    ValueError
        ``channel`` is not a channel of the recording, or the recording has no channel.
    """
    from ..io.channels import resolve_channel

    return resolve_channel(recording, channel)


def uniform_bursts(recording, channel, *, min_samples=16, max_gap_s=None):
    """Split a recording's channel into bursts, each uniformly sampled.

    A burst whose time steps depart from their mean by more than 1 % (phone clocks, loggers with
    jitter) is resampled linearly onto a uniform grid at its mean step; time stamps rounded to a
    microsecond are kept as they are.

    Parameters
    ----------
    recording : xarray.Dataset
        A recording (see :func:`vibkit.read_recording`).
    channel : str
        Data variable along ``time``.
    min_samples : int
        Bursts shorter than this are dropped.
    max_gap_s : float, optional
        Invalid samples (:func:`vibkit.signal.detect.flag_invalid`: non-finite, fill values
        ``|x| >= 1e30``, absurd values) are replaced by linear interpolation when they run over at
        most this time; a longer run, or one at an end of a burst, is cut out and splits the burst
        (never bridged). [s]  Default :data:`MAX_GAP_S`.

    Returns
    -------
    list of Burst
    """
    max_gap_s = MAX_GAP_S if max_gap_s is None else float(max_gap_s)
    da = recording[channel]
    t = np.asarray(recording["time"].values, dtype=float)
    x = np.asarray(da.values, dtype=float)
    if "segment" in recording.variables:
        seg = np.asarray(recording["segment"].values)
    else:
        seg = np.zeros(t.size, dtype=int)
    out = []
    bad_all = flag_invalid(x) if x.size else None
    for s in np.unique(seg):
        idx = np.flatnonzero(seg == s)
        if idx.size < min_samples:
            continue
        for piece in _split_at_gaps(idx, bad_all.mask, t, max_gap_s):
            ts, xs = t[piece], x[piece].copy()
            bad = bad_all.mask[piece]
            if bad.all() or piece.size < min_samples:
                continue
            counts = {}
            if bad.any():
                counts = {"non_finite": int(np.sum(bad & ~np.isfinite(xs))),
                          "fill_value": int(np.sum(bad & np.isfinite(xs) & (np.abs(xs) >= FILL_THRESHOLD))),
                          "total": int(bad.sum())}
                counts["absurd"] = counts["total"] - counts["non_finite"] - counts["fill_value"]
                ok = ~bad
                xs[bad] = np.interp(ts[bad], ts[ok], xs[ok])
            span = ts[-1] - ts[0]
            if not span > 0:
                continue
            dt = span / (ts.size - 1)
            jitter = float(np.max(np.abs(np.diff(ts) - dt)) / dt)
            if jitter > JITTER_RESAMPLE:
                grid = ts[0] + dt * np.arange(ts.size)
                xs = np.interp(grid, ts, xs)
            out.append(Burst(int(s), float(ts[0]), 1.0 / dt, xs, jitter > JITTER_RESAMPLE, counts))
    if not out:
        if bad_all is not None and bad_all.count == x.size:
            raise ValueError(f"channel {channel!r}: every sample is invalid ({bad_all.non_finite} non-finite, "
                             f"{bad_all.fill_value} fill values |x| >= {FILL_THRESHOLD:g}, {bad_all.absurd} absurd)")
        raise ValueError(f"channel {channel!r}: no burst with at least {min_samples} valid samples")
    return out


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


@dataclass(frozen=True)
class Hypothesis:
    """One reading of a spectral periodicity.

    Attributes
    ----------
    name : str
        What the periodicity would be (``"link pass"``, ``"step pass"``, ``"sprocket shaft"`` ...).
    frequency_hz : float
        [Hz]
    snr_db : float
        Spectral power near that frequency over the noise floor. [dB]
    implied_pitch_m : float
        The link pitch this reading implies at the given speed. [m]
    nearest_catalogue_m : float
        Nearest catalogue pitch. [m]
    deviation_percent : float
        ``implied / nearest - 1`` [%]
    chosen : bool
    reason : str
    """

    name: str
    frequency_hz: float
    snr_db: float
    implied_pitch_m: float
    nearest_catalogue_m: float
    deviation_percent: float
    chosen: bool
    reason: str


@dataclass(frozen=True)
class PitchEstimate:
    """Result of :func:`estimate_pitch` (all SI; see :meth:`as_dict` for the JSON form).

    ``detected`` / ``status`` say whether a link-pass family was found at all (``"ok"`` or
    ``"no link-pass found"``; then every frequency and pitch field is NaN).  ``method`` is
    ``"spectral"`` (harmonic least squares, stationary record) or ``"mean-phase"`` (total tracked phase
    over the time, when the frequency wanders), with ``method_reason``.
    """

    channel: str
    speed_m_s: float
    speed_sigma_m_s: float
    fundamental_hz: float
    fundamental_sigma_hz: float
    pitch_m: float
    pitch_sigma_m: float
    band_hz: tuple
    harmonics: list
    per_burst: list
    hypotheses: list
    warnings: list
    notes: list
    nominal_pitch_m: float | None = None
    elongation_percent: float | None = None
    elongation_sigma_percent: float | None = None
    limits_percent: tuple = DEFAULT_LIMITS_PERCENT
    verdict: str | None = None
    snr_db: float = float("nan")
    chi2_per_dof: float = float("nan")
    extra: dict = field(default_factory=dict)
    detected: bool = True
    status: str = STATUS_OK
    detection: dict = field(default_factory=dict)
    method: str = "spectral"
    method_reason: str = ""
    invalid_samples: dict = field(default_factory=dict)
    decision: Decision | None = None
    speed_source: str = "given"

    @property
    def has_link_pass(self) -> bool:
        """Whether a frequency and a pitch may be reported (status ``ok`` or ``inconclusive``)."""
        return self.status in (STATUS_OK, STATUS_INCONCLUSIVE)

    @property
    def reason(self) -> str:
        """Why the status is what it is (the decision's reason)."""
        return self.decision.reason if self.decision is not None else self.detection.get("reason", "")

    def as_dict(self) -> dict:
        """Plain JSON-ready dict (keys carry units).

        Without a detected link-pass family (``status == "no link-pass found"``) the dict has no
        frequency, pitch or elongation keys at all: there is no number to report.
        """
        head = {"status": self.status, "reason": self.reason, "detected": self.detected,
                "detection": dict(self.detection), "invalid_samples": dict(self.invalid_samples)}
        if not self.has_link_pass:
            d = {"channel": self.channel, **head, "speed_m_s": self.speed_m_s, "speed_source": self.speed_source,
                 "band_hz": list(self.band_hz), "warnings": list(self.warnings), "notes": list(self.notes)}
            if self.decision is not None and self.decision.implied_pitch_m is not None:
                d["implied_pitch_m"] = self.decision.implied_pitch_m  # what the refused family would mean
            return d
        d = {
            **head,
            "method": self.method,
            "method_reason": self.method_reason,
            "channel": self.channel,
            "speed_m_s": self.speed_m_s,
            "speed_source": self.speed_source,
            "speed_sigma_m_s": self.speed_sigma_m_s,
            "band_hz": list(self.band_hz),
            "fundamental_hz": self.fundamental_hz,
            "fundamental_sigma_hz": self.fundamental_sigma_hz,
            "pitch_m": self.pitch_m,
            "pitch_sigma_m": self.pitch_sigma_m,
            "snr_db": self.snr_db,
            "harmonics": [dict(h) for h in self.harmonics],
            "bursts": [dict(b) for b in self.per_burst],
            "burst_chi2_per_dof": None if math.isnan(self.chi2_per_dof) else self.chi2_per_dof,
            "hypotheses": [vars(h).copy() for h in self.hypotheses],
            "warnings": list(self.warnings),
            "notes": list(self.notes),
        }
        if self.nominal_pitch_m is not None:
            d.update(nominal_pitch_m=self.nominal_pitch_m, elongation_percent=self.elongation_percent,
                     elongation_sigma_percent=self.elongation_sigma_percent,
                     limits_percent=list(self.limits_percent), verdict=self.verdict)
        return d


_check_limits = check_limits


def _nearest(p):
    return nearest_catalogue(p)


def _snr_at(bursts, f):
    """Mean (over bursts) power near f over the median spectral floor [dB]."""
    vals = []
    for b in bursts:
        n = b.x.size
        if f >= b.fs / 2 or n / b.fs * f < 1.0:
            continue
        nfft = 1 << int(np.ceil(np.log2(4 * n)))
        p = np.abs(np.fft.rfft((b.x - b.x.mean()) * np.hanning(n), nfft)) ** 2
        fr = np.fft.rfftfreq(nfft, 1.0 / b.fs)
        df = b.fs / n
        near = np.abs(fr - f) <= df
        floor = np.median(p[(fr > 0.2) & (fr < min(b.fs / 2, 50.0))]) / np.log(2.0)
        vals.append(10 * np.log10(max(p[near].max(), 1e-300) / max(floor, 1e-300)))
    return float(np.mean(vals)) if vals else float("nan")


def _hypotheses(bursts, f0, speed, teeth, pitch_range):
    """Readings of the chosen peak f and of the periodicities it implies, with the pitch each gives."""
    lo, hi = pitch_range
    snr_f = _snr_at(bursts, f0)
    rows = []

    def row(name, f_link, chosen, reason):
        p = speed / f_link
        c, dev = _nearest(p)
        return Hypothesis(name, float(f_link), _snr_at(bursts, f_link), float(p), c, float(dev), chosen, reason)

    rows.append(row("f is the link pass", f0, True,
                    f"strongest harmonic family in {1000 * lo:.0f}-{1000 * hi:.0f} mm (octave-safe harmonic-sum "
                    f"search), {snr_f:.0f} dB over the floor"))
    for name, factor in (("f is the 2nd link-pass harmonic", 0.5), ("f is half the link pass", 2.0),
                         ("f is the step pass (3 links)", 3.0), (f"f is the sprocket shaft (Z = {teeth})", teeth)):
        fl = f0 * factor
        p = speed / fl
        if not lo <= p <= hi:
            why = f"rejected: implies {1000 * p:.1f} mm, outside the plausible {1000 * lo:.0f}-{1000 * hi:.0f} mm"
        else:
            why = "rejected: less harmonic evidence than f in the family search"
        rows.append(row(name, fl, False, why))
    # what the chosen reading predicts elsewhere in the spectrum
    for name, fe in (("step pass expected at f/3", f0 / 3.0), (f"sprocket shaft expected at f/{teeth}", f0 / teeth)):
        snr = _snr_at(bursts, fe)
        seen = "not resolved" if math.isnan(snr) else (f"seen, {snr:.0f} dB" if snr > 20 else f"weak, {snr:.0f} dB")
        c, dev = _nearest(speed / f0)
        rows.append(Hypothesis(name, float(fe), snr, float(speed / f0), c, float(dev), False,
                               f"consequence of the chosen reading ({seen}); not a link-pass candidate"))
    return rows


def _dropped_samples(recording, name, bursts):
    """Samples of the channel not in any burst because they were invalid and cut out."""
    n_total = int(np.asarray(recording[name].values).size)
    mask = flag_invalid(np.asarray(recording[name].values, dtype=float)).mask
    interpolated = sum(b.invalid.get("total", 0) for b in bursts)
    return max(0, int(mask.sum()) - interpolated) if n_total else 0


def _prepared(bursts, band):
    """Bursts scaled to unit size (no overflow or underflow in squares) and decimated to what the
    harmonics need (``10 band[1]`` kept); returns ``(bursts, scale)`` with ``x_original = scale x``."""
    from ..signal._checks import decimate_for_band

    scale = max(float(np.max(np.abs(b.x - np.median(b.x)))) for b in bursts)
    if not (scale > 0 and math.isfinite(scale)):
        scale = 1.0
    out = []
    for b in bursts:
        x = (b.x - np.median(b.x)) / scale
        x, fs, _q = decimate_for_band(x, b.fs, 10.0 * band[1], oversample=2.5)
        out.append(Burst(b.segment, b.t0, fs, x, b.resampled, b.invalid))
    return out, scale


#: spectral and mean-phase estimates further apart than this many combined sigmas: not stationary
DISAGREE_SIGMAS = 5.0
#: shortest burst for the mean-phase estimate, in periods of the fundamental
MIN_TRACK_PERIODS = 40


def _burst_mean_phase(b, e):
    """Mean-phase estimate of one burst (None when too short or when tracking fails)."""
    from ..signal.meanfreq import mean_link_pass_frequency

    f0 = e.fundamental_hz
    if b.x.size / b.fs * f0 < MIN_TRACK_PERIODS:
        return None
    try:
        return mean_link_pass_frequency(b.x, b.fs, f0=f0, amplitudes=[h.amplitude for h in e.harmonics],
                                        n_harmonics=min(3, len(e.harmonics)))
    except ValueError:
        return None


def _choose_method(e, mp):
    """``("spectral" | "mean-phase", why)`` for one burst.

    The mean-phase estimate is used when the frequency wanders: the tracked instantaneous frequency
    spreads over more than half a spectral bin (``spread x T > 0.5``) and more than twice what noise
    alone gives, or the two estimates disagree by more than ``DISAGREE_SIGMAS`` combined sigmas.
    """
    if mp is None:
        return "spectral", "record too short to track the phase; spectral estimate"
    dis = abs(mp.frequency_hz - e.fundamental_hz) / math.hypot(mp.sigma_hz, e.fundamental_sigma_hz)
    wander = mp.spread_bins > 0.5 and mp.spread_hz > 2.0 * mp.noise_spread_hz
    if wander or dis > DISAGREE_SIGMAS:
        why = (f"not stationary: the tracked frequency spreads {mp.spread_hz:.3g} Hz (std), "
               f"{mp.spread_bins:.2g} spectral bins over {mp.span_s:.4g} s (noise alone: {mp.noise_spread_hz:.2g} Hz); "
               f"spectral and mean-phase estimates differ by {dis:.1f} sigma: mean link-pass frequency from the total "
               f"tracked phase ({mp.cycles:.1f} link passes)")
        return "mean-phase", why
    return "spectral", (f"stationary: the tracked frequency spreads {mp.spread_bins:.2g} spectral bins over "
                        f"{mp.span_s:.4g} s (noise alone: {mp.noise_spread_hz:.2g} Hz) and agrees with the spectral "
                        f"estimate ({dis:.1f} sigma): harmonic least squares (Cramer-Rao sigma)")


def estimate_pitch(recording, *, speed, speed_sigma=0.0, channel=None, band=None, nominal_pitch=None,
                   limits_percent=DEFAULT_LIMITS_PERCENT, pitch_range=DEFAULT_PITCH_RANGE_M, n_harmonics=5,
                   teeth=28, p_fa=DEFAULT_P_FA, speed_source="given", frequency_only=False):
    """Link pitch from a recording's link-pass frequency and an independently measured speed.

    Parameters
    ----------
    recording : xarray.Dataset
        A recording (see :func:`vibkit.read_recording`), continuous or in bursts, uniformly
        sampled or not.
    speed : float
        Chain (step) speed. [m/s]
    speed_sigma : float, optional
        Standard deviation of ``speed``. [m/s]
    channel : str, optional
        Channel to analyse (default: the first).
    band : (float, float), optional
        Search band of the link-pass fundamental. [Hz]  Default: ``speed / pitch_range``.
    nominal_pitch : float, optional
        Nominal link pitch; gives the elongation and a verdict. [m]
    limits_percent : (float, float, float)
        Elongation limits: watch, plan replacement, replace. [%]
    pitch_range : (float, float)
        Plausible pitches. [m]
    n_harmonics : int
        Harmonics fitted.
    teeth : int
        Sprocket teeth (>= 3), for the shaft-frequency hypothesis.
    speed_source : str
        Where ``speed`` came from (``"given"``, ``"file: chain_speed_m_s"`` ...), named in the result.
    frequency_only : bool
        ``speed`` is a placeholder (``vibkit spectrum`` without a known speed): no plausibility check.
    p_fa : float
        False-alarm probability of the detection test run first
        (:func:`vibkit.signal.detect.detect_link_pass`): without a harmonic family in the band the
        result has ``detected = False``, ``status = "no link-pass found"`` and NaN numbers.

    Returns
    -------
    PitchEstimate
        ``status`` and ``decision`` from :func:`vibkit.diagnose.decision.decide`: a refusal (``"no
        link-pass found"``, ``"implausible"``) has NaN frequency and pitch and no verdict; ``"inconclusive"``
        keeps its numbers with the verdict ``"inconclusive"``.

    Raises
    ------
    ValueError
        Non-positive speed, negative sigma, bad band/limits/range, unknown channel, or no
        fundamental could be estimated.

    Notes
    -----
    Invalid samples (non-finite, fill values ``|x| >= 1e30``, absurd) are excluded as
    :func:`uniform_bursts` says, and counted in ``invalid_samples`` and a warning.  Each burst long
    enough (40 periods) is also tracked in phase; its mean link-pass frequency (total phase over the
    time) replaces the spectral estimate when the frequency wanders (see ``_choose_method``).
    ``L = v / f``; ``sigma_L = L sqrt((sigma_f/f)^2 + (sigma_v/v)^2)``.  Bursts are estimated
    separately (never bridged) and combined as ``f = sum(w_i f_i) / sum(w_i)``, ``w_i = 1/sigma_i^2``.
    The elongation is ``100 (L / L_nominal - 1)`` [%].

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> t = np.arange(4000) / 200.0
    >>> rec = xr.Dataset({"x": ("time", np.sin(2 * np.pi * 3.75 * t))}, coords={"time": t})
    >>> round(estimate_pitch(rec, speed=0.5).pitch_m, 4)
    0.1333
    """
    from ..signal import link_pass_estimate
    from ..signal.detect import detect_link_pass

    speed = float(speed)
    if not (math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be a positive number of m/s, got {speed!r}")
    speed_sigma = float(speed_sigma)
    if not (math.isfinite(speed_sigma) and speed_sigma >= 0):
        raise ValueError(f"speed_sigma must be >= 0 m/s, got {speed_sigma!r}")
    lo_p, hi_p = (float(v) for v in pitch_range)
    if not 0 < lo_p < hi_p:
        raise ValueError(f"pitch_range must be (min, max) with 0 < min < max [m], got {pitch_range!r}")
    limits = _check_limits(limits_percent)
    if isinstance(teeth, bool) or not isinstance(teeth, (int, np.integer)) or teeth < 3:
        raise ValueError(f"teeth must be an integer >= 3 (sprocket teeth), got {teeth!r}")
    if not 0 < float(p_fa) < 0.5:
        raise ValueError(f"p_fa must lie in (0, 0.5), got {p_fa!r}")
    if nominal_pitch is not None and not float(nominal_pitch) > 0:
        raise ValueError(f"nominal_pitch must be a positive length [m], got {nominal_pitch!r}")
    if band is None:
        band = (speed / hi_p, speed / lo_p)
    band = tuple(float(v) for v in band)
    if len(band) != 2 or not 0 < band[0] < band[1]:
        raise ValueError(f"band must be (low, high) with 0 < low < high [Hz], got {band!r}")
    name = pick_channel(recording, channel)
    raw_bursts = uniform_bursts(recording, name)
    warnings, notes = [], []
    nyq = min(b.fs for b in raw_bursts) / 2
    if band[1] >= nyq:
        raise ValueError(f"band {band[0]:.4g}-{band[1]:.4g} Hz reaches the Nyquist frequency {nyq:.4g} Hz of "
                         f"channel {name!r}")
    if any(b.resampled for b in raw_bursts):
        warnings.append("irregular time stamps: bursts resampled linearly to a uniform grid before the spectrum")
    invalid = {k: sum(b.invalid.get(k, 0) for b in raw_bursts) for k in ("non_finite", "fill_value", "absurd", "total")}
    n_dropped = _dropped_samples(recording, name, raw_bursts)
    if invalid["total"] or n_dropped:
        invalid["dropped"] = n_dropped
        warnings.append(f"{invalid['total'] + n_dropped} invalid sample(s) ({invalid['non_finite']} non-finite, "
                        f"{invalid['fill_value']} fill values |x| >= {FILL_THRESHOLD:g}, {invalid['absurd']} absurd) "
                        f"excluded: {invalid['total']} in runs of at most {MAX_GAP_S:g} s interpolated, "
                        f"{n_dropped} in longer runs or at the ends cut out (the record split there)")
    bursts, scale = _prepared(raw_bursts, band)
    units = str(recording[name].attrs.get("units", "1"))
    common = dict(channel=name, speed_m_s=speed, speed_sigma_m_s=speed_sigma, band_hz=band, limits_percent=limits,
                  extra={"units": units, "frequency_only": bool(frequency_only)}, invalid_samples=invalid,
                  speed_source=speed_source)
    # 1. is there a link-pass family at all?
    fs_det = float(np.median([b.fs for b in bursts]))
    # the recorder's step (its valid levels, before scaling and decimation) bounds the noise floors
    x_rec = np.asarray(recording[name].values[:QUANTUM_SAMPLES], dtype=float).ravel()
    quantum = quantisation_step(x_rec[~flag_invalid(x_rec).mask]) / scale
    decimation = max(1.0, float(np.median([b.fs for b in raw_bursts])) / fs_det)
    det = detect_link_pass([b.x for b in bursts if abs(b.fs / fs_det - 1) < 0.01], fs_det, band=band,
                           n_harmonics=n_harmonics, p_fa=p_fa, quantum=quantum, decimation=decimation)
    if not det.detected:
        warnings.insert(0, det.reason)
        nan = float("nan")
        return PitchEstimate(fundamental_hz=nan, fundamental_sigma_hz=nan, pitch_m=nan, pitch_sigma_m=nan,
                             harmonics=[], per_burst=[], hypotheses=[], warnings=warnings, notes=notes,
                             detected=False, status=STATUS_NOT_FOUND, detection=det.as_dict(), method="none",
                             method_reason="no link-pass family detected",
                             decision=decide(detected=False, detection_reason=det.reason), **common)
    # 2. estimate, burst by burst
    ests, skipped = [], []
    for b, b_raw in zip(bursts, raw_bursts):
        try:
            e = link_pass_estimate(b.x, b.fs, band=band, n_harmonics=n_harmonics, quantum=quantum,
                                   decimation=b_raw.fs / b.fs)
        except ValueError as exc:
            skipped.append(f"burst {b.segment}: {exc}")
            continue
        ests.append((b, e, _burst_mean_phase(b, e)))
    if not ests:
        raise ValueError(f"channel {name!r}: no burst long enough to estimate a link-pass frequency in "
                         f"{band[0]:.3g}-{band[1]:.3g} Hz ({'; '.join(skipped)})")
    if skipped:
        warnings.append(f"{len(skipped)} burst(s) too short, skipped")
    f_sel, s_sel, methods, reasons = [], [], [], []
    for _b, e, mp in ests:
        m, why = _choose_method(e, mp)
        methods.append(m)
        reasons.append(why)
        if m == "mean-phase":
            f_sel.append(mp.frequency_hz)
            s_sel.append(mp.sigma_hz)
        else:
            f_sel.append(e.fundamental_hz)
            s_sel.append(e.fundamental_sigma_hz)
    method = methods[0] if len(set(methods)) == 1 else "mixed"
    method_reason = reasons[0] if len(ests) == 1 else "; ".join(f"burst {b.segment}: {r}" for (b, _, _), r in
                                                                 zip(ests, reasons))
    f = np.array(f_sel)
    s = np.array(s_sel)
    if np.all(s > 0):
        w = 1.0 / s**2
        f0 = float(np.sum(w * f) / np.sum(w))
        sf = float(1.0 / np.sqrt(np.sum(w)))
        chi2 = float(np.sum(w * (f - f0) ** 2) / (f.size - 1)) if f.size > 1 else float("nan")
    else:
        f0, sf, chi2 = float(np.mean(f)), float(np.std(f)), float("nan")
        w = np.ones_like(f)
    if f.size > 1 and chi2 > 4.0:
        # bursts disagree more than their sigmas allow (speed drift between bursts): widen
        sf *= math.sqrt(chi2)
        warnings.append(f"burst estimates scatter {math.sqrt(chi2):.1f} x more than their sigmas (speed drift?); "
                        "sigma widened accordingly")
    for _, e, _ in ests:
        for wmsg in e.warnings:
            if wmsg not in warnings:
                warnings.append(wmsg)
    if f0 < band[0] * 1.02 or f0 > band[1] * 0.98:
        warnings.append(f"the fundamental {f0:.4g} Hz lies at the edge of the search band "
                        f"{band[0]:.3g}-{band[1]:.3g} Hz; widen --band or check the speed")
    pitch = speed / f0
    rel_f = sf / f0
    rel_v = speed_sigma / speed
    psig = pitch * math.hypot(rel_f, rel_v)
    if rel_v > rel_f:
        warnings.append(f"the speed's uncertainty ({100 * rel_v:.3g} %) dominates the pitch's "
                        f"(frequency {100 * rel_f:.3g} %): to see 0.5 % elongation the speed must be known to "
                        "about 0.1 %")
    if speed_sigma == 0:
        notes.append("no speed uncertainty given: pitch_sigma_m is the frequency's part only; to see 0.5 % "
                     "elongation the speed must be known to about 0.1 %")
    notes.append("a speed derived from the motor's rpm and the nominal sprocket returns the nominal pitch by "
                 f"construction: one sprocket turn always moves Z = {teeth} links, whatever their length; "
                 "measure the speed on the steps or handrail")
    # harmonics: weighted mean amplitude over bursts
    k = min(len(e.harmonics) for _, e, _ in ests)
    harm = []
    for i in range(k):
        amps = np.array([e.harmonics[i].amplitude for _, e, _ in ests]) * scale
        hdet = any(e.harmonics[i].detected for _, e, _ in ests)
        harm.append({"order": i + 1, "frequency_hz": (i + 1) * f0,
                     "amplitude": float(np.sum(w * amps) / np.sum(w)), "detected": bool(hdet)})
    per = []
    for (b, e, mp), m, fb, sb in zip(ests, methods, f_sel, s_sel):
        row = {"segment": b.segment, "t0_s": b.t0, "duration_s": b.x.size / b.fs, "fs_hz": b.fs,
               "fundamental_hz": fb, "fundamental_sigma_hz": sb, "method": m,
               "spectral_hz": e.fundamental_hz, "spectral_sigma_hz": e.fundamental_sigma_hz,
               "snr_db": e.snr_db, "resampled": b.resampled}
        if mp is not None:
            row.update(mean_phase_hz=mp.frequency_hz, mean_phase_sigma_hz=mp.sigma_hz,
                       tracked_spread_hz=mp.spread_hz, tracked_spread_bins=mp.spread_bins)
        per.append(row)
    snr = float(np.mean([e.snr_db for _, e, _ in ests]))
    res = dict(fundamental_hz=f0, fundamental_sigma_hz=sf, pitch_m=pitch, pitch_sigma_m=psig, harmonics=harm,
               per_burst=per, hypotheses=_hypotheses([b for b, _, _ in ests], f0, speed, int(teeth), (lo_p, hi_p)),
               warnings=warnings, notes=notes, snr_db=snr, chi2_per_dof=chi2, detection=det.as_dict(),
               method=method, method_reason=method_reason, **common)
    # 3. the decision: this family, in the band, steady, plausible, resolved (vibkit.diagnose.decision)
    worst = max(((abs(e.fundamental_hz - mp.frequency_hz), e.fundamental_hz, mp.frequency_hz)
                 for _, e, mp in ests if mp is not None), default=None)
    dec = decide(detected=True, detection_reason=det.reason, detection_hz=det.frequency_hz,
                 resolution_hz=1.0 / det.segment_s, fundamental_hz=f0, fundamental_sigma_hz=sf, band_hz=band,
                 speed_m_s=None if frequency_only else speed, speed_sigma_m_s=speed_sigma,
                 nominal_pitch_m=None if frequency_only else nominal_pitch, limits_percent=limits,
                 spectral_hz=worst[1] if worst else None, mean_phase_hz=worst[2] if worst else None,
                 speed_source=speed_source, significant_orders=det.significant_orders)
    if not dec.has_link_pass:
        # refused: no frequency, pitch or verdict leaves this function (the reason says what the family implies)
        warnings.insert(0, dec.reason)
        nan = float("nan")
        return PitchEstimate(fundamental_hz=nan, fundamental_sigma_hz=nan, pitch_m=nan, pitch_sigma_m=nan,
                             harmonics=[], per_burst=[], hypotheses=[], warnings=warnings, notes=notes, detected=True,
                             status=dec.status, detection=det.as_dict(), method=method, method_reason=method_reason,
                             decision=dec, **common)
    if dec.status == STATUS_INCONCLUSIVE:
        warnings.insert(0, f"inconclusive: {dec.reason}")
    res.update(decision=dec, status=dec.status)
    if nominal_pitch is not None and not frequency_only:
        nom = float(nominal_pitch)
        el = 100.0 * (pitch / nom - 1.0)
        res.update(nominal_pitch_m=nom, elongation_percent=el, elongation_sigma_percent=100.0 * psig / nom,
                   verdict=dec.verdict)
    return PitchEstimate(**res)
