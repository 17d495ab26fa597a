"""The steady-line detector's null: a periodogram bin over the running median of its neighbours, against a Monte
Carlo of Gaussian noise (the floor's error integrated by its exact law, not as a Gaussian)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vibkit.signal import steadyline as sl

FS = 100.0


def _bins_and_maxima(rng, seconds, records, lo=2.0, hi=45.0):
    """White Gaussian noise: (the normalised periodogram at its unpadded bins in lo-hi, each record's maximum over
    the padded grid in lo-hi, the floor's half-width)."""
    n = int(round(seconds * FS))
    bins, maxima = [], []
    for _ in range(records // 500):
        _, _, _, r = sl._spectra(rng.standard_normal((500, n)), FS, 4, 1.0)
        f = np.fft.rfftfreq(2 * (r.shape[1] - 1), 1.0 / FS)
        step = (2 * (r.shape[1] - 1)) // n
        inband = np.flatnonzero((f >= lo) & (f <= hi))
        maxima.append(r[:, inband].max(axis=1))
        bins.append(r[:, inband[inband % step == 0]].ravel())
    return np.concatenate(bins), np.concatenate(maxima), sl._floor_half(n, FS, 4, 1.0)


@pytest.mark.parametrize("seconds", [11.0, 20.0])
def test_the_floors_exact_law_bounds_a_bins_tail_and_is_not_loose(seconds):
    """P(bin > s floor) measured on 3000 records (1.5-2.6 million bins) at 9-12 dB: the stated tail is at least the
    measured rate less three binomial errors, and at most 3.5 times it (the Gaussian floor error it replaces stated
    5-35 times the rate at 11-12 dB: this fails on it)."""
    bins, _, half = _bins_and_maxima(np.random.default_rng(5), seconds, 3000)
    h = sl._floor_law(half, [1.0])
    for db in (9, 10, 11, 12):
        s = 10 ** (db / 10)
        rate = float(np.mean(bins > s))
        err = math.sqrt(rate / bins.size)
        stated = sl._tail_floored(s, [1.0], h)
        assert stated >= rate - 3 * err, (db, stated, rate)
        assert stated <= 3.5 * (rate + 3 * err), (db, stated, rate)


def test_the_band_maximums_bound_holds_on_the_padded_grid():
    """The maximum over 2-45 Hz of 4000 records of 15 s: the rate at which it exceeds 11-13 dB is within three
    binomial errors under the stated ``GRID_FACTOR M`` times the per-frequency tail."""
    _, maxima, half = _bins_and_maxima(np.random.default_rng(6), 15.0, 4000)
    m = sl.GRID_FACTOR * 43.0 * 15.0
    for db in (11, 12, 13):
        s = 10 ** (db / 10)
        rate = float(np.mean(maxima > s))
        assert rate - 3 * math.sqrt(max(rate, 1 / maxima.size) / maxima.size) <= m * sl._tail_floored(
            s, [1.0], sl._floor_law(half, [1.0])
        ), db


def test_the_floor_law_is_exact_for_independent_bins():
    """With independent Exp(1) bins (no window's correlation), the order statistic's transform gives the rate at
    which the centre of a 2 h + 1 window exceeds s times its median over ln 2: 400 000 windows, within 4 %."""
    rng = np.random.default_rng(9)
    h = 8
    e = rng.exponential(size=(400_000, 2 * h + 1))
    ratio = e[:, h] / (np.median(e, axis=1) / math.log(2.0))
    for s in (4.0, 8.0):
        rate = float(np.mean(ratio > s))
        assert sl._laplace_floor(s, h)[0] == pytest.approx(rate, rel=4 * math.sqrt(1 / (rate * ratio.size)) + 0.02)
