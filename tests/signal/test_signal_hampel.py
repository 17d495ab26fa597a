"""Hampel filter: identical to a plain reference loop (MATLAB definition), events, false-alarm mode."""

import numpy as np
import pytest
from scipy.stats import norm

from vibkit.signal import hampel, hampel_events, hampel_false_alarm_rate, hampel_n_sigma_for_rate


def reference_hampel(x, k, n_sigma):
    """Direct transcription of MATLAB's definition (NaN ignored inside windows)."""
    n = x.size
    y, j = x.copy(), np.zeros(n, bool)
    med, sig = np.empty(n), np.empty(n)
    for i in range(n):
        w = x[max(0, i - k) : i + k + 1]
        w = w[~np.isnan(w)]
        if w.size == 0:
            med[i] = sig[i] = np.nan
            continue
        m = np.median(w)
        s = 1.4826 * np.median(np.abs(w - m))
        med[i], sig[i] = m, s
        if not np.isnan(x[i]) and abs(x[i] - m) > n_sigma * s:
            j[i], y[i] = True, m
    return y, j, med, sig


def test_identical_to_reference_on_random_data_with_outliers_and_edges():
    rng = np.random.default_rng(0)
    for trial in range(60):
        n = int(rng.integers(5, 400))
        k = int(rng.integers(1, (n - 1) // 2 + 1))
        x = rng.standard_normal(n)
        x[rng.random(n) < 0.05] *= 25.0
        if trial % 3 == 0:
            x[rng.random(n) < 0.1] = np.nan
        if trial % 4 == 0:
            x = np.round(x)  # ties and zero MAD
        ns = float(rng.uniform(0, 4))
        got = hampel(x, k, ns)
        want = reference_hampel(x, k, ns)
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b)


def test_identical_to_reference_long_record_chunked():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(120_000)
    x[::997] += 40.0
    x[::1009] = np.nan
    got = hampel(x, 4, 3.0)
    want = reference_hampel(x[:3000], 4, 3.0)
    np.testing.assert_array_equal(got.filtered[:2996], want[0][:2996])
    tail = reference_hampel(x[-3000:], 4, 3.0)
    np.testing.assert_array_equal(got.filtered[-2996:], tail[0][-2996:])
    spikes = np.arange(0, x.size, 997)
    assert got.is_outlier[spikes[1:-1]].all()


def test_axis_and_fill_nan():
    rng = np.random.default_rng(2)
    x = rng.standard_normal((3, 50))
    x[1, 10] = np.nan
    r = hampel(x.T, 3, 3, axis=0)
    for i in range(3):
        np.testing.assert_array_equal(r.filtered[:, i], reference_hampel(x[i], 3, 3)[0])
    f = hampel(x[1], 3, 3, fill_nan=True).filtered
    assert f[10] == reference_hampel(x[1], 3, 3)[2][10]


def test_events_report_spikes_with_time_and_size():
    rng = np.random.default_rng(3)
    fs = 100.0
    x = 0.01 * rng.standard_normal(2000)
    x[500] += 1.0
    x[1200:1202] -= 0.8
    ev = hampel_events(x, fs, half_window=5, n_sigma=20.0, t0=10.0)
    assert [e.index for e in ev] == [500, 1200] or [e.index for e in ev] == [500, 1201]
    assert ev[0].time_s == pytest.approx(15.0)
    assert ev[0].deviation == pytest.approx(1.0, abs=0.05) and ev[0].size_sigma > 50
    assert ev[1].stop - ev[1].start == 2 and ev[1].deviation < 0


@pytest.mark.slow
def test_false_alarm_rate_is_what_n_sigma_really_gives():
    rng = np.random.default_rng(4)
    x = rng.standard_normal(400_000)
    for k in (3, 10):
        observed = np.mean(hampel(x, k, 3.0).is_outlier[k:-k])
        stated = hampel_false_alarm_rate(k, 3.0)
        assert observed == pytest.approx(stated, rel=0.05)
        assert stated > 2 * norm.sf(3.0)  # well above the asymptotic 0.27 %
    ns = hampel_n_sigma_for_rate(3, 0.01)
    observed = np.mean(hampel(x, 3, false_alarm_rate=0.01).is_outlier[3:-3])
    assert observed == pytest.approx(0.01, rel=0.1)
    assert hampel_false_alarm_rate(3, ns) == pytest.approx(0.01, rel=0.02)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(x=np.ones(5), half_window=3), "half_window"),
        (dict(x=np.ones(5), half_window=0), "half_window"),
        (dict(x=np.ones(9), half_window=2, n_sigma=-1), "n_sigma"),
        (dict(x=np.array([]), half_window=1), "empty"),
        (dict(x=np.full(9, np.nan), half_window=1), "all NaN"),
        (dict(x=np.ones(9), half_window=1, n_sigma=2, false_alarm_rate=0.01), "either"),
        (dict(x=np.ones(9), half_window=1, false_alarm_rate=0.9), "false_alarm_rate"),
    ],
)
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hampel(**kwargs)


@pytest.mark.slow
def test_rate_of_a_wide_window_at_a_small_false_alarm_rate():
    """k = 50 (a 0.1 s half window at 500 Hz, as the report uses) at 1e-3: the threshold from the
    conditional tail probability flags white noise at the stated rate (2,000 expected flags in
    2,000,000 samples: binomial sd 2.2 %)."""
    rng = np.random.default_rng(11)
    x = rng.standard_normal(2_000_000)
    observed = np.mean(hampel(x, 50, false_alarm_rate=1e-3).is_outlier[50:-50])
    assert observed == pytest.approx(1e-3, rel=0.08)


def test_the_calibration_is_computed_once_per_window_and_rate(tmp_path, monkeypatch):
    """A report filters every burst at the same window and rate: the threshold is found once, and a cached
    threshold is the one the bisection gives afresh (bit for bit), for every spelling of the arguments."""
    from vibkit.signal.hampel import _n_sigma_for_rate

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # its file of thresholds: this test's own
    _n_sigma_for_rate.cache_clear()
    first = hampel_n_sigma_for_rate(4, 0.002)
    assert _n_sigma_for_rate.cache_info().misses == 1
    assert hampel_n_sigma_for_rate(np.int64(4), "0.002") == first  # the same window and rate, spelt otherwise
    assert hampel(np.arange(21.0), 4, false_alarm_rate=0.002).filtered.size == 21
    info = _n_sigma_for_rate.cache_info()
    assert (info.hits, info.misses) == (2, 1)
    _n_sigma_for_rate.cache_clear()
    assert hampel_n_sigma_for_rate(4, 0.002) == first
    assert hampel_false_alarm_rate(4, first) == pytest.approx(0.002, rel=0.02)
    assert hampel_n_sigma_for_rate(5, 0.002) != first  # another window: another threshold


def test_a_threshold_found_once_is_kept_beside_the_kernels_and_read_back_exactly(tmp_path, monkeypatch):
    """The calibration is kept in the kernel cache's folder: the next process reads the very number (no draws),
    a file from other draws or a damaged file is not trusted, and an unwritable folder only costs the search."""
    import importlib

    hp = importlib.import_module("vibkit.signal.hampel")  # the module (vibkit.signal.hampel is the function)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    hp._n_sigma_for_rate.cache_clear()
    found = hampel_n_sigma_for_rate(6, 0.003)
    stored = tmp_path / hp.THRESHOLD_CACHE
    assert stored.is_file()

    def no_search(*_a):
        raise AssertionError("searched again")

    hp._n_sigma_for_rate.cache_clear()
    with monkeypatch.context() as m:
        m.setattr(hp, "_find_n_sigma", no_search)
        assert hampel_n_sigma_for_rate(6, 0.003) == found  # read back, bit for bit
    assert hampel_false_alarm_rate(6, found) == pytest.approx(0.003, rel=0.02)
    # other draws (a changed seed) are another key: searched afresh, not read
    hp._n_sigma_for_rate.cache_clear()
    with monkeypatch.context() as m:
        m.setattr(hp, "_MC_SEED", hp._MC_SEED + 1)
        calls = []
        m.setattr(hp, "_find_n_sigma", lambda k, r: calls.append((k, r)) or 5.0)
        assert hampel_n_sigma_for_rate(6, 0.003) == 5.0 and calls == [(6, 0.003)]
    # a damaged file: searched afresh, the same number, the file rewritten whole
    stored.write_text('{"k=6 rate=0.003": ')
    hp._n_sigma_for_rate.cache_clear()
    assert hampel_n_sigma_for_rate(6, 0.003) == found
    assert stored.read_text().startswith("{")
    # a folder that cannot be made (a file in its way): nothing kept, the search still answers
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(blocker / "cache"))
    hp._n_sigma_for_rate.cache_clear()
    assert hampel_n_sigma_for_rate(6, 0.003) == found
    hp._n_sigma_for_rate.cache_clear()


@pytest.mark.parametrize("seed", range(4))
def test_the_numpy_path_of_a_short_record_is_the_kernels_to_the_last_bit(seed, monkeypatch):
    """A short record without NaN is filtered by numpy (no kernel to load): the compiled kernel's numbers exactly,
    ties and a zero MAD included, at every window the record's ends truncate."""
    import importlib

    H = importlib.import_module("vibkit.signal.hampel")  # the module (the package's name `hampel` is the function)

    rng = np.random.default_rng(seed)
    for _ in range(15):
        n = int(rng.integers(3, 3000))
        k = int(rng.integers(1, (n - 1) // 2 + 1))
        x = rng.standard_normal(n) * 10 ** rng.uniform(-6, 3)
        x[rng.random(n) < 0.03] *= 30.0
        if seed % 2:
            x = np.round(x, 1)  # ties and zero MAD
        ns = float(rng.uniform(0, 5))
        monkeypatch.setattr(H, "NUMPY_MAX_ELEMENTS", 10**12)
        by_numpy = hampel(x, k, ns)
        monkeypatch.setattr(H, "NUMPY_MAX_ELEMENTS", 0)
        by_kernel = hampel(x, k, ns)
        for a, b in zip(by_numpy, by_kernel, strict=True):
            np.testing.assert_array_equal(a, b, strict=True)


@pytest.mark.parametrize("seed", range(3))
def test_the_windows_the_ends_truncate_are_numpys_medians_to_the_last_bit(seed, monkeypatch):
    """The numpy path takes the windows the record's ends truncate all at once: each window's median and MAD are
    ``numpy.median``'s of that window to the last bit (odd and even lengths, ties, a zero MAD)."""
    import importlib

    H = importlib.import_module("vibkit.signal.hampel")
    monkeypatch.setattr(H, "NUMPY_MAX_ELEMENTS", 10**12)
    rng = np.random.default_rng(seed)
    for trial in range(40):
        n = int(rng.integers(3, 600))
        k = int(rng.integers(1, (n - 1) // 2 + 1))
        x = rng.standard_normal(n) * 10 ** rng.uniform(-6, 3)
        if trial % 2:
            x = np.round(x, 1)  # ties and zero MAD
        got = hampel(x, k, 3.0)
        med = np.empty(n)
        sig = np.empty(n)
        for i in range(n):  # the definition, window by window
            w = x[max(0, i - k) : i + k + 1]
            med[i] = np.median(w)
            sig[i] = H.MAD_SCALE * np.median(np.abs(w - med[i]))
        np.testing.assert_array_equal(got.median, med, strict=True)
        np.testing.assert_array_equal(got.sigma, sig, strict=True)
