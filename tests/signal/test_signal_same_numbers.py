"""Cheaper forms of the signal layer's computations for long records give the numbers of the forms they
replace: the harmonic search's Welch spectrum transformed a block of segments at a time (bit for bit, whatever
the record's length against the block's), the interpolated DFT's frequency without its tone fit (bit for bit),
and ``exp(1j theta)`` from a cosine and a sine (bit for bit where numpy's cosine and sine are the C library's;
within an ulp where numpy vectorises them)."""

import numpy as np
import pytest

from vibkit.signal import peaks


def _loop(x, nseg, step, w, nfft):
    """The sum written out as the search computed it: one transform per segment, added in order."""
    p = np.zeros(nfft // 2 + 1)
    for a in range(0, x.size - nseg + 1, step):
        seg = x[a : a + nseg]
        p += np.abs(np.fft.rfft((seg - seg.mean()) * w, nfft)) ** 2
    return p


@pytest.mark.parametrize(
    ("n", "nseg", "nfft"),
    [(20_011, 800, 4096), (1600, 1600, 8192), (5_003, 333, 2048), (7_777, 1000, 4096), (3_001, 64, 256)],
)
def test_blocked_welch_sum_equals_the_segment_loop_bit_for_bit(n, nseg, nfft, monkeypatch):
    rng = np.random.default_rng(n)
    x = 3.0 * rng.standard_normal(n) + 1.0 + np.sin(2 * np.pi * 0.013 * np.arange(n))
    w = np.hanning(nseg)
    step = max(1, nseg // 2)
    count = len(range(0, n - nseg + 1, step))
    # blocks of a few rows: the number of segments is not a multiple of the block
    monkeypatch.setattr(peaks, "WELCH_BLOCK_VALUES", 3 * nfft)
    got = peaks._welch_sum(x, nseg, step, count, w, nfft)
    assert np.array_equal(got, _loop(x, nseg, step, w, nfft))
    monkeypatch.setattr(peaks, "WELCH_BLOCK_VALUES", 1 << 21)
    assert np.array_equal(peaks._welch_sum(x, nseg, step, count, w, nfft), got)


def test_the_interpolated_frequency_alone_is_the_interpolated_dfts_bit_for_bit():
    from vibkit.signal.estimate import interpolated_dft, interpolated_frequency

    rng = np.random.default_rng(7)
    fs = 200.0
    t = np.arange(40_001) / fs
    x = np.cos(2 * np.pi * 7.5031 * t + 0.3) + 0.4 * np.cos(2 * np.pi * 3.75155 * t) + 0.3 * rng.standard_normal(t.size)
    for kw in ({"band": (7.0, 8.0)}, {"f_guess": 7.5}, {"band": (3.5, 4.0), "iterations": 2}, {}):
        assert interpolated_frequency(x, fs, **kw) == interpolated_dft(x, fs, **kw).frequency_hz


def test_expj_is_the_complex_exponential_of_an_imaginary_argument():
    from vibkit.signal.estimate import expj

    rng = np.random.default_rng(11)
    for theta in (
        2 * np.pi * 0.0187654321 * np.arange(100_000),  # the DTFT's angles, far from zero
        (np.arange(20_001) - 10_000) / 200.0 * 23.5619,  # a harmonic basis' angles, both signs
        -3.0 * np.cumsum(rng.random(5_000)),  # a demodulation's
        np.array([0.0, -0.0, np.pi, -np.pi / 2, 1e-300]),
    ):
        got, ref = expj(theta), np.exp(1j * theta)
        assert got.dtype == ref.dtype and got.shape == ref.shape
        np.testing.assert_allclose(got.view(float), ref.view(float), rtol=0, atol=1e-15)
