"""A long record's estimates, made on a copy decimated to what its harmonics need.

:func:`vibkit.diagnose.pitch.estimate_pitch` detects the link pass on the record at the rate its detection needs
(ten times the band's top); the estimates after it (harmonic least squares, the phase tracking of the mean-phase
estimate, the parts check's fits) need only the harmonics fitted.  A burst longer than :data:`LONG_BURST_S` (a
day's recording; every shipped scene, fleet file and phone ride is minutes at most and keeps its rate, bit for
bit) is estimated on a copy decimated to :data:`LONG_OVERSAMPLE` times its highest harmonic fitted
(:func:`long_record_bursts`: a third of the samples of 8 h at 200 Hz), its fits' sigmas and noise stated as the
recorded rate states them (:func:`at_recorded_rate`); a fast recorder's bursts that are not, which the
detection's own decimation shortened, are restated the same way (:func:`fast_recorder_at_recorded_rate`).  The
mean-phase estimate tracks the phase on a copy decimated further, to what its tracked harmonics need
(:func:`mean_phase_burst`); the hypotheses' spectrum is the copy's where it holds every frequency asked about
(:func:`spectrum_burst`).  The rows of the result keep the burst at its rate.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..signal._checks import decimate_for_band, decimated_noise_fraction
from ..signal.bursts import Burst

#: a burst longer than this is a long record [s]: after the detection, its estimates (spectral, mean-phase, the
#: parts check) are made on a copy decimated to what the harmonics fitted need (:func:`long_record_bursts`), every
#: shipped scene, fleet file and phone ride (minutes at most) is far shorter and keeps the full rate, bit for bit
LONG_BURST_S = 1800.0
#: ... decimated to at least this many times the highest harmonic fitted, ``(n_harmonics + 0.5)`` times the
#: detected fundamental (the low-pass at 0.8 of the new Nyquist frequency passes it flat; the oversampling of the
#: detection's own decimation, :data:`vibkit.diagnose.pitch_steps.DECIMATION_OVERSAMPLE`)
LONG_OVERSAMPLE = 2.5
#: a decimated copy's spectrum is taken as the recorded one's up to this fraction of its rate: 0.7 of the low-pass'
#: cutoff (0.8 of the new Nyquist frequency), where the zero-phase Butterworth keeps 99.3 % of the power
#: (:func:`spectrum_burst`)
SPECTRUM_TOP = 0.7 * 0.8 / 2.0


def long_record_bursts(prep, f0, n_harmonics):
    """The bursts the estimates are made on: ``[(burst, full-rate burst or None, decimation q, noise fraction)]``.

    A burst of :data:`LONG_BURST_S` or less is itself (``None``, 1, 1.0): every shipped record, bit for bit.  A longer
    one (a day at 200 Hz: 5.76 million samples) is decimated to at least :data:`LONG_OVERSAMPLE` times its highest
    harmonic fitted, ``(n_harmonics + 0.5) f0`` with ``f0`` the detected fundamental
    (:func:`vibkit.signal._checks.decimate_for_band`: 3 times at 200 Hz for 3.75 Hz), so that the harmonic fits,
    the phase tracking and the parts' fits work on a third of the samples or fewer.  The decimation's low-pass
    leaves about 0.76 of the white noise a band of the new rate would hold
    (:func:`vibkit.signal._checks.decimated_noise_fraction`): fits reading their noise density from their residual
    would state sigmas ``sqrt(0.76)`` too small; :func:`at_recorded_rate` states them as the recorded rate would.
    """
    out = []
    for b in prep.bursts:
        if b.x.size / b.fs <= LONG_BURST_S or not (math.isfinite(f0) and f0 > 0):
            out.append((b, None, 1, 1.0))
            continue
        x, fs, q = decimate_for_band(b.x, b.fs, (n_harmonics + 0.5) * f0, oversample=LONG_OVERSAMPLE)
        if q < 2:
            out.append((b, None, 1, 1.0))
            continue
        out.append((Burst(b.segment, b.t0, fs, x, b.resampled, b.invalid), b, q, decimated_noise_fraction(b.fs, q)))
    return out


def at_recorded_rate(e, mp, n, q, fraction, mp_fraction=None):
    """A decimated copy's estimates ``(spectral, mean-phase)`` stated as the burst at its recorded rate states them
    (:func:`long_record_bursts`): the frequencies' sigmas (and the noise-alone spread of the tracked frequency) over
    ``sqrt(fraction)``, and the noise the spectral fit read as white noise of the same density over the recorded
    band: its standard deviation times ``sqrt(q / fraction)``, the SNR over it ``10 log10(fraction / q)`` dB lower,
    a harmonic detected above three standard deviations of its amplitude (``noise sqrt(2 / N)`` at the recorded
    rate, ``N`` its ``q n`` samples; the copy's ``n`` samples are fitted as they are: at :data:`LONG_OVERSAMPLE`
    times its highest harmonic, :func:`vibkit.signal.link_pass_estimate` decimates no further).  ``mp_fraction``:
    the noise fraction of the copy the mean-phase estimate was tracked on, where it is another
    (:func:`mean_phase_burst`; default ``fraction``)."""
    factor = 1.0 / math.sqrt(fraction)
    noise = e.noise_std * math.sqrt(q / fraction)
    amp_sd = noise * math.sqrt(2.0 / (q * n))
    harmonics = [replace(h, detected=bool(h.amplitude > 3.0 * amp_sd)) for h in e.harmonics]
    e = replace(
        e,
        fundamental_sigma_hz=e.fundamental_sigma_hz * factor,
        noise_std=noise,
        snr_db=e.snr_db + 10.0 * math.log10(fraction / q),
        harmonics=harmonics,
    )
    if mp is not None:
        mp_factor = factor if mp_fraction is None else 1.0 / math.sqrt(mp_fraction)
        mp = replace(mp, sigma_hz=mp.sigma_hz * mp_factor, noise_spread_hz=mp.noise_spread_hz * mp_factor)
    return e, mp, factor


def fast_recorder_at_recorded_rate(e, mp, factor, fs_recorded, fs_burst, fs_fitted):
    """The estimates of a burst that :func:`vibkit.diagnose.pitch_steps._scaled` decimated (a recorder faster than
    the detection needs: over ``DECIMATION_OVERSAMPLE HARMONIC_SPAN`` times the band's top, e.g. 500 Hz for a
    2.5-6 Hz band), their sigmas stated for the noise as recorded: the decimation's low-pass keeps only
    :func:`vibkit.signal._checks.decimated_noise_fraction` of the new band's white noise, which the fits read as
    their noise, so their sigmas (the mean-phase, the parts': ``factor``) are divided by its square root.

    Only the last decimation before a fit shapes the noise in the band it fits (an earlier one's low-pass lies
    beyond it): the spectral fit is restated here only where :func:`vibkit.signal.link_pass_estimate` fitted the
    burst as it came (``e.decimation`` 1; where it decimated further it restated its own sigma), and nothing where
    the fits ran on a long record's copy (``fs_fitted``, the rate fitted, not ``fs_burst``:
    :func:`long_record_bursts`, restated by :func:`at_recorded_rate`).  A burst at its recorded rate (every 200 Hz
    record) is returned as it is."""
    q = round(fs_recorded / fs_burst)
    if q < 2 or fs_fitted != fs_burst:
        return e, mp, factor
    restate = 1.0 / math.sqrt(decimated_noise_fraction(fs_recorded, q))
    if e.decimation < 2:
        e = replace(e, fundamental_sigma_hz=e.fundamental_sigma_hz * restate)
    if mp is not None:
        mp = replace(mp, sigma_hz=mp.sigma_hz * restate, noise_spread_hz=mp.noise_spread_hz * restate)
    return e, mp, factor * restate


def mean_phase_burst(b, f0, n_track):
    """The copy a long record's mean-phase estimate is made on: ``(burst, q, noise fraction)``.

    The phase tracker (:func:`vibkit.signal.meanfreq.mean_link_pass_frequency`) uses ``n_track`` harmonics and fits
    the ends and the record-wide phases with as many as the rate holds: ``b`` (a long record's copy, at
    :data:`LONG_OVERSAMPLE` times the highest harmonic of the spectral fit) is decimated once more to
    :data:`LONG_OVERSAMPLE` times ``(n_track + 0.5) f0`` (``b`` itself, ``(1, 1.0)``, where that saves nothing).
    Its sigmas are stated for the recorded noise by ``1 / sqrt(fraction)`` of this last decimation (only the last
    low-pass shapes the noise in the band fitted, :func:`fast_recorder_at_recorded_rate`)."""
    if not (math.isfinite(f0) and f0 > 0):
        return b, 1, 1.0
    x, fs, q = decimate_for_band(b.x, b.fs, (n_track + 0.5) * f0, oversample=LONG_OVERSAMPLE)
    if q < 2:
        return b, 1, 1.0
    return Burst(b.segment, b.t0, fs, x, b.resampled, b.invalid), q, decimated_noise_fraction(b.fs, q)


def spectrum_burst(b, copy, freqs):
    """``(burst, top)``: what the hypotheses' spectrum of ``b`` (at its recorded rate) is taken from.

    ``copy`` (a long record's decimated copy, :func:`long_record_bursts`; None for every other burst) where every
    frequency of ``freqs`` that ``b`` can say about (under its Nyquist frequency, a cycle or more over the burst)
    lies under ``top = SPECTRUM_TOP copy.fs``: its spectrum is the recorded one's there (the low-pass passes it,
    noise and lines alike, the powers scaled alike), a third of the transform or less; the floor band ends at
    ``top`` (:func:`vibkit.diagnose.pitch_steps._burst_power`).  Else ``(b, None)``: e.g. a sprocket shaft's
    rotation read as the link pass, ``teeth f0`` under the recorded Nyquist frequency."""
    if copy is None:
        return b, None
    top = SPECTRUM_TOP * copy.fs
    said = [f for f in freqs if f < b.fs / 2 and b.x.size / b.fs * f >= 1.0]
    if any(f >= top for f in said):
        return b, None
    return copy, top
