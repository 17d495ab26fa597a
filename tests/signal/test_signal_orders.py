"""Order tracking, order spectra, Vold-Kalman filter."""

import numpy as np
import pytest

from vibkit.signal import (
    order_map,
    order_spectrum,
    phase_from_shaft_angle,
    phase_from_tacho,
    resample_to_angle,
    track_phase,
    vold_kalman,
)
from vibkit.signal.kernels import _vk_solve
from vibkit.signal.orders import _vk_banded, _vk_sparse

from support.chain import family_of_phase

FS = 2050.0


def wandering(seconds=60.0, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(int(FS * seconds)) / FS
    f_inst = 3.75 * (1 + 0.01 * np.sin(2 * np.pi * t / 15 + 0.3))  # +-1 %
    phi = 2 * np.pi * np.cumsum(f_inst) / FS
    s = family_of_phase(phi, (1.0, 0.6, 0.3), phases=(0, 1, 2))
    x = s + rng.standard_normal(t.size) * np.std(s)  # 0 dB: noise power = signal power
    return t, f_inst, phi, x


def test_track_phase_recovers_wandering_link_pass_to_0p05_percent():
    t, f_inst, _, x = wandering()
    tr = track_phase(x, FS, band=(3.0, 4.5))
    edge = int(6.0 * FS)  # filter end effects: about 1 / bandwidth_hz (5.3 s) at each end
    rel = (tr.frequency_hz[edge:-edge] - f_inst[edge:-edge]) / f_inst[edge:-edge]
    assert np.sqrt(np.mean(rel**2)) < 5e-4


def test_order_spectrum_from_tracked_phase_has_sharp_orders():
    _, _, _, x = wandering()
    tr = track_phase(x, FS, band=(3.0, 4.5))
    ang = resample_to_angle(x, FS, tr.phase_rad, samples_per_cycle=32)
    o, a = order_spectrum(ang)
    for k, amp in ((1, 1.0), (2, 0.6), (3, 0.3)):
        i = np.argmin(np.abs(o - k))
        assert a[i] == pytest.approx(amp, rel=0.05)


def test_known_shaft_angle_resampling_is_exact_for_orders():
    teeth = 28
    t = np.arange(int(20 * FS)) / FS
    theta = 2 * np.pi * (3.75 / teeth) * (t + 0.5 * t**2 / 20)  # accelerating shaft
    link = phase_from_shaft_angle(theta, teeth=teeth)
    x = 0.8 * np.cos(2 * link) + 0.1 * np.cos(link)
    ang = resample_to_angle(x, FS, link, samples_per_cycle=16)
    o, a = order_spectrum(ang)
    assert a[np.argmin(np.abs(o - 2))] == pytest.approx(0.8, rel=1e-3)
    assert a[np.argmin(np.abs(o - 1))] == pytest.approx(0.1, rel=1e-2)
    ang_shaft = resample_to_angle(x, FS, theta, samples_per_cycle=8 * teeth)  # orders up to 4 Z
    o2, a2 = order_spectrum(ang_shaft)
    assert o2[np.argmax(a2)] == pytest.approx(2 * teeth)


def test_phase_from_tacho_linear_for_constant_speed():
    pulses = np.arange(0, 10, 0.25)
    t = np.linspace(0, 9.75, 100)
    np.testing.assert_allclose(phase_from_tacho(pulses, t, pulses_per_cycle=2), 2 * np.pi * t / 0.5, atol=1e-9)
    with pytest.raises(ValueError, match="pulse_times"):
        phase_from_tacho(pulses[::-1], t)


def test_order_map_shape_and_peak():
    t = np.arange(int(30 * FS)) / FS
    phi = 2 * np.pi * 3.75 * t
    o, tm, s = order_map(np.cos(3 * phi), FS, phi, samples_per_cycle=16, cycles_per_frame=8)
    assert s.shape == (o.size, tm.size)
    assert np.all(o[np.argmax(s, axis=0)] == 3)
    assert np.all(np.diff(tm) > 0) and 0 < tm[0] < tm[-1] < 30


def test_vold_kalman_extracts_order_amplitude_and_phase():
    rng = np.random.default_rng(5)
    t = np.arange(int(40 * FS)) / FS
    phi = 2 * np.pi * 3.75 * (t + 0.002 * t**2)
    x = np.cos(phi) + 0.7 * np.cos(2 * phi + 0.3) + rng.standard_normal(t.size)
    # 0.7 Hz: just above the narrowest band at 2050 Hz (condition number 1e12); 0.2 Hz is refused
    v = vold_kalman(x, FS, phi, order=2, bandwidth_hz=0.7)
    inner = slice(int(5 * FS), -int(5 * FS))
    assert np.mean(v.amplitude[inner]) == pytest.approx(0.7, rel=0.02)
    assert np.angle(np.mean(v.envelope[inner])) == pytest.approx(0.3, abs=0.03)
    resid = v.waveform[inner] - 0.7 * np.cos(2 * phi[inner] + 0.3)
    assert np.std(resid) < 0.05


def test_vk_solvers_agree():
    rng = np.random.default_rng(6)
    y = rng.standard_normal(5000) + 1j * rng.standard_normal(5000)
    r2 = 1e6
    a = _vk_solve(y, r2)
    import scipy.linalg
    import scipy.sparse.linalg

    b = scipy.linalg.solveh_banded(_vk_banded(y.size, r2), y)
    c = scipy.sparse.linalg.spsolve(_vk_sparse(y.size, r2), y)
    np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(a, c, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: resample_to_angle(np.ones(100), FS, -np.arange(100.0)), "phase"),
        (lambda: resample_to_angle(np.ones(100), FS, np.arange(100.0) * 1e-3), "cycle"),
        (lambda: vold_kalman(np.ones(100), FS, np.arange(100.0), bandwidth_hz=0.0), "bandwidth_hz"),
        (lambda: vold_kalman(np.ones(100), FS, np.arange(100.0), bandwidth_hz=1.0, solver="x"), "solver"),
        (lambda: track_phase(np.random.default_rng(0).standard_normal(20000), FS, band=(3.0, 2000.0)), "Nyquist"),
    ],
)
def test_bad_arguments(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_vold_kalman_refuses_a_band_past_its_condition_limit():
    """The docstring's limit 16 r**2 <= 1e12 is enforced: the narrowest band passes, a narrower one is
    refused with the parameter, the condition and the narrowest band allowed in the message."""
    from vibkit.signal.orders import VK_MAX_CONDITION, vk_bandwidth_to_r, vk_min_bandwidth

    fs = 2000.0
    bmin = vk_min_bandwidth(fs)
    assert 16 * vk_bandwidth_to_r(bmin, fs) ** 2 == pytest.approx(VK_MAX_CONDITION, rel=1e-9)
    assert bmin == pytest.approx(3.183e-4 * fs, rel=1e-3)  # asin(1e-3) / pi
    n = int(fs * 60)
    phase = 2 * np.pi * 3.75 * np.arange(n) / fs
    x = np.cos(phase)
    res = vold_kalman(x, fs, phase, bandwidth_hz=bmin * 1.0001)
    mid = slice(n // 4, 3 * n // 4)
    np.testing.assert_allclose(res.amplitude[mid], 1.0, atol=1e-3)  # accurate at the limit
    # the band at condition 1e14, where amplitudes drift (1.002 for 1.000 on some records), is refused
    narrow = fs / np.pi * np.arcsin(np.sqrt(1 / (4 * np.sqrt(1e14 / 16))))
    with pytest.raises(
        ValueError, match=r"bandwidth_hz=0\.201\d* is too narrow .* 1\.0e\+14 exceeds the limit 1e\+12"
    ) as err:
        vold_kalman(x, fs, phase, bandwidth_hz=narrow)
    assert f"bandwidth_hz >= {bmin:.4g} Hz" in str(err.value)


def test_track_phase_in_blocks_is_the_whole_spectrogram_track(monkeypatch):
    """The coarse ridge's spectrogram and the return to the record's rate run a block at a time (bounded memory on
    a day-long record): blocks of 4,096 values give the one-block track, bit for bit but for the phase's spline back
    to the record's rate (within rounding: each block's spline has its own knots), and it follows the true tone."""
    import importlib

    orders = importlib.import_module("vibkit.signal.orders")
    rng = np.random.default_rng(12)
    fs, f, n = 200.0, 3.75, 40_000
    t = np.arange(n) / fs
    x = np.sin(2 * np.pi * f * t) + 0.4 * np.sin(4 * np.pi * f * t) + 0.3 * rng.standard_normal(n)
    whole = orders.track_phase(x, fs, band=(2.5, 6.0))
    monkeypatch.setattr(orders, "SPECTROGRAM_BLOCK_VALUES", 4096)
    blocked = orders.track_phase(x, fs, band=(2.5, 6.0))
    for name in ("frequency_hz", "ridge_time_s", "ridge_hz"):
        assert np.array_equal(getattr(blocked, name), getattr(whole, name)), name
    np.testing.assert_allclose(blocked.phase_rad, whole.phase_rad, rtol=1e-12, atol=0)
    inner = slice(n // 10, -n // 10)  # away from the filters' end effects
    assert np.max(np.abs(blocked.frequency_hz[inner] - f)) < 0.01


@pytest.mark.parametrize("q", [2, 3, 7])
def test_the_spline_back_to_the_record_rate_in_blocks_is_the_whole_spline(q):
    """Blocks of the output, each from its knots and 64 more each side, give the record-length not-a-knot spline
    within 1e-12 relative (its end conditions reach a block from 64 knots away by 0.27^64), extrapolated ends
    included; the linear interpolation in blocks is the whole one bit for bit."""
    import scipy.interpolate

    from vibkit.signal.orders import _interp_blocks, _spline_blocks

    rng = np.random.default_rng(q)
    fs_full, n_full = 200.0, 20_003
    n = -(-n_full // q)  # the decimated samples: every q-th of the record's
    t = np.arange(n) * q / fs_full
    freq = 3.75 + 0.05 * np.cumsum(rng.standard_normal(n)) / np.sqrt(n)
    phase = 2 * np.pi * np.cumsum(freq) * q / fs_full + 0.01 * rng.standard_normal(n)
    t_full = np.arange(n_full) / fs_full
    want = scipy.interpolate.CubicSpline(t, phase)(t_full)
    for block in (1000, 4096, n_full, 10 * n_full):
        got = _spline_blocks(t, phase, fs_full, n_full, block)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
        assert np.array_equal(_interp_blocks(t, freq, fs_full, n_full, block), np.interp(t_full, t, freq))
