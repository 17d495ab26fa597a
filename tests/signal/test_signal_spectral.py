"""Spectra against analytic truths: sine amplitude, Parseval, PSD integral = variance, CI coverage."""

import numpy as np
import pytest

from vibkit.signal import amplitude_spectrum, spectrogram, study_power_spectrum, welch_psd

FS = 1000.0


def test_sine_amplitude_reads_a_on_bin_for_every_window():
    t = np.arange(4000) / FS
    x = 2.5 * np.sin(2 * np.pi * 50.0 * t) + 0.7
    # cosine-sum windows have exact zeros 400 bins away (the negative-frequency image); Kaiser's
    # sidelobes there are about 1e-7.
    for window, rel in (("hann", 1e-10), ("boxcar", 1e-10), ("hamming", 1e-10), (("kaiser", 8.0), 1e-6)):
        f, a = amplitude_spectrum(x, FS, window=window)
        k = np.argmin(np.abs(f - 50.0))
        assert a[k] == pytest.approx(2.5, rel=rel)


def test_parseval_boxcar():
    rng = np.random.default_rng(0)
    for n in (1000, 1001):
        x = rng.standard_normal(n)
        _, a = amplitude_spectrum(x, FS, window="boxcar", detrend=False)
        nyq = a[-1] ** 2 if n % 2 == 0 else a[-1] ** 2 / 2
        total = a[0] ** 2 + np.sum(a[1:-1] ** 2) / 2 + nyq
        assert total == pytest.approx(np.mean(x**2), rel=1e-12)


def test_study_power_definition():
    n = 1000
    t = np.arange(n) / FS
    x = 3.0 * np.cos(2 * np.pi * 100.0 * t)  # bin 200 of the 2N-point FFT
    f, p = study_power_spectrum(x, FS, frequency_axis="exact")
    assert f[200] == pytest.approx(100.0)
    assert p[200] == pytest.approx(3.0**2 / 4, rel=1e-12)
    fs_, _ = study_power_spectrum(x, FS)
    assert fs_[-1] == pytest.approx(FS / 2) and fs_.size == n


def test_welch_integral_equals_variance_and_sine_power():
    rng = np.random.default_rng(1)
    x = 0.3 * rng.standard_normal(200_000)
    r = welch_psd(x, FS, nperseg=1024)
    df = r.frequency_hz[1] - r.frequency_hz[0]
    assert np.sum(r.psd) * df == pytest.approx(np.var(x), rel=0.01)
    t = np.arange(200_000) / FS
    s = 2.0 * np.sin(2 * np.pi * 123.0 * t)
    r = welch_psd(s, FS, nperseg=1000)
    assert np.sum(r.psd) * df * 1024 / 1000 == pytest.approx(2.0**2 / 2, rel=1e-3)


def test_welch_confidence_interval_coverage():
    rng = np.random.default_rng(2)
    sigma2 = 2.0
    true = 2 * sigma2 / FS  # one-sided white PSD
    hits = []
    for _ in range(40):
        r = welch_psd(np.sqrt(sigma2) * rng.standard_normal(8192), FS, nperseg=512, confidence=0.9)
        inner = slice(2, -2)
        hits.append(np.mean((r.lower[inner] <= true) & (true <= r.upper[inner])))
    assert np.mean(hits) == pytest.approx(0.9, abs=0.03)


def test_spectrogram_amplitude_scaling():
    t = np.arange(8000) / FS
    x = 1.5 * np.cos(2 * np.pi * 125.0 * t)
    f, _, s = spectrogram(x, FS, nperseg=256)
    k = np.argmin(np.abs(f - 125.0))
    assert np.allclose(s[k], 1.5, rtol=1e-9)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: amplitude_spectrum(np.ones(10), 0.0), "fs"),
        (lambda: amplitude_spectrum(np.array([]), 1.0), "empty"),
        (lambda: amplitude_spectrum(np.full(10, np.nan), 1.0), "all NaN"),
        (lambda: amplitude_spectrum(np.r_[1.0, np.nan, 2.0], 1.0), "NaN"),
        (lambda: welch_psd(np.ones(100), 1.0, nperseg=200), "nperseg"),
        (lambda: spectrogram(np.ones(100), 1.0, nperseg=101), "nperseg"),
        (lambda: welch_psd(np.ones(100), 1.0, confidence=1.5), "confidence"),
    ],
)
def test_bad_arguments_name_the_parameter(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_nan_interpolate_policy_fills_linearly():
    x = np.arange(10.0)
    y = x.copy()
    y[4] = np.nan
    _, a = amplitude_spectrum(y, 1.0, window="boxcar", detrend=False, nan_policy="interpolate")
    _, b = amplitude_spectrum(x, 1.0, window="boxcar", detrend=False)
    np.testing.assert_allclose(a, b, rtol=1e-12)
