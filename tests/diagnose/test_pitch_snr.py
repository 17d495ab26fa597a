"""The hypotheses' signal-to-floor ratios: each burst transformed once, the same numbers as the full spectrum (a long
record's in rows of the four-step FFT: equal within rounding)."""

import numpy as np

from vibkit.diagnose import pitch_steps as steps
from vibkit.signal.bursts import Burst
from vibkit.signal.spectral import padded_power_rows


def _reference_snr(bursts, f):
    """The formula written out on the whole zero-padded spectrum and its rfftfreq frequencies."""
    vals = []
    for b in bursts:
        n = b.x.size
        if f >= b.fs / 2 or n / b.fs * f < 1.0:
            continue
        nfft = 1 << int(np.ceil(np.log2(steps.SNR_ZERO_PAD * n)))
        p = np.abs(np.fft.rfft((b.x - b.x.mean()) * np.hanning(n), nfft)) ** 2
        fr = np.fft.rfftfreq(nfft, 1.0 / b.fs)
        near = np.abs(fr - f) <= b.fs / n
        lo, hi = steps.SNR_FLOOR_BAND_HZ
        floor = np.median(p[(fr > lo) & (fr < min(b.fs / 2, hi))]) / np.log(2.0)
        vals.append(10 * np.log10(max(p[near].max(), steps.TINY_POWER) / max(floor, steps.TINY_POWER)))
    return float(np.mean(vals)) if vals else float("nan")


def _bursts():
    rng = np.random.default_rng(5)
    out = []
    for i, (fs, n) in enumerate(((100.0, 3001), (100.0, 1777), (200.0, 4096), (50.0, 60))):
        t = np.arange(n) / fs
        x = np.sin(2 * np.pi * 3.54 * t) + 0.3 * np.sin(2 * np.pi * 1.18 * t) + 0.5 * rng.standard_normal(n)
        out.append(Burst(i, 100.0 * i, fs, x, False))
    return out


def test_one_spectrum_per_burst_gives_the_full_spectrum_numbers_bit_for_bit():
    bursts = _bursts()
    # the chosen peak, its readings, the consequences, the band edges, near Nyquist and a too-low one (skipped)
    freqs = (3.54, 1.77, 7.08, 10.62, 0.1264, 1.18, 24.9, 49.99, 0.2, 0.0101, 0.5 * 3.54 / 3)
    got = steps._snr_at(bursts, freqs)  # every burst transformed once for all of them
    for f, g in zip(freqs, got):
        want = _reference_snr(bursts, f)
        assert (np.isnan(g) and np.isnan(want)) or g == want, (f, g, want)
        alone = steps._snr_at(bursts, [f])[0]  # asked alone: the same
        assert alone == g or np.isnan(g)


def _reference_power(b, freqs):
    """The largest power near each f and the floor, from the whole zero-padded spectrum (rfftfreq's bins)."""
    n = b.x.size
    nfft = 1 << int(np.ceil(np.log2(steps.SNR_ZERO_PAD * n)))
    p = np.abs(np.fft.rfft((b.x - b.x.mean()) * np.hanning(n), nfft)) ** 2
    fr = np.fft.rfftfreq(nfft, 1.0 / b.fs)
    lo, hi = steps.SNR_FLOOR_BAND_HZ
    floor = np.median(p[(fr > lo) & (fr < min(b.fs / 2, hi))]) / np.log(2.0)
    peaks = [p[np.abs(fr - f) <= b.fs / n].max() if f < b.fs / 2 and n / b.fs * f >= 1 else np.nan for f in freqs]
    return p, np.array(peaks), floor


def test_the_spectrum_in_rows_of_the_four_step_fft_equals_the_padded_one(monkeypatch):
    rng = np.random.default_rng(11)
    freqs = (3.54, 1.77, 7.08, 10.62, 0.1264, 1.18, 24.9, 49.99, 0.2, 0.0101)
    # row lengths giving 2, 4 and 64 rows; records shorter and longer than a row, a power of two and not
    for fs, n, row_bins in ((100.0, 3001, 256), (100.0, 3001, 4096), (200.0, 4096, 8192), (100.0, 1777, 4096)):
        t = np.arange(n) / fs
        x = np.sin(2 * np.pi * 3.54 * t) + 0.3 * np.sin(2 * np.pi * 1.18 * t) + 0.5 * rng.standard_normal(n)
        b = Burst(0, 0.0, fs, x, False)
        p_ref, peaks_ref, floor_ref = _reference_power(b, freqs)
        nfft = 2 * (p_ref.size - 1)
        assert nfft > row_bins  # the rows' path, not the padded transform
        y = (x - x.mean()) * np.hanning(n)
        p = np.full(p_ref.size, np.nan)
        seen = []
        for s, pw in padded_power_rows(y, nfft, row_bins):
            p[s :: nfft // row_bins] = pw
            seen.append(s)
        assert sorted(seen) == list(range(nfft // row_bins))  # every residue once
        np.testing.assert_allclose(p, p_ref, rtol=1e-9, atol=0)
        monkeypatch.setattr(steps, "SNR_ROW_BINS", row_bins)
        peaks, floor = steps._burst_power(b, freqs)
        np.testing.assert_allclose(peaks, peaks_ref, rtol=1e-9, atol=0)  # NaN where skipped, in both
        assert abs(floor / floor_ref - 1) < 1e-9
        monkeypatch.undo()


def test_the_chosen_peak_is_over_the_floor_and_a_frequency_without_a_line_is_not():
    bursts = _bursts()[:3]
    line, noise = steps._snr_at(bursts, [3.54, 17.3])
    assert line > 20.0  # a unit sine in 0.5 noise: far over the median floor
    assert abs(noise) < 10.0  # noise alone: near the floor


def test_the_floor_band_as_a_slice_holds_the_bins_rfftfreq_puts_strictly_inside_it():
    for nfft, fs in ((1 << 25, 200.0), (4096, 100.0), (1024, 2000.0), (1 << 20, 1.0 / 0.37), (256, 20.0)):
        fr = np.fft.rfftfreq(nfft, 1.0 / fs)
        step = 1.0 / (nfft * (1.0 / fs))
        for lo, hi in ((0.2, min(fs / 2, 50.0)), (0.2, fs / 2), (fr[3], fr[9]), (0.0, 1e9), (fs, 2 * fs)):
            k0, k1 = steps._bins_between(step, fr.size, lo, hi)
            assert np.array_equal(np.arange(k0, k1), np.flatnonzero((fr > lo) & (fr < hi))), (nfft, fs, lo, hi)


def test_the_rows_refuse_a_row_length_that_does_not_divide_the_transform():
    import pytest

    with pytest.raises(ValueError, match="row length dividing nfft"):
        padded_power_rows(np.ones(100), 1024, 300)
    with pytest.raises(ValueError, match="at most nfft=64 samples"):
        padded_power_rows(np.ones(100), 64, 16)
