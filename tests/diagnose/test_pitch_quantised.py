"""Clean and quantised tones through ``vibkit pitch``: an integer-count tone gives the same frequency and
pitch as the same tone in floating point (it used to be refused: its detected "family" sat on a rounding
spur at 3.14 Hz), a quantised harmonic family keeps its verdict, quantised noise is still refused."""

import json

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.diagnose.pitch import STATUS_INCONCLUSIVE, STATUS_NOT_FOUND, STATUS_OK, estimate_pitch

from support.recording import recording

SPEED = 0.4667


def _rec(x, fs):
    return recording({"x": x}, fs, units=None, time_units=None)


def test_cli_integer_tone_as_the_float_tone(tmp_path, capsys):
    """The reproduction of the report: 2048 counts at 3.5 Hz, 120 s at 200 Hz."""
    fs = 200.0
    t = np.arange(0, 120, 1 / fs)
    x = 2048 * np.sin(2 * np.pi * 3.5 * t)
    p_int, p_float = tmp_path / "tone_int.csv", tmp_path / "tone_float.csv"
    np.savetxt(
        p_int,
        np.column_stack([t, np.round(x).astype(int)]),
        delimiter=",",
        header="time_s,accel_counts",
        comments="",
        fmt=["%.4f", "%d"],
    )
    np.savetxt(
        p_float, np.column_stack([t, x]), delimiter=",", header="time_s,accel", comments="", fmt=["%.4f", "%.6f"]
    )
    out = {}
    for name, p in (("int", p_int), ("float", p_float)):
        # one spectral line without a harmonic: a pitch, no verdict (exit 3)
        assert main(["pitch", str(p), "--speed", str(SPEED), "--nominal-pitch", "133.33mm", "--json"]) == 3
        out[name] = json.loads(capsys.readouterr().out)
    for d in out.values():
        assert d["status"] == STATUS_INCONCLUSIVE and d["detection"]["significant_orders"] == [1]
        assert abs(d["detection"]["frequency_hz"] - 3.5) <= 1 / d["detection"]["segment_s"]
        # the pitch to 1e-5 (the elongation to 1e-3 %, 500 x below the first limit)
        assert d["pitch_m"] == pytest.approx(SPEED / 3.5, rel=1e-5)
    assert out["int"]["fundamental_hz"] == pytest.approx(out["float"]["fundamental_hz"], rel=1e-6)


@pytest.mark.parametrize("fs", [200.0, 1000.0])  # 1000 Hz: decimated before the detection
@pytest.mark.parametrize("amplitude", [3, 2048, 32767])
def test_quantised_tones_give_the_tone_pitch(fs, amplitude):
    rng = np.random.default_rng(int(fs) + amplitude)
    t = np.arange(0, 60, 1 / fs)
    for f0 in (2.7, 5.5):
        for noise in (0.0, 0.2):
            x = np.round(
                amplitude * np.sin(2 * np.pi * f0 * t + rng.uniform(0, 6.3)) + noise * rng.standard_normal(t.size)
            )
            est = estimate_pitch(_rec(x, fs), speed=SPEED, nominal_pitch=SPEED / f0)
            assert est.status == STATUS_INCONCLUSIVE, (f0, noise, est.decision.reason)
            assert est.pitch_m == pytest.approx(SPEED / f0, rel=1e-5), (f0, noise)


def test_quantised_family_keeps_its_verdict():
    fs = 200.0
    t = np.arange(0, 60, 1 / fs)
    f0 = 3.5
    x = sum(a * np.cos(2 * np.pi * (k + 1) * f0 * t + 0.5 * k) for k, a in enumerate((20.0, 10.0, 6.0)))
    est = estimate_pitch(_rec(np.round(x), fs), speed=SPEED, nominal_pitch=SPEED / f0)
    assert est.status == STATUS_OK and est.verdict == "ok"
    assert est.pitch_m == pytest.approx(SPEED / f0, rel=1e-5)


def test_quantised_noise_is_refused():
    rng = np.random.default_rng(23)
    for sd in (0.1, 0.3, 1.0, 5.0):
        for _ in range(3):
            x = np.round(sd * rng.standard_normal(8000))
            est = estimate_pitch(_rec(x, 200.0), speed=SPEED, nominal_pitch=0.13333)
            assert est.status == STATUS_NOT_FOUND and not est.detected, (sd, est.decision.reason)
