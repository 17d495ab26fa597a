"""A long record's estimates on a decimated copy (``pitch_long.long_record_bursts``): short records untouched, the
long path against the full-rate path and against a known truth."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from vibkit.diagnose import pitch_long, pitch_steps
from vibkit.diagnose.pitch import estimate_pitch
from vibkit.signal._checks import decimate_for_band, decimated_noise_fraction

from support import chain
from support.recording import recording

FS = 100.0  # [Hz]
SPEED = 0.25  # [m/s]: a link pass of 1.875 Hz with 133 mm links, five harmonics under 10.3 Hz: decimated 3 times


def _record(hours, seed, amp=0.0, snr_db=0.0, kind="walk"):
    """A chain at ``SPEED`` (1 + w(t)), |w| <= amp (a random walk through knots every 150 s), white noise at
    ``snr_db`` per sample; ``(recording, mean speed, true mean link-pass frequency)``."""
    x, v, pitch = chain.wandering(hours * 3600.0, FS, 600.0, amp, snr_db, kind, seed, v0=SPEED)
    return recording({"x": x}, FS), v, v / pitch


def test_short_records_keep_their_bursts_untouched():
    """Up to LONG_BURST_S a burst is estimated as it is (the same object: every shipped record bit for bit);
    beyond, on a copy decimated by an integer factor >= 2 with the rate's noise fraction."""
    x = chain.chain(3.75, seconds=60.0, fs=FS)
    rec = recording({"x": x}, FS)
    prep = pitch_steps.prepare_bursts(rec, "x", (2.5, 6.25))
    ((b, full, q, frac),) = pitch_long.long_record_bursts(prep, 3.75, 5)
    assert b is prep.bursts[0] and full is None and q == 1 and frac == 1.0

    rec, _v, f_true = _record(0.6, 1)
    prep = pitch_steps.prepare_bursts(rec, "x", (1.25, 3.2))
    ((b, full, q, frac),) = pitch_long.long_record_bursts(prep, f_true, 5)
    assert full is prep.bursts[0]
    assert q == int(FS // (pitch_long.LONG_OVERSAMPLE * 5.5 * f_true)) == 3
    assert b.fs == FS / q and b.x.size == math.ceil(full.x.size / q)
    assert frac == decimated_noise_fraction(FS, q)


def test_noise_fraction_of_the_decimation_is_what_white_noise_keeps():
    """The fraction against the variance of decimated white noise, over the new band's: 2 M samples give it to
    about 0.2 % (its relative standard deviation is sqrt(2 q / n) ~ 0.2 %); q = 1 leaves everything."""
    rng = np.random.default_rng(3)
    w = rng.standard_normal(2_000_000)
    for q in (2, 3, 6):
        y, _fs, got_q = decimate_for_band(w, FS, FS / (2.5 * q) * 0.999, oversample=2.5)
        assert got_q == q
        assert np.var(y) * q == pytest.approx(decimated_noise_fraction(FS, q), rel=0.01)
    assert decimated_noise_fraction(FS, 1) == 1.0


def test_long_path_agrees_with_the_full_rate_path(monkeypatch):
    """35 min with a slow wander: the decimated estimate lands within the full-rate one's stated sigma, states
    that sigma within 10 %, takes the same method and status, and reports the burst at its recorded rate."""
    rec, _v, _f = _record(35 / 60, 5, amp=2e-4, snr_db=0.0)
    long = estimate_pitch(rec, speed=SPEED)
    monkeypatch.setattr(pitch_long, "LONG_BURST_S", math.inf)
    full = estimate_pitch(rec, speed=SPEED)
    assert long.status == full.status == "ok"
    assert long.method == full.method
    assert abs(long.fundamental_hz - full.fundamental_hz) < full.fundamental_sigma_hz
    assert long.fundamental_sigma_hz == pytest.approx(full.fundamental_sigma_hz, rel=0.1)
    b_long, b_full = long.per_burst[0], full.per_burst[0]
    assert b_long["fs_hz"] == b_full["fs_hz"] == pytest.approx(FS)
    assert b_long["duration_s"] == b_full["duration_s"]
    assert abs(b_long["mean_phase_hz"] - b_full["mean_phase_hz"]) < b_full["mean_phase_sigma_hz"]
    assert b_long["mean_phase_sigma_hz"] == pytest.approx(b_full["mean_phase_sigma_hz"], rel=0.2)
    # the SNR and the harmonics as the recorded rate states them; the residual is taken for white noise, which a
    # wander's unfitted part near the harmonics is not: stated up to 1.3 dB low here (equal without a wander)
    assert long.snr_db == pytest.approx(full.snr_db, abs=2.0)
    assert [h["detected"] for h in long.harmonics] == [h["detected"] for h in full.harmonics]
    # the hypotheses' spectrum is the decimated copy's (pitch_long.spectrum_burst): the recorded spectrum's within
    # its passband, its floor read over the passband only and its bins on another grid: within 0.25 dB here
    # (0.1 dB seen), the same lines resolved
    got, want = [h.snr_db for h in long.hypotheses], [h.snr_db for h in full.hypotheses]
    np.testing.assert_allclose(got, want, atol=0.25)


@pytest.mark.slow
def test_long_path_sigma_covers_the_truth():
    """A dozen steady hours at 0 dB: the stated sigma covers the true frequency (11 of 12 within 2 sigma, the rms
    of the errors in sigmas within 0.6-1.5: a chi^2 of 12 degrees of freedom falls there 98 % of the time). With
    a wander (0.02 %), the bursts' mean-phase estimates do too (7 of 8 within their own 2 sigma)."""
    z = []
    for seed in range(12):
        rec, v, f_true = _record(1.0, seed)
        est = estimate_pitch(rec, speed=v)
        assert est.status == "ok"
        z.append((est.fundamental_hz - f_true) / est.fundamental_sigma_hz)
    z = np.abs(z)
    assert np.sum(z <= 2) >= 11
    assert 0.6 <= math.sqrt(np.mean(z**2)) <= 1.5
    zm = []
    for seed in range(8):
        rec, v, f_true = _record(1.0, seed, amp=2e-4)
        row = estimate_pitch(rec, speed=v).per_burst[0]
        zm.append(abs(row["mean_phase_hz"] - f_true) / row["mean_phase_sigma_hz"])
    assert np.sum(np.array(zm) <= 2) >= 7


def _traced_peak(rec, speed):
    """The largest memory (tracemalloc) the analysis of ``rec`` holds at once beyond what was live before [bytes]."""
    tracemalloc.start()
    try:
        live = tracemalloc.get_traced_memory()[0]
        assert estimate_pitch(rec, speed=speed).status == "ok"
        return tracemalloc.get_traced_memory()[1] - live
    finally:
        tracemalloc.stop()


def test_long_record_memory_grows_as_a_small_multiple_of_its_samples():
    """Memory in proportion to the record: 40 min and 160 min (the long path both) differ in the analysis' traced
    peak by at most 7.5 times the samples' bytes they differ by (6.6 measured; fixed-size spectra and blocks cancel
    out of the difference); 9.1 before a clean record's burst came from views of its columns, was checked without
    gathered copies and scaled in place."""
    peaks, sizes = [], []
    for minutes in (40, 160):
        rec, v, _f = _record(minutes / 60, 1)
        peaks.append(_traced_peak(rec, v))
        sizes.append(rec["x"].values.nbytes)
    assert peaks[1] - peaks[0] <= 7.5 * (sizes[1] - sizes[0])


def test_spectrum_burst_takes_the_copy_only_where_it_holds_every_frequency():
    """The hypotheses' spectrum comes from a long record's copy where every frequency asked about that the recorded
    burst can say about lies under SPECTRUM_TOP of the copy's rate; else from the burst at its rate."""
    rec, _v, f_true = _record(0.6, 2)
    prep = pitch_steps.prepare_bursts(rec, "x", (1.25, 3.2))
    ((copy, full, _q, _frac),) = pitch_long.long_record_bursts(prep, f_true, 5)
    top = pitch_long.SPECTRUM_TOP * copy.fs
    assert pitch_long.spectrum_burst(full, copy, [f_true, 3 * f_true]) == (copy, top)
    assert pitch_long.spectrum_burst(full, copy, [f_true, 1.01 * top]) == (full, None)
    assert pitch_long.spectrum_burst(full, copy, [f_true, FS]) == (copy, top)  # above Nyquist: nobody can say
    assert pitch_long.spectrum_burst(full, None, [f_true]) == (full, None)


def test_decimation_by_blocks_is_the_whole_record_filter_bit_for_bit():
    """A record over FILTER_BLOCK samples is low-passed and decimated a block at a time (one forward copy held, not
    three): the same samples as the zero-phase filter of the whole record, decimated, bit for bit."""
    from vibkit.signal import _checks

    rng = np.random.default_rng(8)
    x = np.cumsum(rng.standard_normal(_checks.FILTER_BLOCK + 54_321)) * 1e-3 + rng.standard_normal(
        _checks.FILTER_BLOCK + 54_321
    )
    for f_keep in (13.0, 20.0, 8.0):  # q = 3, 2 and 5 at 100 Hz with oversample 2.5
        got, fs, q = decimate_for_band(x, 100.0, f_keep, oversample=2.5)
        cutoff = 0.8 * 100.0 / (2.0 * q)
        padlen = int(6.0 * 100.0 / cutoff)
        whole = _checks.sosfiltfilt(_checks._decimation_sos(100.0, q), x, padtype="even", padlen=padlen)[::q]
        assert q >= 2 and fs == 100.0 / q
        np.testing.assert_array_equal(got, whole)
