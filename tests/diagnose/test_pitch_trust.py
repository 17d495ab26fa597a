"""Pitch you can trust: no link-pass, no number; invalid samples; wandering speed; the detector's
false-alarm rate."""

import json
import warnings

import numpy as np
import pytest
import scipy.stats

from vibkit.cli import main
from vibkit.diagnose.pitch import STATUS_NOT_FOUND, estimate_pitch
from vibkit.signal.detect import detect_link_pass, flag_invalid, harmonic_sum_pvalue, harmonic_sum_threshold

from support.chain import wandering as _wandering
from support.recording import recording

LEON = "data/field/leon-tensioner.csv"
FS = 200.0
SPEED = 0.49  # default band: 0.49 / (0.2 .. 0.08 m) = 2.45 .. 6.125 Hz


def _rec(x, fs=FS, t=None):
    return recording({"x": x}, fs, t=t, units="m")


def _t(seconds=40.0, fs=FS):
    return np.arange(int(seconds * fs)) / fs


def _no_link_pass_signals():
    t = _t()
    rng = np.random.default_rng(11)
    return {
        "white noise": rng.standard_normal(t.size),
        "constant": np.full(t.size, 3.0),
        "all zeros": np.zeros(t.size),
        "step": np.where(t > 17.3, 1.0, 0.0),
        "step in noise": np.where(t > 17.3, 1.0, 0.0) + 1e-3 * rng.standard_normal(t.size),
        "8 Hz square wave": np.sign(np.sin(2 * np.pi * 8.0 * t)),
        "8 Hz square wave in noise": np.sign(np.sin(2 * np.pi * 8.0 * t)) + 0.1 * rng.standard_normal(t.size),
        "index ramp": np.arange(t.size, dtype=float),
        "index restarting every 1000 rows": (np.arange(t.size) % 1000).astype(float),
        "time column as data": t.copy(),
    }


@pytest.mark.parametrize("name", list(_no_link_pass_signals()))
def test_no_link_pass_gives_no_number(name, capfd):
    x = _no_link_pass_signals()[name]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        est = estimate_pitch(_rec(x), speed=SPEED, nominal_pitch=0.4 / 3)
    assert not est.detected and est.status == STATUS_NOT_FOUND
    assert np.isnan(est.pitch_m) and np.isnan(est.fundamental_hz)
    d = est.as_dict()
    assert d["status"] == "no link-pass found"
    assert not {"pitch_m", "fundamental_hz", "elongation_percent", "verdict"} & set(d)
    out = capfd.readouterr()
    assert "DLASCL" not in out.out + out.err


def test_square_wave_is_not_read_as_a_third_of_its_frequency():
    t = _t()
    x = np.sign(np.sin(2 * np.pi * 8.0 * t))
    det = detect_link_pass(x, FS, band=(2.45, 6.125))
    assert not det.detected
    assert det.frequency_hz == pytest.approx(8.0, rel=0.02)  # named as the periodicity, outside the band
    # in its own lines' words: the odd harmonics 8, 24, 40 ... Hz, all multiples of 8 Hz (not "orders 3, 5 of 2.7 Hz")
    assert "significant lines (8" in det.reason and "are all multiples of 8" in det.reason, det.reason
    # a band that holds 8 Hz gives the right answer
    est = estimate_pitch(_rec(x), speed=1.0, band=(5.0, 10.0), frequency_only=True)
    assert est.detected and est.fundamental_hz == pytest.approx(8.0, abs=1e-3)


def test_cli_pitch_and_spectrum_no_link_pass(tmp_path, capsys):
    p = tmp_path / "noise.csv"
    t = _t()
    np.savetxt(
        p,
        np.column_stack([t, np.random.default_rng(3).standard_normal(t.size)]),
        delimiter=",",
        header="time_s,x_m",
        comments="",
    )
    assert main(["pitch", str(p), "--speed", "0.49", "--json"]) == 1
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    assert d["schema"] == "vibkit.pitch/1" and d["status"] == "no link-pass found" and "pitch_m" not in d
    assert d["detection"]["p_fa"] == 1e-3
    lines = [ln for ln in cap.err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "no link-pass found" in lines[0]
    assert main(["pitch", str(p), "--speed", "0.49"]) == 1
    assert "no link-pass found" in capsys.readouterr().out
    assert main(["spectrum", str(p), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert d["schema"] == "vibkit.spectrum/1" and d["status"] == "no link-pass found" and "fundamental_hz" not in d


def test_cli_detected_status_ok_and_teeth_usage(capsys):
    assert main(["pitch", LEON, "--speed", "0.49", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["status"] == "ok" and d["detected"] is True and d["method"] in ("spectral", "mean-phase")
    assert d["detection"]["p_value"] < 1e-6
    for bad in ("2", "0", "-5", "x"):
        with pytest.raises(SystemExit) as exc:
            main(["pitch", LEON, "--speed", "0.49", "--teeth", bad])
        assert exc.value.code == 2
        assert "--teeth" in capsys.readouterr().err


def test_leon_with_one_fill_value_sample():
    import vibkit

    rec = vibkit.read_recording(LEON)
    clean = estimate_pitch(rec, speed=0.49, nominal_pitch=0.4 / 3)
    ch = list(rec.data_vars)[0]
    v = rec[ch].values.copy()
    v[4321] = 9.96921e36  # netCDF's default fill value
    rec[ch] = (rec[ch].dims, v, rec[ch].attrs)
    est = estimate_pitch(rec, speed=0.49, nominal_pitch=0.4 / 3)
    assert est.detected
    assert est.fundamental_hz == pytest.approx(3.54, abs=0.005)
    assert abs(est.fundamental_hz - clean.fundamental_hz) < est.fundamental_sigma_hz
    assert est.pitch_m == pytest.approx(0.1384, abs=2e-4)
    assert abs(est.elongation_percent - clean.elongation_percent) < est.elongation_sigma_percent
    assert est.invalid_samples["fill_value"] == 1
    assert any("fill value" in w for w in est.warnings)


@pytest.mark.parametrize("kind", ["nan", "inf", "fill", "1e300", "absurd"])
def test_invalid_samples_flagged_and_excluded(kind):
    t = _t(30.0)
    rng = np.random.default_rng(8)
    x = np.cos(2 * np.pi * 3.75 * t) + 0.3 * np.cos(2 * np.pi * 7.5 * t) + 0.1 * rng.standard_normal(t.size)
    bad = {"nan": np.nan, "inf": np.inf, "fill": 9.96921e36, "1e300": 1e300, "absurd": 5e4}[kind]
    x[[1000, 1001, 3000]] = bad
    assert flag_invalid(x).count == 3
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        est = estimate_pitch(_rec(x), speed=0.5)
    assert est.fundamental_hz == pytest.approx(3.75, abs=5 * est.fundamental_sigma_hz + 1e-4)
    assert est.invalid_samples["total"] == 3 and any("invalid sample" in w for w in est.warnings)


def test_long_gap_splits_the_record():
    t = _t(40.0)
    x = np.cos(2 * np.pi * 3.75 * t) + 0.05 * np.random.default_rng(9).standard_normal(t.size)
    x[2000:2400] = np.nan  # 2 s gap: cut out, never bridged
    est = estimate_pitch(_rec(x), speed=0.5)
    assert len(est.per_burst) == 2
    assert est.invalid_samples["dropped"] == 400
    assert est.fundamental_hz == pytest.approx(3.75, abs=1e-3)


def test_every_sample_invalid_is_a_clear_error():
    with pytest.raises(ValueError, match="every sample is invalid"):
        estimate_pitch(_rec(np.full(4000, 9.96921e36)), speed=0.5)


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e25])
def test_huge_and_tiny_values(scale):
    t = _t(20.0)
    x = scale * (np.cos(2 * np.pi * 3.75 * t) + 0.01 * np.random.default_rng(1).standard_normal(t.size))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        est = estimate_pitch(_rec(x), speed=0.5)
    assert est.fundamental_hz == pytest.approx(3.75, abs=1e-3)
    assert est.harmonics[0]["amplitude"] == pytest.approx(scale, rel=0.01)


def test_bad_teeth_and_p_fa():
    t = _t(20.0)
    rec = _rec(np.cos(2 * np.pi * 3.75 * t))
    with pytest.raises(ValueError, match="teeth"):
        estimate_pitch(rec, speed=0.5, teeth=2)
    with pytest.raises(ValueError, match="p_fa"):
        estimate_pitch(rec, speed=0.5, p_fa=0.7)


# ------------------------------------------------------------------------------------------- wandering speed
# support.chain.wandering: speed v(t) = v0 (1 + w(t)), |w| <= amp; returns (signal, mean speed, pitch)

_GRID = [
    (dur, per, kind, snr)
    for dur in (30.0, 120.0, 600.0)
    for per in (10.0, 60.0, 300.0)
    for kind in ("sine", "walk")
    for snr in (0.0, 20.0)
    if not (dur == 600.0 and snr == 20.0)
]


@pytest.mark.parametrize("duration, period, kind, snr_db", _GRID)
def test_wandering_speed_pitch_within_0p1_percent(duration, period, kind, snr_db):
    fs = 50.0 if duration > 100 else 100.0
    x, v_mean, pitch = _wandering(duration, fs, period, 0.02, snr_db, kind, seed=int(duration + period) + len(kind))
    est = estimate_pitch(_rec(x, fs), speed=v_mean)
    assert est.detected
    assert abs(est.pitch_m / pitch - 1) < 1e-3
    assert abs(est.pitch_m - pitch) < 5 * est.pitch_sigma_m + 2e-5 * pitch


def test_wander_uses_mean_phase_where_the_spectral_peak_fails():
    from vibkit.signal import link_pass_estimate

    x, v_mean, pitch = _wandering(120.0, 100.0, 60.0, 0.02, 10.0, "sine", seed=4)
    spectral = link_pass_estimate(x, 100.0, band=(2.5, 6.25))
    assert abs(v_mean / spectral.fundamental_hz / pitch - 1) > 3e-3  # a sideband, not the mean
    est = estimate_pitch(_rec(x, 100.0), speed=v_mean)
    assert est.method == "mean-phase" and "not stationary" in est.method_reason
    assert abs(est.pitch_m / pitch - 1) < 2e-4


def test_stationary_record_keeps_the_spectral_estimate():
    rng = np.random.default_rng(5)
    t = _t(60.0, 100.0)
    x = np.cos(2 * np.pi * 3.75 * t) + 0.4 * np.cos(2 * np.pi * 7.5 * t + 1) + 0.5 * rng.standard_normal(t.size)
    est = estimate_pitch(_rec(x, 100.0), speed=0.5)
    assert est.method == "spectral" and "stationary" in est.method_reason
    assert abs(est.fundamental_hz - 3.75) < 4 * est.fundamental_sigma_hz


# ------------------------------------------------------------------------------------------ false alarms


def test_threshold_is_the_gamma_quantile():
    # without floor error the threshold is the Gamma(H k, 1/k) upper quantile
    t = harmonic_sum_threshold(1e-3, 5, 3)
    assert t == pytest.approx(scipy.stats.gamma.isf(1e-3, 15, scale=1 / 3), rel=1e-8)
    assert harmonic_sum_pvalue(t, 5, 3) == pytest.approx(1e-3, rel=1e-6)
    assert harmonic_sum_threshold(1e-3, 5, 3, 0.1) > t  # an uncertain floor raises it


@pytest.mark.slow
def test_false_alarm_rate_on_1000_noise_records():
    """Measured rates at 0.05, 0.01 and 1e-3 within their binomial 99.9 % intervals (1,000 records)."""
    rng = np.random.default_rng(2026)
    n_rec = 1000
    pv = np.array(
        [detect_link_pass(rng.standard_normal(3000), 100.0, band=(2.45, 6.125)).p_value for _ in range(n_rec)]
    )
    for p in (0.05, 0.01, 1e-3):
        lo, hi = scipy.stats.binom.interval(0.999, n_rec, p)
        assert lo <= np.sum(pv < p) <= hi, (p, np.sum(pv < p))


def test_detects_a_weak_family():
    # -10 dB per sample, 30 s: integrated SNR about 25 dB; must be found, at the right place
    rng = np.random.default_rng(6)
    t = _t(30.0, 100.0)
    x = (
        np.cos(2 * np.pi * 3.75 * t)
        + 0.5 * np.cos(2 * np.pi * 7.5 * t)
        + np.sqrt(10 * 0.625) * rng.standard_normal(t.size)
    )
    det = detect_link_pass(x, 100.0, band=(2.45, 6.125))
    assert det.detected and det.frequency_hz == pytest.approx(3.75, abs=0.15)


@pytest.mark.slow
def test_false_alarm_rate_of_short_records_is_at_most_the_stated_one():
    """Records too short for two segments are tested once per piece, Bonferroni over the candidate
    bin tuples: conservative (rate at most the stated one, within binomial noise)."""
    rng = np.random.default_rng(77)
    n_rec = 1000
    dets = [detect_link_pass(rng.standard_normal(200), 100.0, band=(2.45, 6.125), p_fa=0.05) for _ in range(n_rec)]
    assert all(d.extra["test"].startswith("bonferroni") for d in dets)
    _, hi = scipy.stats.binom.interval(0.999, n_rec, 0.05)
    assert sum(d.detected for d in dets) <= hi


def test_a_short_tone_is_no_gait_by_its_own_leakage():
    """The shipped phyphox layout holds 3 s of a 3.9 Hz sine: two 1.5 s segments, 0.67 Hz bins. The search put the
    family at 3.15 Hz, and the line at its 3f/2 (4.73 Hz) took its strength from the tone's own bin at 4.0 Hz: the
    tone was refused as a 1.58 Hz gait (a stranger's find). A fractional line must be another line than the
    family's own; a tone of a record this short is no gait, and a real gait (phyphox walking, y) still is one."""
    import vibkit

    rec = vibkit.read_recording("data/field/layouts/phyphox.csv")
    z, fs = rec["linear_acceleration_z"].values, rec.attrs["sample_rate_hz"]
    d = detect_link_pass(z, fs, band=(2.5, 6.0))
    assert "subharmonic" not in d.extra and "(f/2)" not in d.reason, d.reason
    walk = vibkit.read_recording("data/thirdparty/phyphox_walking_linear_accelerometer.csv")
    w = detect_link_pass(walk["y"].values, walk.attrs["sample_rate_hz"], band=(2.5, 6.25))
    assert not w.detected and w.extra.get("subharmonic") == 2, w.reason
