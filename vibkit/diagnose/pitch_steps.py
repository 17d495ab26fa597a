"""The steps of :func:`vibkit.diagnose.pitch.estimate_pitch`, in the order it runs them.

bursts (:func:`prepare_bursts`) -> detection (:func:`detect`) -> per-burst estimates
(:func:`estimate_bursts`) -> method (:func:`choose_methods`) -> combination (:func:`combine`) ->
pitch (:func:`pitch_from`) -> decision (:func:`evidence` for :func:`vibkit.diagnose.decision.decide`).
The rows of the result come from :func:`harmonic_rows`, :func:`burst_rows` and :func:`hypotheses`.
Small frozen dataclasses carry what one step hands to the next; each step says why in its docstring,
and every tuning number is a named constant here with its reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..signal import link_pass_estimate
from ..signal._checks import decimate_for_band
from ..signal.bursts import (
    FILL_THRESHOLD,
    MAX_GAP_S,
    Burst,
    dropped_samples,
    flag_invalid,
    uniform_bursts,
)
from ..signal.detect import HARMONIC_SPAN, detect_link_pass
from ..signal.meanfreq import mean_link_pass_frequency
from ..signal.quantisation import quantisation_step
from ..signal.spectral import padded_power_rows
from .decision import DISAGREE_SIGMAS, LinkPassEvidence, nearest_catalogue
from .pitch_long import (
    at_recorded_rate,
    fast_recorder_at_recorded_rate,
    long_record_bursts,
    mean_phase_burst,
    spectrum_burst,
)
from .speed import speed_part_too_large

#: samples (from the start) whose levels give the recorder's quantisation step
QUANTUM_SAMPLES = 1 << 20
#: the decimated rate is at least this many times the highest frequency kept: its Nyquist frequency 1.25
#: times it, so that the decimation's low-pass (at 0.8 of Nyquist) passes it flat
DECIMATION_OVERSAMPLE = 2.5
#: the detection test needs one sampling frequency: bursts whose rate differs from the median rate by more
#: than this fraction are left out of it (they are still estimated)
SAME_FS_TOLERANCE = 0.01
#: shortest burst for the mean-phase estimate, in periods of the fundamental
MIN_TRACK_PERIODS = 40
#: harmonics tracked in phase at most: the strongest few carry the phase, higher ones add noise
TRACK_HARMONICS = 3
#: the tracked frequency wanders when it spreads over more than this many spectral bins (half a bin
#: moves the spectral peak) ...
WANDER_BINS = 0.5
#: ... and over more than this many times the spread that noise alone gives
WANDER_NOISE_FACTOR = 2.0
#: burst estimates scattering more than this chi^2 per degree of freedom (an rms scatter of two sigmas)
#: disagree beyond their sigmas (speed drift between bursts): the combined sigma is widened by sqrt(chi^2)
CHI2_WIDEN = 4.0
#: a fundamental within 2 % of an edge of the search band may be cut off by it: warned
BAND_EDGE_LOW = 1.02
BAND_EDGE_HIGH = 0.98
#: a predicted line this far over the floor is "seen" in the hypotheses (100 x the floor's power) [dB]
SEEN_SNR_DB = 20.0
#: the floor of the hypotheses' SNR: the median spectrum between these frequencies, above the drift and the
#: leakage of the mean, below 50 Hz where a link pass's first harmonics lie at any escalator speed (not the
#: floor of a fast recorder's empty upper band) [Hz]
SNR_FLOOR_BAND_HZ = (0.2, 50.0)
#: zero padding of the hypotheses' spectrum (FFT length >= this many times the record)
SNR_ZERO_PAD = 4
#: the hypotheses' spectrum is transformed in rows of this many bins when it is longer
#: (:func:`vibkit.signal.spectral.padded_power_rows`: the same bins within rounding, a few rows in memory instead of
#: the padded record, its transform and their scratch)
SNR_ROW_BINS = 1 << 20
#: power and floor are kept above this in the SNR's logarithm (an empty spectrum is not -inf dB)
TINY_POWER = 1e-300


@dataclass(frozen=True)
class Request:
    """The checked arguments of :func:`vibkit.diagnose.pitch.estimate_pitch` that the steps read (SI): speed
    and its sigma [m/s], search band [Hz], plausible pitches [m], elongation limits [%], the nominal pitch
    as given [m] (or None), sprocket teeth, and whether the speed is a placeholder (frequency only)."""

    speed: float
    speed_sigma: float | None
    band: tuple
    pitch_range: tuple
    limits: tuple
    nominal_pitch: object
    teeth: int
    frequency_only: bool


@dataclass(frozen=True)
class PreparedBursts:
    """The bursts of one channel (:func:`prepare_bursts`): as read (``raw``: their rates, lengths and invalid-sample
    counts; their samples were centred and scaled in place, no second copy of the record) and scaled and decimated
    for the spectrum (``bursts``, ``x_raw = scale x + median``), with the recorder's quantisation step in the scaled
    units, the invalid-sample counts and the warnings they give."""

    raw: list
    bursts: list
    scale: float
    quantum: float
    invalid: dict
    warnings: list


@dataclass(frozen=True)
class BurstEstimate:
    """One burst's spectral estimate (:class:`vibkit.signal.LinkPassEstimate`), its mean-phase estimate
    (None when too short to track), and the method chosen (:func:`choose_methods`) with its frequency.

    A long record's (:mod:`vibkit.diagnose.pitch_long`) was estimated on a decimated copy, ``burst``: ``full_rate``
    is the burst it came from, ``sigma_factor`` what the fits' sigmas were multiplied by (the parts check's too).
    """

    burst: Burst
    spectral: object
    mean_phase: object
    method: str = ""
    reason: str = ""
    frequency_hz: float = float("nan")
    sigma_hz: float = float("nan")
    full_rate: Burst | None = None
    sigma_factor: float = 1.0

    @property
    def scaled(self) -> Burst:
        """The burst at the rate of :func:`prepare_bursts` (the hypotheses' spectrum, the rows' rate and length):
        ``burst``, or the one a long record's estimates were decimated from (``full_rate``)."""
        return self.burst if self.full_rate is None else self.full_rate


@dataclass(frozen=True)
class Combination:
    """The bursts' frequencies combined (:func:`combine`): ``f0`` and its sigma, chi^2 per degree of freedom
    (NaN for one burst), the weights, the method (``"mixed"`` when bursts differ) and its reason."""

    f0: float
    sigma: float
    chi2: float
    weights: np.ndarray
    method: str
    method_reason: str
    warnings: list


def prepare_bursts(recording, name, band):
    """The channel's uniform bursts (:func:`vibkit.signal.bursts.uniform_bursts`), checked against the band's
    Nyquist frequency, counted for invalid samples, scaled and decimated (:func:`_scaled`)."""
    raw = uniform_bursts(recording, name)
    warnings = []
    nyq = min(b.fs for b in raw) / 2
    if band[1] >= nyq:
        hint = (
            "; a rate this low is most often a time column in another unit than its header says: check it "
            "(--time-unit ms), or give --sample-rate"
            if nyq < 2.0
            else ""
        )
        raise ValueError(
            f"band {band[0]:.4g}-{band[1]:.4g} Hz reaches the Nyquist frequency {nyq:.4g} Hz of channel {name!r}{hint}"
        )
    # irregular time stamps: resampled to a uniform grid; whether that matters is judged by jitter_effect
    invalid = {k: sum(b.invalid.get(k, 0) for b in raw) for k in ("non_finite", "fill_value", "absurd", "total")}
    n_dropped = dropped_samples(recording, name, raw)
    if invalid["total"] or n_dropped:
        invalid["dropped"] = n_dropped
        warnings.append(
            f"{invalid['total'] + n_dropped} invalid sample(s) ({invalid['non_finite']} non-finite, "
            f"{invalid['fill_value']} fill values |x| >= {FILL_THRESHOLD:g}, {invalid['absurd']} absurd) "
            f"excluded: {invalid['total']} in runs of at most {MAX_GAP_S:g} s interpolated, "
            f"{n_dropped} in longer runs or at the ends cut out (the record split there)"
        )
    bursts, scale = _scaled(raw, band)
    # the recorder's step (its valid levels, before scaling and decimation) bounds the noise floors
    x_rec = np.asarray(recording[name].values[:QUANTUM_SAMPLES], dtype=float).ravel()
    quantum = quantisation_step(x_rec[~flag_invalid(x_rec).mask]) / scale
    return PreparedBursts(raw, bursts, scale, quantum, invalid, warnings)


def _scaled(bursts, band):
    """Bursts scaled to unit size (no overflow or underflow in squares) and decimated to what the
    harmonics need (``HARMONIC_SPAN band[1]`` kept, the span the detection searches); returns ``(bursts, scale)`` with ``x_original = scale x``."""
    # each burst's own samples (uniform_bursts' copies) centred on its median and scaled in place, the largest
    # deviation found a block at a time: the same numbers as ``(x - median) / scale`` without a second copy of the
    # record (the bursts as read keep their rates, lengths and counts; their samples become the scaled ones)
    for b in bursts:
        x = b.x  # (a frozen Burst's array, changed in place)
        x -= np.median(x)
    scale = max(
        max(float(np.max(np.abs(b.x[i : i + QUANTUM_SAMPLES]))) for i in range(0, b.x.size, QUANTUM_SAMPLES))
        for b in bursts
    )
    if not (scale > 0 and math.isfinite(scale)):
        scale = 1.0
    out = []
    for b in bursts:
        x = b.x
        x /= scale
        x, fs, _q = decimate_for_band(x, b.fs, HARMONIC_SPAN * band[1], oversample=DECIMATION_OVERSAMPLE)
        out.append(Burst(b.segment, b.t0, fs, x, b.resampled, b.invalid))
    return out, scale


def detect(prep, *, band, n_harmonics, p_fa, name="x"):
    """Is there a link-pass family at all? :func:`vibkit.signal.detect.detect_link_pass` on the bursts at
    the median sampling frequency.  ValueError naming channel ``name`` when no burst is at that rate."""
    fs_det = float(np.median([b.fs for b in prep.bursts]))
    decimation = max(1.0, float(np.median([b.fs for b in prep.raw])) / fs_det)
    pieces = [b.x for b in prep.bursts if abs(b.fs / fs_det - 1) < SAME_FS_TOLERANCE]
    if not pieces:  # e.g. two bursts at different rates: their median rate is neither's
        rates = ", ".join(f"{b.x.size} samples at {b.fs:.4g} Hz" for b in prep.raw)
        raise ValueError(
            f"channel {name!r}: its {len(prep.raw)} bursts are sampled at rates more than {SAME_FS_TOLERANCE:.0%} "
            f"apart ({rates}); the link-pass test needs bursts at one sample rate (record without gaps, or "
            "check the time column)"
        )
    return detect_link_pass(
        pieces, fs_det, band=band, n_harmonics=n_harmonics, p_fa=p_fa, quantum=prep.quantum, decimation=decimation
    )


def estimate_bursts(prep, *, name, band, n_harmonics, f0=float("nan")):
    """Spectral and mean-phase estimates of each burst, never bridged; ``(estimates, warnings)``.  A burst longer
    than :data:`vibkit.diagnose.pitch_long.LONG_BURST_S` is estimated on a decimated copy
    (:func:`vibkit.diagnose.pitch_long.long_record_bursts`, with ``f0`` the detected
    fundamental [Hz]; NaN: every burst at its rate).

    Raises
    ------
    ValueError
        No burst is long enough for an estimate.
    """
    ests, skipped = [], []
    for (b, full, q, fraction), b_raw, b_prep in zip(long_record_bursts(prep, f0, n_harmonics), prep.raw, prep.bursts):
        try:
            e = link_pass_estimate(
                b.x, b.fs, band=band, n_harmonics=n_harmonics, quantum=prep.quantum, decimation=b_raw.fs / b.fs
            )
        except ValueError as exc:
            skipped.append(f"burst {b.segment}: {exc}")
            continue
        if full is None:
            mp, factor = _burst_mean_phase(b, e), 1.0
        else:  # tracked on a copy decimated to what the tracked harmonics need
            b_mp, _q_mp, fraction_mp = mean_phase_burst(b, e.fundamental_hz, TRACK_HARMONICS)
            mp = _burst_mean_phase(b_mp, e)
            e, mp, factor = at_recorded_rate(e, mp, b.x.size, q, fraction, mp_fraction=fraction_mp)
        e, mp, factor = fast_recorder_at_recorded_rate(e, mp, factor, b_raw.fs, b_prep.fs, b.fs)
        ests.append(BurstEstimate(b, e, mp, full_rate=full, sigma_factor=factor))
    if not ests:
        raise ValueError(
            f"channel {name!r}: no burst long enough to estimate a link-pass frequency in "
            f"{band[0]:.3g}-{band[1]:.3g} Hz ({'; '.join(skipped)})"
        )
    return ests, [f"{len(skipped)} burst(s) too short, skipped"] if skipped else []


def _burst_mean_phase(b, e):
    """Mean-phase estimate of one burst (None when too short or when tracking fails)."""
    f0 = e.fundamental_hz
    if b.x.size / b.fs * f0 < MIN_TRACK_PERIODS:
        return None
    try:
        return mean_link_pass_frequency(
            b.x,
            b.fs,
            f0=f0,
            amplitudes=[h.amplitude for h in e.harmonics],
            n_harmonics=min(TRACK_HARMONICS, len(e.harmonics)),
        )
    except ValueError:
        return None


def choose_methods(ests):
    """Each burst with its method (:func:`_choose_method`) and the frequency and sigma that method gives."""
    out = []
    for be in ests:
        m, why = _choose_method(be.spectral, be.mean_phase)
        if m == "mean-phase":
            f, s = be.mean_phase.frequency_hz, be.mean_phase.sigma_hz
        else:
            f, s = be.spectral.fundamental_hz, be.spectral.fundamental_sigma_hz
        out.append(BurstEstimate(be.burst, be.spectral, be.mean_phase, m, why, f, s, be.full_rate, be.sigma_factor))
    return out


def _choose_method(e, mp):
    """``("spectral" | "mean-phase", why)`` for one burst.

    The mean-phase estimate is used when the frequency wanders: the tracked instantaneous frequency
    spreads over more than :data:`WANDER_BINS` spectral bins (``spread x T > 0.5``) and more than
    :data:`WANDER_NOISE_FACTOR` times what noise alone gives, or the two estimates disagree by more than
    :data:`DISAGREE_SIGMAS` combined sigmas.
    """
    if mp is None:
        return "spectral", "record too short to track the phase; spectral estimate"
    dis = abs(mp.frequency_hz - e.fundamental_hz) / math.hypot(mp.sigma_hz, e.fundamental_sigma_hz)
    wander = mp.spread_bins > WANDER_BINS and mp.spread_hz > WANDER_NOISE_FACTOR * mp.noise_spread_hz
    if wander or dis > DISAGREE_SIGMAS:
        why = (
            f"not stationary: the tracked frequency spreads {mp.spread_hz:.3g} Hz (std), "
            f"{mp.spread_bins:.2g} spectral bins over {mp.span_s:.4g} s (noise alone: {mp.noise_spread_hz:.2g} Hz); "
            f"spectral and mean-phase estimates differ by {dis:.1f} sigma: mean link-pass frequency from the total "
            f"tracked phase ({mp.cycles:.1f} link passes)"
        )
        return "mean-phase", why
    return "spectral", (
        f"stationary: the tracked frequency spreads {mp.spread_bins:.2g} spectral bins over "
        f"{mp.span_s:.4g} s (noise alone: {mp.noise_spread_hz:.2g} Hz) and agrees with the spectral "
        f"estimate ({dis:.1f} sigma): harmonic least squares (Cramer-Rao sigma)"
    )


def combine(ests, name="x"):
    """Inverse-variance mean of the bursts' chosen frequencies, its sigma widened by sqrt(chi^2) when the
    bursts scatter beyond :data:`CHI2_WIDEN`; a plain mean and standard deviation when a sigma is zero.

    Raises
    ------
    ValueError
        Naming channel ``name``: every burst's sigma is infinite (or so large that its weight is zero), so
        no burst gives a frequency to average."""
    methods = [be.method for be in ests]
    method = methods[0] if len(set(methods)) == 1 else "mixed"
    if len(ests) == 1:
        method_reason = ests[0].reason
    else:
        method_reason = "; ".join(f"burst {be.burst.segment}: {be.reason}" for be in ests)
    f = np.array([be.frequency_hz for be in ests])
    s = np.array([be.sigma_hz for be in ests])
    warnings = []
    if np.all(s > 0):
        w = 1.0 / s**2
        if not np.sum(w) > 0:  # 0/0 below: no burst carries any weight
            sigmas = ", ".join(f"{v:.3g}" for v in s)
            raise ValueError(
                f"channel {name!r}: no burst gives a link-pass frequency with a finite uncertainty (sigma {sigmas} "
                "Hz): the harmonics found are lost in the noise, so there is no frequency to measure a pitch from"
            )
        f0 = float(np.sum(w * f) / np.sum(w))
        sf = float(1.0 / np.sqrt(np.sum(w)))
        chi2 = float(np.sum(w * (f - f0) ** 2) / (f.size - 1)) if f.size > 1 else float("nan")
    else:
        f0, sf, chi2 = float(np.mean(f)), float(np.std(f)), float("nan")
        w = np.ones_like(f)
    if f.size > 1 and chi2 > CHI2_WIDEN:
        # bursts disagree more than their sigmas allow (speed drift between bursts): widen
        sf *= math.sqrt(chi2)
        warnings.append(
            f"burst estimates scatter {math.sqrt(chi2):.1f} x more than their sigmas (speed drift?); "
            "sigma widened accordingly"
        )
    return Combination(f0, sf, chi2, w, method, method_reason, warnings)


def pitch_from(comb, req):
    """``(pitch, sigma, warnings, notes)``: ``L = v / f`` with ``sigma_L = L hypot(sigma_f / f, sigma_v / v)``,
    a warning when ``f`` sits at an edge of the band or the speed's uncertainty dominates."""
    f0, sf = comb.f0, comb.sigma
    speed, speed_sigma, band = req.speed, req.speed_sigma, req.band
    warnings, notes = [], []
    if f0 < band[0] * BAND_EDGE_LOW or f0 > band[1] * BAND_EDGE_HIGH:
        warnings.append(
            f"the fundamental {f0:.4g} Hz lies at the edge of the search band "
            f"{band[0]:.3g}-{band[1]:.3g} Hz; widen --band or check the speed"
        )
    pitch = speed / f0
    rel_f = sf / f0
    rel_v = (speed_sigma or 0.0) / speed
    psig = pitch * math.hypot(rel_f, rel_v)
    elongation = 100.0 * (pitch / req.nominal_pitch - 1.0) if req.nominal_pitch is not None else None
    too_large = speed_part_too_large(rel_v, elongation, req.limits)
    if too_large:
        decision = (
            f"the nearest limit is {min(abs(elongation - lim) for lim in req.limits):.2g} % away"
            if elongation is not None
            else f"a verdict needs the elongation's sigma under a third of the first limit ({req.limits[0]:g} %)"
        )
        warnings.append(
            f"the speed's uncertainty ({100 * rel_v:.2g} %) is too large for the verdict: {decision}; "
            "measure the speed on the steps (not the handrail: it may run up to 2 % faster)"
        )
    if speed_sigma is None:
        notes.append(
            "speed uncertainty not stated: the pitch's and the elongation's sigmas are not known (the "
            f"frequency alone gives {100 * rel_f:.2g} %); give --speed-uncertainty"
        )
    if speed_sigma is None or too_large:
        # a speed measured to what the verdict needs does not get it; one without its uncertainty, or one too
        # uncertain for a verdict, may be the motor's
        notes.append(
            "if this speed was derived from the motor's rpm and the nominal sprocket, it returns the nominal pitch "
            "by construction: one sprocket turn always moves as many links as it has teeth, whatever their length; "
            "measure the speed on the steps (not the handrail: it may run up to 2 % faster)"
        )
    other = _other_catalogue_pitch(pitch, elongation, req)
    if other:
        notes.append(other)
    return pitch, psig, warnings, notes


def _other_catalogue_pitch(pitch, elongation, req):
    """A note when an elongation past the first limit is a catalogue pitch other than the nominal one, nearly
    exactly (the hypotheses' "catalogue" column says 135.46 mm +0.1 % beside "+1.70 % of 133.33 mm -> watch"):
    the chain may be that pitch's, new.  Empty otherwise."""
    if elongation is None or req.frequency_only or abs(elongation) < req.limits[0]:
        return ""
    c, dev = nearest_catalogue(pitch)
    nominal = float(req.nominal_pitch)
    if abs(c / nominal - 1.0) < 0.005 or abs(dev) > abs(elongation) / 4:
        return ""
    return (
        f"the pitch {1000 * pitch:.1f} mm is within {abs(dev):.1g} % of the catalogue pitch {1000 * c:.2f} mm: if the "
        f"chain is a {1000 * c:.2f} mm chain, not the nominal {1000 * nominal:.2f} mm one, it is not elongated; "
        "check the chain's marking or the maker's drawing"
    )


def harmonic_rows(ests, comb, scale):
    """Harmonics: the weighted mean amplitude over bursts (in the channel's units), detected in any."""
    k = min(len(be.spectral.harmonics) for be in ests)
    harm = []
    for i in range(k):
        amps = np.array([be.spectral.harmonics[i].amplitude for be in ests]) * scale
        hdet = any(be.spectral.harmonics[i].detected for be in ests)
        harm.append(
            {
                "order": i + 1,
                "frequency_hz": (i + 1) * comb.f0,
                "amplitude": float(np.sum(comb.weights * amps) / np.sum(comb.weights)),
                "detected": bool(hdet),
            }
        )
    return harm


def burst_rows(ests):
    """One row per burst: its estimates, the method used, and the mean-phase tracking when there is one."""
    per = []
    for be in ests:
        b, e, mp = be.scaled, be.spectral, be.mean_phase
        row = {
            "segment": b.segment,
            "t0_s": b.t0,
            "duration_s": b.x.size / b.fs,
            "fs_hz": b.fs,
            "fundamental_hz": be.frequency_hz,
            "fundamental_sigma_hz": be.sigma_hz,
            "method": be.method,
            "spectral_hz": e.fundamental_hz,
            "spectral_sigma_hz": e.fundamental_sigma_hz,
            "snr_db": e.snr_db,
            "resampled": b.resampled,
        }
        if mp is not None:
            row.update(
                mean_phase_hz=mp.frequency_hz,
                mean_phase_sigma_hz=mp.sigma_hz,
                tracked_spread_hz=mp.spread_hz,
                tracked_spread_bins=mp.spread_bins,
            )
        per.append(row)
    return per


def evidence(det, ests, comb, req, *, speed_source):
    """What :func:`vibkit.diagnose.decision.decide` weighs: the detection, the combined estimate, and the
    burst whose spectral and mean-phase estimates differ most (its steadiness check)."""
    worst = max(
        (
            (
                abs(be.spectral.fundamental_hz - be.mean_phase.frequency_hz),
                be.spectral.fundamental_hz,
                be.mean_phase.frequency_hz,
                abs(be.spectral.fundamental_hz - be.mean_phase.frequency_hz)
                / math.hypot(be.spectral.fundamental_sigma_hz, be.mean_phase.sigma_hz),
            )
            for be in ests
            if be.mean_phase is not None
        ),
        default=None,
    )
    return LinkPassEvidence(
        detected=True,
        detection_reason=det.reason,
        detection_hz=det.frequency_hz,
        resolution_hz=1.0 / det.segment_s,
        fundamental_hz=comb.f0,
        fundamental_sigma_hz=comb.sigma,
        band_hz=req.band,
        speed_m_s=None if req.frequency_only else req.speed,
        speed_sigma_m_s=req.speed_sigma,
        nominal_pitch_m=None if req.frequency_only else req.nominal_pitch,
        limits_percent=req.limits,
        spectral_hz=worst[1] if worst else None,
        mean_phase_hz=worst[2] if worst else None,
        methods_sigmas=worst[3] if worst else None,
        speed_source=speed_source,
        significant_orders=det.significant_orders,
    )


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


def _burst_power(b, freqs, top=None):
    """One burst's zero-padded Hann power spectrum (FFT length :func:`_snr_nfft`) where :func:`_snr_at` looks: its
    largest power within ``fs / n`` of each of ``freqs`` (NaN where the burst cannot say, as :func:`_snr_at` skips)
    and its median floor over :data:`SNR_FLOOR_BAND_HZ`; ``(peaks, floor)``, the burst transformed once.

    A spectrum of up to :data:`SNR_ROW_BINS` bins is numpy's ``rfft`` of the padded record, as it always was. A
    longer one (a day at 200 Hz: 2^25 points, 768 MB for the padded copy, the transform and its scratch) is the
    same transform taken as rows of the four-step FFT (:func:`vibkit.signal.spectral.padded_power_rows`): the same
    bins, equal within rounding, one row of :data:`SNR_ROW_BINS` bins in memory at a time, and only the floor band's
    powers kept.

    ``top`` [Hz]: the highest frequency the burst's spectrum holds as recorded (a long record's decimated copy,
    :func:`vibkit.diagnose.pitch_long.spectrum_burst`): the floor band ends there; default the Nyquist frequency.
    """
    n = b.x.size
    nfft = _snr_nfft(n)
    step = 1.0 / (nfft * (1.0 / b.fs))  # rfftfreq's spacing, as it computes it
    df = b.fs / n
    lo, hi = SNR_FLOOR_BAND_HZ
    k0, k1 = _bins_between(step, nfft // 2 + 1, lo, min(b.fs / 2 if top is None else top, hi))
    # the bins within df of each f (rfftfreq's k * step for the few k near f, the same values it gives)
    near = []
    for f in freqs:
        if f >= b.fs / 2 or n / b.fs * f < 1.0:
            near.append(None)
            continue
        a0 = max(0, int(np.floor((f - df) / step)) - 2)
        a1 = min(nfft // 2 + 1, int(np.ceil((f + df) / step)) + 3)
        ks = np.arange(a0, a1)
        near.append(ks[np.abs(ks * step - f) <= df])
    # in place where numpy allows it (the same numbers as ``abs(rfft((x - mean) * hann, nfft)) ** 2``)
    y = b.x - b.x.mean()
    y *= np.hanning(n)
    if nfft <= SNR_ROW_BINS:
        c = np.fft.rfft(y, nfft)
        del y
        p = np.abs(c)
        del c
        np.square(p, out=p)
        peaks = np.array([np.nan if ks is None else p[ks].max() for ks in near])
        return peaks, np.median(p[k0:k1]) / np.log(2.0)
    band = np.empty(k1 - k0)
    peaks = np.full(len(near), -np.inf)
    n_rows = nfft // SNR_ROW_BINS
    for r, pr in padded_power_rows(y, nfft, SNR_ROW_BINS):
        # bins k = r + n_rows m: the floor band's kept, and those near each f looked at
        m_a = max(0, -((r - k0) // n_rows))  # the row's first bin at or above k0
        m_b = max(m_a, min(pr.size, -((r - k1) // n_rows)))  # ... and its first at or above k1
        band[r + n_rows * m_a - k0 :: n_rows][: m_b - m_a] = pr[m_a:m_b]
        for i, ks in enumerate(near):
            if ks is not None:
                mine = ks[(ks - r) % n_rows == 0]
                if mine.size:
                    peaks[i] = max(peaks[i], pr[(mine - r) // n_rows].max())
    peaks[[ks is None for ks in near]] = np.nan
    return peaks, np.median(band, overwrite_input=True) / np.log(2.0)


def _snr_nfft(n):
    """The hypotheses' FFT length for a record of ``n`` samples: a power of two, zero padded :data:`SNR_ZERO_PAD`
    times at least."""
    return 1 << int(np.ceil(np.log2(SNR_ZERO_PAD * n)))


def _bins_between(step, size, lo, hi):
    """``(k0, k1)``: the bins ``k`` (of ``size``) whose frequency ``k * step`` (rfftfreq's values) lies strictly
    between ``lo`` and ``hi``, as a slice (rfftfreq's whole array and its mask were the spectrum's size again)."""

    def first_above(f, strict):
        k = min(size, max(0, int(f / step) - 2))
        while k < size and (k * step <= f if strict else k * step < f):
            k += 1
        return k

    k0 = first_above(lo, True)
    k1 = max(k0, first_above(hi, False))
    return k0, k1


def _snr_at(bursts, freqs, copies=None):
    """Mean (over bursts) power near each f of ``freqs`` over the median spectral floor
    (:data:`SNR_FLOOR_BAND_HZ`) [dB], a list; NaN where no burst can say.  Each burst is transformed once for every
    frequency asked about (:func:`_burst_power`).  ``copies``: per burst, a long record's decimated copy or None
    (:func:`vibkit.diagnose.pitch_long.spectrum_burst`: the copy is transformed instead where it holds every
    frequency asked about)."""
    freqs = [float(f) for f in freqs]
    vals = [[] for _ in freqs]
    for b, copy in zip(bursts, copies or [None] * len(bursts)):
        b, top = spectrum_burst(b, copy, freqs)
        peaks, floor = _burst_power(b, freqs, top)
        for i, pk in enumerate(peaks):
            if not np.isnan(pk):
                vals[i].append(10 * np.log10(max(pk, TINY_POWER) / max(floor, TINY_POWER)))
    return [float(np.mean(v)) if v else float("nan") for v in vals]


def hypotheses(bursts, f0, speed, teeth, pitch_range, links_per_step=3, copies=None):
    """Readings of the chosen peak f and of the periodicities it implies, with the pitch each gives (the step
    pass is the link pass over ``links_per_step``).  ``copies``: per burst, a long record's decimated copy or None
    (:func:`_snr_at`)."""
    lo, hi = pitch_range
    k = links_per_step
    others = (
        ("f is the 2nd link-pass harmonic", 0.5),
        ("f is half the link pass", 2.0),
        (f"f is the step pass ({links_per_step} links)", float(links_per_step)),
        (f"f is the sprocket shaft (Z = {teeth})", teeth),
    )
    expected = ((f"step pass expected at f/{k}", f0 / k), (f"sprocket shaft expected at f/{teeth}", f0 / teeth))
    # every frequency looked up below, each burst transformed once for all of them
    asked = [f0, f0, *(f0 * factor for _n, factor in others), *(fe for _n, fe in expected)]
    snrs = iter(_snr_at(bursts, asked, copies))
    snr_f = next(snrs)
    rows = []

    def row(name, f_link, chosen, reason):
        p = speed / f_link
        c, dev = nearest_catalogue(p)
        return Hypothesis(name, float(f_link), next(snrs), float(p), c, float(dev), chosen, reason)

    rows.append(
        row(
            "f is the link pass",
            f0,
            True,
            f"strongest harmonic family in {1000 * lo:.0f}-{1000 * hi:.0f} mm (octave-safe harmonic-sum "
            f"search), {snr_f:z.0f} dB over the floor",
        )
    )
    for name, factor in others:
        fl = f0 * factor
        p = speed / fl
        if not lo <= p <= hi:
            why = f"rejected: implies {1000 * p:.1f} mm, outside the plausible {1000 * lo:.0f}-{1000 * hi:.0f} mm"
        else:
            why = "rejected: less harmonic evidence than f in the family search"
        rows.append(row(name, fl, False, why))
    # what the chosen reading predicts elsewhere in the spectrum
    for name, fe in expected:
        snr = next(snrs)
        seen = (
            "not resolved"
            if math.isnan(snr)
            else (f"seen, {snr:z.0f} dB" if snr > SEEN_SNR_DB else f"weak, {snr:z.0f} dB")
        )
        c, dev = nearest_catalogue(speed / f0)
        reason = f"consequence of the chosen reading ({seen}); not a link-pass candidate"
        rows.append(Hypothesis(name, float(fe), snr, float(speed / f0), c, float(dev), False, reason))
    return rows
