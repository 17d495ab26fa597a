"""Frequency estimators against the Cramer-Rao bound (Monte Carlo, fixed seeds) and octave safety."""

import numpy as np
import pytest

from vibkit.signal import (
    crb_harmonic,
    crb_single_tone,
    find_fundamental,
    harmonic_ls,
    interpolated_dft,
    link_pass_estimate,
)

FS = 100.0
N = 1000
T = np.arange(N) / FS


def test_harmonic_ls_within_1p2_of_harmonic_crb_and_sigma_matches_spread():
    rng = np.random.default_rng(10)
    amps = np.array([0.5, 1.0, 0.3])  # second harmonic stronger than the fundamental
    noise = np.sqrt(np.sum(amps**2) / 2)  # 0 dB
    f0 = 3.7512
    err, sig = [], []
    for _ in range(200):
        ph = rng.uniform(0, 2 * np.pi, 3)
        x = sum(a * np.cos(2 * np.pi * (k + 1) * f0 * T + p) for k, (a, p) in enumerate(zip(amps, ph)))
        x = x + noise * rng.standard_normal(N)
        r = harmonic_ls(x, FS, f_guess=f0 + 0.01, n_harmonics=3)
        err.append(r.frequency_hz - f0)
        sig.append(r.sigma_hz)
    rms = np.sqrt(np.mean(np.square(err)))
    bound = crb_harmonic(N, FS, amps, noise)
    assert rms <= 1.2 * bound
    assert np.mean(sig) / rms == pytest.approx(1.0, abs=0.15)


def test_interpolated_dft_within_2x_single_tone_crb_and_sigma_matches_spread():
    rng = np.random.default_rng(11)
    err, sig = [], []
    for i in range(300):
        f0 = (123 + (i % 10) / 10) * FS / N  # offsets across the bin
        x = np.cos(2 * np.pi * f0 * T + rng.uniform(0, 2 * np.pi)) + rng.standard_normal(N) / np.sqrt(2)
        r = interpolated_dft(x, FS)
        err.append(r.frequency_hz - f0)
        sig.append(r.sigma_hz)
    rms = np.sqrt(np.mean(np.square(err)))
    assert rms <= 2.0 * crb_single_tone(N, FS, 1.0)
    assert np.mean(sig) / rms == pytest.approx(1.0, abs=0.15)


def test_crb_constant_is_the_real_sine_value():
    # one harmonic: the harmonic bound reduces to the single-tone bound
    assert crb_harmonic(N, FS, [2.0], 1.0) == pytest.approx(crb_single_tone(N, FS, 2.0))
    # var = 12 fs^2 / ((2 pi)^2 snr N (N^2 - 1))
    assert crb_single_tone(N, FS, 1.0) ** 2 == pytest.approx(12 * FS**2 / ((2 * np.pi) ** 2 * N * (N**2 - 1)))


def test_fundamental_no_octave_error_when_a_harmonic_dominates():
    rng = np.random.default_rng(12)
    fs = 512.0
    t = np.arange(int(10 * fs)) / fs
    for trial in range(30):
        f0 = rng.uniform(2.2, 5.8)
        amps = rng.uniform(0.05, 1.0, 6)
        amps[1] = 2.0
        if trial % 2:
            amps[0] = 0.05  # fundamental below the noise: the odd third harmonic identifies it
            amps[2] = 0.5
        x = sum(a * np.cos(2 * np.pi * (k + 1) * f0 * t + rng.uniform(0, 6.3)) for k, a in enumerate(amps))
        x = x + rng.standard_normal(t.size) * np.sqrt(np.sum(amps**2) / 2)
        r = find_fundamental(x, fs, band=(1.5, 6.0))  # two octaves
        assert r.frequency_hz == pytest.approx(f0, rel=0.005)


def test_link_pass_estimate_one_call():
    rng = np.random.default_rng(13)
    fs = 2050.0
    t = np.arange(int(10 * fs)) / fs
    f0 = 3.742
    x = (
        0.2 * np.cos(2 * np.pi * f0 * t)
        + 1.0 * np.cos(2 * np.pi * 2 * f0 * t + 1)
        + 0.1 * np.cos(2 * np.pi * 3 * f0 * t)
    )
    x += rng.standard_normal(t.size)
    r = link_pass_estimate(x, fs, band=(2.0, 6.0), n_harmonics=4)
    assert abs(r.fundamental_hz - f0) < 4 * r.fundamental_sigma_hz
    assert [h.order for h in r.harmonics] == [1, 2, 3, 4]
    assert r.harmonics[1].amplitude == pytest.approx(1.0, abs=0.05)
    assert r.harmonics[1].frequency_hz == pytest.approx(2 * r.fundamental_hz)
    assert r.harmonics[0].detected and not r.harmonics[3].detected
    fast = link_pass_estimate(x, fs, band=(2.0, 6.0), method="interpolated-dft")
    assert abs(fast.fundamental_hz - f0) < 4 * fast.fundamental_sigma_hz


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: find_fundamental(np.ones(1000), 100.0, band=(2.0, 60.0)), "Nyquist"),
        (
            lambda: find_fundamental(np.random.default_rng(0).standard_normal(100), 100.0, band=(2.0, 6.0)),
            "three periods",
        ),
        (lambda: harmonic_ls(np.ones(1000), 100.0, f_guess=20.0, n_harmonics=3), "Nyquist"),
        (lambda: harmonic_ls(np.ones(100), 100.0, f_guess=0.5), "two periods"),
        (lambda: interpolated_dft(np.ones(100), -1.0), "fs"),
        (lambda: link_pass_estimate(np.ones(100), 100.0, method="magic"), "method"),
    ],
)
def test_bad_arguments(call, match):
    with pytest.raises(ValueError, match=match):
        call()


@pytest.mark.parametrize("f0", [2.3, 3.75, 5.1])
def test_noise_free_simulated_signal(f0):
    # simulations are (nearly) noise free: leakage must not be taken for harmonics
    t = np.arange(20000) / 2000.0
    x = 0.3 * np.cos(2 * np.pi * f0 * t) + np.cos(4 * np.pi * f0 * t) + 0.1 * np.cos(6 * np.pi * f0 * t + 1)
    r = link_pass_estimate(x, 2000.0, band=(2.0, 6.0), n_harmonics=3)
    assert r.fundamental_hz == pytest.approx(f0, rel=1e-6)
    assert [h.amplitude for h in r.harmonics] == pytest.approx([0.3, 1.0, 0.1], rel=1e-3)


def test_harmonic_ls_in_blocks_is_the_whole_matrix_fit(monkeypatch):
    """The least squares accumulate their sums over blocks of rows (bounded memory on a day-long record): with
    blocks of 777 rows the fit is the one-block (whole-matrix) fit to rounding, and both find the true tone."""
    import vibkit.signal.estimate as est

    rng = np.random.default_rng(8)
    fs, f, n = 100.0, 3.54, 5000
    t = np.arange(n) / fs
    x = 0.2 + np.sin(2 * np.pi * f * t) + 0.4 * np.cos(2 * np.pi * 2 * f * t + 0.3) + 0.3 * rng.standard_normal(n)
    whole = harmonic_ls(x, fs, f_guess=f * (1 + 3e-5), n_harmonics=4)
    monkeypatch.setattr(est, "LS_BLOCK_ROWS", 777)
    blocked = harmonic_ls(x, fs, f_guess=f * (1 + 3e-5), n_harmonics=4)
    assert blocked.frequency_hz == pytest.approx(whole.frequency_hz, rel=1e-12)
    np.testing.assert_allclose(blocked.amplitudes, whole.amplitudes, rtol=1e-12)
    np.testing.assert_allclose(blocked.phases, whole.phases, rtol=0, atol=1e-12)
    assert blocked.noise_std == pytest.approx(whole.noise_std, rel=1e-12)
    assert blocked.offset == pytest.approx(whole.offset, rel=1e-12)
    assert abs(blocked.frequency_hz - f) < 5 * blocked.sigma_hz  # and both are right
    np.testing.assert_allclose(blocked.amplitudes[:2], [1.0, 0.4], atol=0.03)


def test_mean_link_pass_frequency_fit_in_blocks_is_the_whole_matrix_fit(monkeypatch):
    """The record-wide harmonic fit behind the mean link-pass frequency sums its normal equations over blocks:
    blocks of 1,000 rows give the one-block fit to rounding (1e-12), and the truth within its sigma."""
    import importlib

    meanfreq = importlib.import_module("vibkit.signal.meanfreq")
    rng = np.random.default_rng(21)
    fs, f, n = 100.0, 3.54, 12_000
    t = np.arange(n) / fs
    x = np.sin(2 * np.pi * f * t) + 0.4 * np.sin(4 * np.pi * f * t + 1.0) + 0.5 * rng.standard_normal(n)
    whole = meanfreq.mean_link_pass_frequency(x, fs, f0=f)
    monkeypatch.setattr(meanfreq, "FIT_BLOCK_ROWS", 1000)
    blocked = meanfreq.mean_link_pass_frequency(x, fs, f0=f)
    assert blocked.frequency_hz == pytest.approx(whole.frequency_hz, rel=1e-12)
    assert blocked.sigma_hz == pytest.approx(whole.sigma_hz, rel=1e-12)
    assert abs(blocked.frequency_hz - f) < 4 * blocked.sigma_hz


@pytest.mark.parametrize("fs", [200.0, 1000.0])
def test_link_pass_sigma_is_the_recorded_noise_s_bound_whether_or_not_the_fit_decimates(fs):
    """A fast recorder's record is decimated for the fit (1 kHz: q = 9; 200 Hz with 4 harmonics: q = 2), and the
    anti-alias low-pass keeps about 0.8 of the new band's white noise.  The stated sigma must still be the
    Cramer-Rao bound of the noise as recorded (read from the fit's residual, so within a few per cent), not
    sqrt(0.8) = 0.89 of it, and the harmonics' detection flags must use the same noise."""
    f0, amps, noise, seconds = 3.75, np.array([1.0, 0.5, 0.3, 0.2]), 3.0, 60
    t = np.arange(int(seconds * fs)) / fs
    ratios = []
    for seed in range(4):
        rng = np.random.default_rng(seed)
        ph = rng.uniform(0, 2 * np.pi, amps.size)
        x = sum(a * np.cos(2 * np.pi * (k + 1) * f0 * t + p) for k, (a, p) in enumerate(zip(amps, ph)))
        x = x + rng.normal(0.0, noise, t.size)
        r = link_pass_estimate(x, fs, band=(2.5, 6.0), n_harmonics=4)
        fitted = np.array([h.amplitude for h in r.harmonics])
        ratios.append(r.fundamental_sigma_hz / crb_harmonic(t.size, fs, fitted, noise))
    assert np.median(ratios) == pytest.approx(1.0, abs=0.05)
    assert max(ratios) < 1.08 and min(ratios) > 0.92
