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

__all__ = [
    "CATALOGUE_PITCHES_M",
    "DEFAULT_LIMITS_PERCENT",
    "DEFAULT_PITCH_RANGE_M",
    "Burst",
    "Hypothesis",
    "PitchEstimate",
    "elongation_verdict",
    "estimate_pitch",
    "pick_channel",
    "uniform_bursts",
]

#: catalogue escalator step-chain pitches [m]: 4 in, 0.4 m step / 3, 135.46 mm (ISO 1275-style)
CATALOGUE_PITCHES_M = (0.1016, 0.4 / 3.0, 0.13546)
#: elongation limits [%]: watch, plan replacement, replace
DEFAULT_LIMITS_PERCENT = (1.5, 2.0, 3.0)
#: plausible link pitches [m]; the link-pass search band is speed / this range
DEFAULT_PITCH_RANGE_M = (0.08, 0.2)
#: step length of the reference escalator (3 links) [m]
STEP_LENGTH_M = 0.4
#: jitter (max |dt - mean dt| over mean dt) above which a burst is resampled to a uniform grid
JITTER_RESAMPLE = 0.01


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
    """

    segment: int
    t0: float
    fs: float
    x: np.ndarray
    resampled: bool


def pick_channel(recording, channel=None) -> str:
    """Name of the channel to analyse: ``channel`` (vibkit's name or the file's header), else the first
    that is not a sample counter (see :func:`vibkit.io.resolve_channel`).

    Raises
    ------
    ValueError
        ``channel`` is not a channel of the recording, or the recording has no channel.
    """
    from .io.channels import resolve_channel

    return resolve_channel(recording, channel)


def uniform_bursts(recording, channel, *, min_samples=16):
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

    Returns
    -------
    list of Burst
    """
    da = recording[channel]
    t = np.asarray(recording["time"].values, dtype=float)
    x = np.asarray(da.values, dtype=float)
    if "segment" in recording.variables:
        seg = np.asarray(recording["segment"].values)
    else:
        seg = np.zeros(t.size, dtype=int)
    out = []
    for s in np.unique(seg):
        idx = np.flatnonzero(seg == s)
        if idx.size < min_samples:
            continue
        ts, xs = t[idx], x[idx]
        ok = np.isfinite(xs)
        if not ok.all():
            xs = np.interp(ts, ts[ok], xs[ok]) if ok.sum() >= 2 else xs
        span = ts[-1] - ts[0]
        if not span > 0:
            continue
        dt = span / (ts.size - 1)
        jitter = float(np.max(np.abs(np.diff(ts) - dt)) / dt)
        if jitter > JITTER_RESAMPLE:
            grid = ts[0] + dt * np.arange(ts.size)
            xs = np.interp(grid, ts, xs)
        out.append(Burst(int(s), float(ts[0]), 1.0 / dt, xs, jitter > JITTER_RESAMPLE))
    if not out:
        raise ValueError(f"channel {channel!r}: no burst with at least {min_samples} samples")
    return out


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
    """Result of :func:`estimate_pitch` (all SI; see :meth:`as_dict` for the JSON form)."""

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

    def as_dict(self) -> dict:
        """Plain JSON-ready dict (keys carry units)."""
        d = {
            "channel": self.channel,
            "speed_m_s": self.speed_m_s,
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


def elongation_verdict(elongation_percent, limits_percent=DEFAULT_LIMITS_PERCENT) -> str:
    """Verdict for a chain elongation [%] against three increasing limits [%].

    Returns one of ``"ok"`` (below the first), ``"watch"``, ``"plan replacement"``, ``"replace"``
    (at or above the third).  A shortened chain (negative elongation beyond the first limit) is
    ``"check speed"``: chains do not shrink, so the speed or the nominal pitch is wrong.
    """
    lim = _check_limits(limits_percent)
    e = float(elongation_percent)
    if e <= -lim[0]:
        return "check speed"
    if e < lim[0]:
        return "ok"
    if e < lim[1]:
        return "watch"
    if e < lim[2]:
        return "plan replacement"
    return "replace"


def _check_limits(limits):
    try:
        lim = tuple(float(v) for v in limits)
    except (TypeError, ValueError):
        raise ValueError(f"limits must be three numbers [%], got {limits!r}") from None
    if len(lim) != 3 or not 0 < lim[0] < lim[1] < lim[2]:
        raise ValueError(f"limits must be three increasing positive percentages, got {limits!r}")
    return lim


def _nearest(p):
    c = min(CATALOGUE_PITCHES_M, key=lambda q: abs(p / q - 1))
    return c, 100.0 * (p / c - 1.0)


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


def estimate_pitch(recording, *, speed, speed_sigma=0.0, channel=None, band=None, nominal_pitch=None,
                   limits_percent=DEFAULT_LIMITS_PERCENT, pitch_range=DEFAULT_PITCH_RANGE_M, n_harmonics=5,
                   teeth=28):
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
        Sprocket teeth, for the shaft-frequency hypothesis.

    Returns
    -------
    PitchEstimate

    Raises
    ------
    ValueError
        Non-positive speed, negative sigma, bad band/limits/range, unknown channel, or no
        fundamental could be estimated.

    Notes
    -----
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
    from .signal import link_pass_estimate

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
    if nominal_pitch is not None and not float(nominal_pitch) > 0:
        raise ValueError(f"nominal_pitch must be a positive length [m], got {nominal_pitch!r}")
    if band is None:
        band = (speed / hi_p, speed / lo_p)
    band = tuple(float(v) for v in band)
    if len(band) != 2 or not 0 < band[0] < band[1]:
        raise ValueError(f"band must be (low, high) with 0 < low < high [Hz], got {band!r}")
    name = pick_channel(recording, channel)
    bursts = uniform_bursts(recording, name)
    warnings, notes = [], []
    nyq = min(b.fs for b in bursts) / 2
    if band[1] >= nyq:
        raise ValueError(f"band {band[0]:.4g}-{band[1]:.4g} Hz reaches the Nyquist frequency {nyq:.4g} Hz of "
                         f"channel {name!r}")
    if any(b.resampled for b in bursts):
        warnings.append("irregular time stamps: bursts resampled linearly to a uniform grid before the spectrum")
    ests, skipped = [], []
    for b in bursts:
        try:
            e = link_pass_estimate(b.x, b.fs, band=band, n_harmonics=n_harmonics)
        except ValueError as exc:
            skipped.append(f"burst {b.segment}: {exc}")
            continue
        ests.append((b, e))
    if not ests:
        raise ValueError(f"channel {name!r}: no burst long enough to estimate a link-pass frequency in "
                         f"{band[0]:.3g}-{band[1]:.3g} Hz ({'; '.join(skipped)})")
    if skipped:
        warnings.append(f"{len(skipped)} burst(s) too short, skipped")
    f = np.array([e.fundamental_hz for _, e in ests])
    s = np.array([e.fundamental_sigma_hz for _, e in ests])
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
    for _, e in ests:
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
    k = min(len(e.harmonics) for _, e in ests)
    harm = []
    for i in range(k):
        amps = np.array([e.harmonics[i].amplitude for _, e in ests])
        det = any(e.harmonics[i].detected for _, e in ests)
        harm.append({"order": i + 1, "frequency_hz": (i + 1) * f0,
                     "amplitude": float(np.sum(w * amps) / np.sum(w)), "detected": bool(det)})
    units = str(recording[name].attrs.get("units", "1"))
    per = [{"segment": b.segment, "t0_s": b.t0, "duration_s": b.x.size / b.fs, "fs_hz": b.fs,
            "fundamental_hz": e.fundamental_hz, "fundamental_sigma_hz": e.fundamental_sigma_hz,
            "snr_db": e.snr_db, "resampled": b.resampled} for b, e in ests]
    snr = float(np.mean([e.snr_db for _, e in ests]))
    res = dict(channel=name, speed_m_s=speed, speed_sigma_m_s=speed_sigma, fundamental_hz=f0,
               fundamental_sigma_hz=sf, pitch_m=pitch, pitch_sigma_m=psig, band_hz=band, harmonics=harm,
               per_burst=per, hypotheses=_hypotheses([b for b, _ in ests], f0, speed, int(teeth), (lo_p, hi_p)),
               warnings=warnings, notes=notes, limits_percent=limits, snr_db=snr, chi2_per_dof=chi2,
               extra={"units": units})
    if nominal_pitch is not None:
        nom = float(nominal_pitch)
        el = 100.0 * (pitch / nom - 1.0)
        res.update(nominal_pitch_m=nom, elongation_percent=el, elongation_sigma_percent=100.0 * psig / nom,
                   verdict=elongation_verdict(el, limits))
        if 100.0 * psig / nom > limits[0] / 2:
            warnings.append(f"elongation uncertainty {100.0 * psig / nom:.2g} % is large against the first limit "
                            f"{limits[0]:g} %: the verdict is not reliable")
    return PitchEstimate(**res)
