"""Cheaper forms of the signal layer's computations for long records give the numbers of the forms they
replace: the harmonic search's Welch spectrum transformed a block of segments at a time (bit for bit, whatever
the record's length against the block's), the interpolated DFT's frequency without its tone fit (bit for bit),
and ``exp(1j theta)`` from a cosine and a sine (bit for bit where numpy's cosine and sine are the C library's;
within an ulp where numpy vectorises them); scipy's ``sosfiltfilt`` with the filter's initial conditions designed once
(bit for bit); the quantisation error's variance with its constant factors computed once (bit for bit); the harmonic searches'
interpolation asked a harmonic at a time (bit for bit); the quantisation variance without its exponentials that underflow
(bit for bit); the split-half tests with each half's floor computed once (exactly)."""

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


@pytest.mark.parametrize("padtype", ["even", "odd"])
@pytest.mark.parametrize("n, padlen", [(500, 0), (500, 37), (500, 499), (2, 1), (4097, 300)])
def test_sosfiltfilt_with_its_initial_conditions_designed_once_is_scipys_bit_for_bit(padtype, n, padlen):
    import scipy.signal

    from vibkit.signal._checks import filter_with_zi, sosfiltfilt

    x = np.random.default_rng(n + padlen).standard_normal(n).cumsum()
    for sos in (
        scipy.signal.butter(4, 7.5, btype="low", fs=200.0, output="sos"),
        scipy.signal.butter(8, 0.3, btype="low", output="sos"),
        scipy.signal.butter(2, 0.05, btype="low", output="sos"),
    ):
        filt = filter_with_zi(sos)
        want = scipy.signal.sosfiltfilt(sos, x, padtype=padtype, padlen=padlen)
        assert np.array_equal(sosfiltfilt(filt, x, padtype=padtype, padlen=padlen), want)
        assert np.array_equal(sosfiltfilt(filt, x, padtype=padtype, padlen=padlen), want)  # the cached pair unchanged
    with pytest.raises(ValueError, match="padlen=5 must lie in"):
        sosfiltfilt(filt, x[:5], padtype="even", padlen=5)


def test_the_quantisation_error_variance_with_its_factors_computed_once_is_the_formula_bit_for_bit():
    from vibkit.signal.quantisation import correlated_error_variance

    k = np.arange(1, 257, dtype=float)
    for q, s in ((1.0, 0.0), (1.0, 0.3), (0.01, 0.004), (2.5e-6, 1e-7), (3.0, 10.0)):
        z = (s / q) ** 2
        terms = q * q / (2.0 * np.pi**2 * k**2) * np.exp(-4.0 * np.pi**2 * k**2 * z)
        tail = q * q / (2.0 * np.pi**2 * k[-1]) if z == 0 else 0.0
        assert correlated_error_variance(q, s) == float(terms.sum() + tail)


def test_the_quantisation_error_variance_without_its_underflowing_terms_is_the_sum_of_all_256_bit_for_bit():
    """The sum keeps only the terms whose exponential can be nonzero (whole rows of numpy's pairwise sum): over noise
    from 1e-4 to 20 steps (every count of kept terms, 8 to 256) it is the 256-term formula exactly."""
    from vibkit.signal.quantisation import _terms_kept, correlated_error_variance

    k = np.arange(1, 257, dtype=float)
    kept = set()
    rng = np.random.default_rng(5)
    for q in (1.0, 0.0123, 3.7e-5):
        for r in np.concatenate([np.geomspace(1e-4, 20.0, 1500), rng.uniform(0.05, 3.0, 500)]):
            s = r * q
            z = (s / q) ** 2
            terms = q * q / (2.0 * np.pi**2 * k**2) * np.exp(-4.0 * np.pi**2 * k**2 * z)
            assert not np.any(terms[_terms_kept(z) :]), (q, s)  # what is left out is exactly zero
            assert correlated_error_variance(q, s) == float(terms.sum()), (q, s)
            kept.add(_terms_kept(z))
    assert {8, 16, 64, 128, 256} <= kept  # every path taken, the full sum included


def test_the_quantisation_error_variance_past_every_exponentials_underflow_is_the_formulas_zero():
    """Past about 4.4 steps of noise every term's exponential is exactly 0 and the variance is returned as 0 without
    them: across that edge (dense), far past it (a finely quantised record's noise bisection) and at infinite noise,
    the 256-term formula exactly, and the edge really crossed (the formula nonzero just below it)."""
    from vibkit.signal.quantisation import correlated_error_variance

    k = np.arange(1, 257, dtype=float)
    below = 0
    for q in (1.0, 0.0123, 1e-6):
        edge = np.sqrt(745.2 / (4.0 * np.pi**2)) * q
        for s in np.concatenate([np.linspace(0.98 * edge, 1.02 * edge, 4001), [3.0 * edge, 1e4 * q, 1e9 * q, np.inf]]):
            z = (s / q) ** 2
            with np.errstate(invalid="ignore"):
                terms = q * q / (2.0 * np.pi**2 * k**2) * np.exp(-4.0 * np.pi**2 * k**2 * z)
            want = float(terms.sum())
            assert correlated_error_variance(q, s) == want, (q, s)
            below += want > 0
    assert below > 0


def test_interpolation_a_harmonic_at_a_time_is_the_row_order_one_bit_for_bit():
    f = np.fft.rfftfreq(4096, 1 / 200.0)
    p = np.random.default_rng(3).exponential(size=f.size)
    for cands, h in ((np.arange(2.5, 6.25, 0.004), 25), (np.array([3.75]), 7), (np.arange(0.1, 99.0, 0.37), 3)):
        hf = cands[:, None] * np.arange(1, h + 1)[None, :]  # reaches past the last bin too (held at its value)
        got = peaks.interp_by_harmonic(hf, f, p)
        assert got.flags.c_contiguous and got.shape == hf.shape
        assert np.array_equal(got, np.interp(hf.ravel(), f, p).reshape(hf.shape))


def test_the_split_half_tests_with_each_halfs_floor_computed_once_are_the_four_floor_ones_exactly():
    """Each half's spectrum normalised once for its search and its (clipped) test: the tests the loop that normalised
    it for every use gives, with and without excluded lines and a clip, on a family in noise and on noise alone."""
    import dataclasses

    from vibkit.signal import detect

    def four_floors(sp, n_h):
        ia, ib = np.arange(0, sp.k, 2), np.arange(1, sp.k, 2)
        out = []
        for s_idx, t_idx in ((ia, ib), (ib, ia)):
            r_s = detect._normalised(sp.pw[s_idx], sp.half, sp.quant, sp.w, sp.mask)
            r_t = detect._normalised(sp.pw[t_idx], sp.half, sp.quant, sp.w, sp.mask, sp.clip)
            fc, _ = detect._search(r_s, sp.f, sp.df, sp.fmin, sp.fmax, sp.f_top)
            kb = detect._harmonic_bins(fc, sp.df, n_h, sp.f.size)
            if kb.size == 0:
                continue
            t = float(r_t[kb].sum())
            s_t = detect._floor_rel_sd(t_idx.size, 2 * sp.half + 1)
            pv = float(detect.harmonic_sum_pvalue(t, kb.size, t_idx.size, s_t))
            out.append((pv, t, detect.harmonic_sum_threshold(sp.p_fa / 2.0, kb.size, t_idx.size, s_t), fc, kb.size))
        return out

    fs, rng = 200.0, np.random.default_rng(11)
    t = np.arange(int(60 * fs)) / fs
    family = sum(a * np.sin(2 * np.pi * h * 3.61 * t + h) for h, a in ((1, 0.05), (2, 0.03), (3, 0.02)))
    for x in (family + 0.1 * rng.standard_normal(t.size), 0.1 * rng.standard_normal(t.size)):
        x = np.round(x / 1e-3) * 1e-3  # a recorder's step: the floors' quantisation bound takes part
        sp = detect._spectra([x], fs, 2.5, 6.25, 45.0, 1e-3, 1e-3, 1.0)
        assert sp.split
        off = np.abs(sp.f - 1.0 * np.round(sp.f / 1.0))
        for cur in (sp, dataclasses.replace(sp, mask=(off <= 1.5 * sp.df) & (sp.f >= 0.9), clip=4.0)):
            got, want = detect._split_half_tests(cur, 5), four_floors(cur, 5)
            assert len(got) == len(want) == 2
            assert got == want


def test_the_harmonic_evidence_logged_where_it_is_positive_is_the_whole_grids_bit_for_bit():
    """The search's evidence ``max(0, log(max(p, 1e-300) / thr))`` with the log taken only where the ratio is over 1
    (or NaN): noise grids of every shape and threshold, ratios at and around 1, zeros, infinities and NaN."""
    rng = np.random.default_rng(11)
    grids = [rng.exponential(size=shape) for shape in ((1501, 25), (201, 7), (1, 1), (3, 1000), (37_525,))]
    edge = np.array([0.0, 1e-320, 1e-300, 4.0, np.nextafter(4.0, 0), np.nextafter(4.0, 9), 8.0, np.inf, np.nan, 1e300])
    grids.append(np.tile(edge, 7))
    for p in grids:
        for thr in (4.0, 1.0, 0.37, 123.0):
            want = np.maximum(np.log(np.maximum(p, 1e-300) / thr), 0.0)
            got = peaks.log_evidence(p, thr)
            assert got.shape == want.shape and got.dtype == want.dtype
            np.testing.assert_array_equal(got, want)
            assert not np.signbit(got[got == 0]).any()  # +0 where the old form gave +0
