"""The hypotheses' signal-to-floor ratios: each burst transformed once, the same numbers as the full spectrum."""

import numpy as np

from vibkit.diagnose import pitch_steps as steps
from vibkit.signal.bursts import Burst


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
    spectra = {}
    # the chosen peak, its readings, the consequences, the band edges, near Nyquist and a too-low one (skipped)
    freqs = (3.54, 1.77, 7.08, 10.62, 0.1264, 1.18, 24.9, 49.99, 0.2, 0.0101, 0.5 * 3.54 / 3)
    for f in freqs:
        got = steps._snr_at(bursts, f, spectra)
        want = _reference_snr(bursts, f)
        assert (np.isnan(got) and np.isnan(want)) or got == want, (f, got, want)
        assert steps._snr_at(bursts, f) == got or np.isnan(got)  # without the shared dict: the same
    assert set(spectra) == {0, 1, 2, 3}  # every burst transformed, each once (a dict entry per burst)


def test_the_chosen_peak_is_over_the_floor_and_a_frequency_without_a_line_is_not():
    bursts = _bursts()[:3]
    assert steps._snr_at(bursts, 3.54) > 20.0  # a unit sine in 0.5 noise: far over the median floor
    assert abs(steps._snr_at(bursts, 17.3)) < 10.0  # noise alone: near the floor


def test_the_floor_band_as_a_slice_holds_the_bins_rfftfreq_puts_strictly_inside_it():
    for nfft, fs in ((1 << 25, 200.0), (4096, 100.0), (1024, 2000.0), (1 << 20, 1.0 / 0.37), (256, 20.0)):
        fr = np.fft.rfftfreq(nfft, 1.0 / fs)
        step = 1.0 / (nfft * (1.0 / fs))
        for lo, hi in ((0.2, min(fs / 2, 50.0)), (0.2, fs / 2), (fr[3], fr[9]), (0.0, 1e9), (fs, 2 * fs)):
            k0, k1 = steps._bins_between(step, fr.size, lo, hi)
            assert np.array_equal(np.arange(k0, k1), np.flatnonzero((fr > lo) & (fr < hi))), (nfft, fs, lo, hi)
