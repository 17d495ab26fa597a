"""PASCO SPARKvue/Capstone CSV ('Time (s) Run #1', 'Acceleration (m/s²) Run #1') at 500 Hz, quantised to
0.1 m/s^2 (written here in that layout: no licensed real file was found).  Quantisation repeats
values without any hold between updates: it is never reported as held samples.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import read_recording
from vibkit.io.timebase import held_update_rate, quantum


def pasco(path, seconds=20.0, fs=500.0, f0=4.0, seed=5):
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    a = 9.8 + 0.6 * np.sin(2 * np.pi * f0 * t) + 0.2 * np.sin(4 * np.pi * f0 * t) + 0.03 * rng.standard_normal(t.size)
    q = np.round(a * 10) / 10
    with open(path, "w", encoding="utf-8") as f:
        f.write("Time (s) Run #1,Acceleration (m/s²) Run #1\n")
        for ti, ai in zip(t, q):
            f.write(f"{ti:.3f},{ai:.1f}\n")
    return t, q


def test_run_headers_units_rate_and_quantisation(tmp_path, capsys):
    p = tmp_path / "pasco.csv"
    t, q = pasco(p)
    ds = read_recording(p)
    assert list(ds.data_vars) == ["acceleration_run_1"]
    da = ds["acceleration_run_1"]
    assert da.attrs["units"] == "m/s^2" and da.attrs["long_name"] == "Acceleration Run #1"
    assert ds["time"].attrs["column"] == "Time (s) Run #1"
    assert ds.attrs["sample_rate_hz"] == pytest.approx(500.0, rel=1e-9) and ds.sizes["time"] == t.size
    np.testing.assert_allclose(da.values, q, rtol=0, atol=1e-12)
    assert da.attrs["quantum"] == pytest.approx(0.1, abs=1e-9)
    assert "update_rate_hz" not in da.attrs and "held samples" not in ds.attrs["history"]
    rc = main(["spectrum", str(p), "--json"])
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert rc == 0 and out["fundamental_hz"] == pytest.approx(4.0, abs=0.01)
    assert "held between updates" not in cap.err


def test_held_values_of_a_slower_sensor_are_still_told_apart():
    """A 100 Hz sensor written at 500 Hz rows repeats each value 5 times: held, not quantised."""
    rng = np.random.default_rng(1)
    fs = 500.0
    t = np.arange(5000) / fs
    slow = np.sin(2 * np.pi * 3 * t[::5]) + 0.01 * rng.standard_normal(1000)
    held = np.repeat(slow, 5)
    assert quantum(held) is None
    assert held_update_rate(t, held) == pytest.approx(100.0, rel=0.01)
    fine = np.round(np.sin(2 * np.pi * 3 * t) * 20) / 20  # 0.05 steps
    assert quantum(fine) == pytest.approx(0.05, abs=1e-12) and held_update_rate(t, fine) is None
