"""Spectrum comparison of non-synchronous simulated and measured signals."""

import numpy as np
import pytest

from vibkit.signal import common_spectrograms, compare_spectra

AMPS = (1.0, 0.6, 0.4, 0.2)


def family(f0, fs, seconds, *, seed, third_factor=1.0, gain=1.0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    x = np.zeros(t.size)
    for k, a in enumerate(AMPS):
        fk = (k + 1) * f0 * (third_factor if k == 2 else 1.0)
        x += gain * a * np.cos(2 * np.pi * fk * t + rng.uniform(0, 2 * np.pi))
    return x + rng.standard_normal(t.size) * np.std(x)  # 0 dB


def test_detects_half_percent_fundamental_mismatch_in_10s_at_0db():
    sim = family(3.75, 2050.0, 10.0, seed=1)
    meas = family(3.75 * 1.005, 1000.0, 10.0, seed=2)  # other rate, other start phase
    c = compare_spectra(sim, 2050.0, meas, 1000.0, n_harmonics=4)
    for row in c.harmonics:
        assert row.frequency_mismatch
        assert row.frequency_ratio_ci[0] > 1.0
        assert row.frequency_ratio == pytest.approx(1.005, abs=0.001)
        assert row.order_meas == pytest.approx(row.order, abs=0.002)
    assert c.fundamental_meas_hz / c.fundamental_sim_hz == pytest.approx(1.005, abs=2e-4)
    assert c.score < 1.0


def test_detects_half_percent_mismatch_of_one_harmonic_in_order_domain():
    sim = family(3.75, 2050.0, 10.0, seed=3)
    meas = family(3.75, 1000.0, 10.0, seed=4, third_factor=1.005)
    c = compare_spectra(sim, 2050.0, meas, 1000.0, n_harmonics=4)
    flagged = [row.order for row in c.harmonics if row.frequency_mismatch]
    assert flagged == [3]
    # the fitted fundamental absorbs part of the shift, so the order reads between 3.005 and 3.015
    assert 3.005 < c.harmonics[2].order_meas < 3.016
    assert c.harmonics[2].frequency_ratio == pytest.approx(1.005, abs=0.001)


def test_no_mismatch_and_amplitude_difference_within_ci():
    sim = family(3.75, 2050.0, 10.0, seed=5)
    meas = family(3.75, 1000.0, 10.0, seed=6, gain=2.0)  # +6.02 dB
    c = compare_spectra(sim, 2050.0, meas, 1000.0, n_harmonics=4)
    assert not c.any_frequency_mismatch
    for row in c.harmonics[:3]:
        lo, hi = row.amplitude_diff_db_ci
        assert lo - 0.5 < 20 * np.log10(2.0) < hi + 0.5
    assert 0.0 <= c.score <= 1.0
    assert c.log_spectral_distance_db > 0


def test_identical_signals_agree_perfectly():
    x = family(3.75, 1000.0, 10.0, seed=7)
    c = compare_spectra(x, 1000.0, x, 1000.0, n_harmonics=4)
    assert c.score == pytest.approx(1.0)
    assert c.log_spectral_distance_db == pytest.approx(0.0, abs=1e-9)


def test_common_spectrograms_share_axes():
    a = family(3.75, 2050.0, 20.0, seed=8)
    b = family(3.8, 1000.0, 15.0, seed=9)
    out = common_spectrograms(a, 2050.0, b, 1000.0, fmax=50.0, frame_s=4.0)
    assert out["amplitude_sim"].shape[0] == out["amplitude_meas"].shape[0] == out["frequency_hz"].size
    assert out["frequency_hz"][-1] <= 50.0
    with pytest.raises(ValueError, match="fmax"):
        common_spectrograms(a, 2050.0, b, 100.0, fmax=60.0, frame_s=4.0)


def test_bad_arguments():
    x = family(3.75, 1000.0, 10.0, seed=10)
    with pytest.raises(ValueError, match="fs_meas"):
        compare_spectra(x, 1000.0, x, 0.0)
    with pytest.raises(ValueError, match="band"):
        compare_spectra(x, 1000.0, x, 1000.0, band=(2.0, 900.0))
