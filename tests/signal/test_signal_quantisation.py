"""Quantised records: the recorder's step, the error that follows the signal, the floor they set, and the
link-pass detection of clean quantised tones (a 2048-count tone at 3.5 Hz was found as a family at 3.14 Hz)."""

import numpy as np
import pytest
import scipy.stats

from vibkit.signal.detect import detect_link_pass
from vibkit.signal.quantisation import correlated_error_variance, quantisation_floor, quantisation_step

FS = 200.0
BAND = (0.4667 / 0.2, 0.4667 / 0.08)  # 2.33 .. 5.83 Hz


def test_step_of_integer_and_scaled_levels():
    rng = np.random.default_rng(1)
    counts = np.round(40 * rng.standard_normal(5000))
    assert quantisation_step(counts) == 1.0
    # an offset and a step that floating point cannot hold exactly (1/3)
    assert quantisation_step(7.25 + counts / 3.0) == pytest.approx(1 / 3, rel=1e-9)
    assert quantisation_step(np.array([0.0, 0.25, 1.0, -0.5])) == 0.25
    # a full-scale 16-bit tone: no two levels one count apart in one period, the step is still 1
    t = np.arange(400) / FS
    tone = np.round(32767 * np.sin(2 * np.pi * 3.5 * t))
    assert np.min(np.diff(np.unique(tone))) > 1
    assert quantisation_step(tone) == 1.0


@pytest.mark.parametrize(
    "x", [np.random.default_rng(2).standard_normal(3000), np.full(100, 4.0), np.sqrt([2.0, 3.0, 5.0, 7.0, 11.0, 13.0])]
)
def test_no_step_for_continuous_or_constant_data(x):
    assert quantisation_step(x) == 0.0


def test_correlated_error_variance_against_its_limits_and_monte_carlo():
    # without noise the whole error q^2/12 follows the signal (sum 1/(2 pi^2 k^2) = 1/12)
    assert correlated_error_variance(2.0, 0.0) == pytest.approx(4.0 / 12.0, rel=1e-3)
    # at half a step of noise only the first term is left: q^2/(2 pi^2) exp(-pi^2)
    assert correlated_error_variance(1.0, 0.5) == pytest.approx(np.exp(-(np.pi**2)) / (2 * np.pi**2), rel=1e-3)
    # Monte Carlo: the variance over the input of the noise-averaged rounding error
    rng = np.random.default_rng(3)
    x = np.linspace(0.0, 1.0, 200, endpoint=False)[:, None]  # one step, evenly: the average over the input
    n = 20000
    for s in (0.1, 0.2, 0.3):
        e = np.round(x + s * rng.standard_normal((1, n))) - x
        # the conditional means' own sampling noise adds var(e | x) / n: removed
        v = np.var(e.mean(axis=1)) - np.mean(e.var(axis=1)) / n
        assert v == pytest.approx(correlated_error_variance(1.0, s), rel=0.05)


def test_floor_white_with_noise_and_one_line_without():
    w = np.hanning(1000)
    s1, s2 = np.sum(w), np.sum(w * w)
    q = 1.0
    # noise of two steps: the white level q^2/12 per sample (the line term is 1e-70 of it)
    noisy = (4.0 + q * q / 12) * s2
    assert quantisation_floor(q, w, noisy) == pytest.approx(q * q / 12 * s2, rel=1e-12)
    # no broadband noise at all: one line carrying the whole error q^2/12
    assert quantisation_floor(q, w, 0.0) == pytest.approx(q * q / 12 * s1 * s1 / 2, rel=1e-3)
    # decimated by 4: the white level per analysed sample is a quarter
    assert quantisation_floor(q, w, 4 * noisy, decimation=4) == pytest.approx(q * q / 48 * s2, rel=1e-12)
    assert quantisation_floor(0.0, w, 0.0) == 0.0


@pytest.mark.parametrize("amplitude", [3, 127, 2048, 32767])
def test_quantised_tone_detected_at_its_frequency(amplitude):
    t = np.arange(0, 120, 1 / FS)
    rng = np.random.default_rng(amplitude)
    for f0 in (2.5, 3.5, 4.123, 5.5):
        for noise in (0.0, 0.3):
            x = amplitude * np.sin(2 * np.pi * f0 * t + rng.uniform(0, 2 * np.pi)) + noise * rng.standard_normal(t.size)
            for rounded in (True, False):
                d = detect_link_pass(np.round(x) if rounded else x, FS, band=BAND)
                assert d.detected, (f0, noise, rounded, d.reason)
                # the detector's stated resolution is its bin, 1 / segment
                assert abs(d.frequency_hz - f0) <= 1.0 / d.segment_s, (f0, noise, rounded, d.frequency_hz)
                # one line: no harmonic of the rounding error counts as the family's
                assert d.significant_orders == (1,), (f0, noise, rounded, d.significant_orders)


@pytest.mark.slow
def test_quantised_noise_keeps_its_false_alarm_rate():
    """Noise-only records rounded to a step of 0.2 .. 3 noise sigmas: false alarms at most p_fa."""
    rng = np.random.default_rng(19)
    n_rec, p_fa = 400, 0.05
    hits = 0
    for i in range(n_rec):
        sd = (0.2, 0.5, 1.0, 3.0)[i % 4]
        hits += detect_link_pass(
            np.round(sd * rng.standard_normal(3000)), 100.0, band=(2.45, 6.125), p_fa=p_fa
        ).detected
    assert hits <= scipy.stats.binom.ppf(0.999, n_rec, p_fa)
