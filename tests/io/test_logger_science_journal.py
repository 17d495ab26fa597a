"""Google Science Journal exports: the 2016 'timestamp,value' file (data/devices/science_journal, real,
BSD-3) and the later multi-sensor layout (written here: no licensed real file), whose rows each hold
only the sensors that updated: every sensor keeps its own samples at its own times.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import read_recording
from vibkit.io.channels import channel_series, own_samples

SJ = Path(__file__).resolve().parents[2] / "data" / "devices" / "science_journal" / "Untitled Experiment Trial 1.csv"


def test_2016_export_epoch_ms_and_one_value_column():
    ds = read_recording(SJ)
    assert list(ds.data_vars) == ["value"] and ds.sizes["time"] == 146
    assert ds.attrs["start_time"] == "2016-05-22T05:07:07.134000+00:00"  # 1463893627134 ms
    assert ds["time"].values[1] == pytest.approx(0.075, abs=1e-9)  # 1463893627209 - ...134 ms
    assert ds["time"].values[-1] == pytest.approx(11.211, abs=1e-9)  # 1463893638345 - ...134 ms
    assert ds["value"].values[0] == 10.0 and ds["value"].values[-1] == 6.0


def sparse_export(path, seconds=20.0, f0=4.0):
    """relative_time [ms] at the accelerometer's 50 Hz and the light sensor's 10 Hz, interleaved; each row
    holds only the sensor that updated (the light sensor lags by 7 ms, so rows never hold both)."""
    acc_t = np.arange(0, seconds * 1000, 20)
    light_t = np.arange(7, seconds * 1000, 100)
    rows = [(t, "acc") for t in acc_t] + [(t, "light") for t in light_t]
    rows.sort()
    lines = ["relative_time,AccX,AccY,AccZ,AmbientLightSensor"]
    for t, kind in rows:
        if kind == "acc":
            s = t / 1000
            lines.append(f"{t:.0f},{0.3 * np.sin(2 * np.pi * f0 * s):.4f},{0.1 * np.cos(s):.4f},{9.81 + 0.01 * s:.4f},")
        else:
            lines.append(f"{t:.0f},,,,{100 + (t // 100) % 7:.0f}")
    path.write_text("\n".join(lines) + "\n")
    return acc_t, light_t


def test_sparse_rows_become_per_sensor_series_on_their_own_times(tmp_path, capsys):
    p = tmp_path / "Recording 1.csv"
    acc_t, light_t = sparse_export(p)
    ds = read_recording(p)
    assert ds.sizes["time"] == acc_t.size + light_t.size  # every row, none invented
    assert [ds[v].attrs["units"] for v in ("accx", "accy", "accz")] == ["m/s^2"] * 3
    assert ds["ambientlightsensor"].attrs["units"] == "lx"
    t, v = channel_series(ds, "accx")
    np.testing.assert_allclose(t, acc_t / 1000, rtol=0, atol=1e-12)  # its own time base, 50 Hz
    np.testing.assert_allclose(v, np.round(0.3 * np.sin(2 * np.pi * 4.0 * acc_t / 1000), 4), rtol=0, atol=1e-12)
    tl, _ = channel_series(ds, "ambientlightsensor")
    np.testing.assert_allclose(tl, light_t / 1000, rtol=0, atol=1e-12)  # and the light sensor's, 10 Hz
    assert ds["accx"].attrs["sparse"] == 1 and ds["accx"].attrs["own_rate_hz"] == pytest.approx(50.0, rel=1e-9)
    assert ds["ambientlightsensor"].attrs["own_rate_hz"] == pytest.approx(10.0, rel=1e-9)
    assert "update_rate_hz" not in ds["accx"].attrs  # empty cells are not held values
    rc = main(["spectrum", str(p), "--channel", "AccX", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["fundamental_hz"] == pytest.approx(4.0, abs=0.02)
    # analysed on its own 1000 samples at 50 Hz: nothing filled in at the light sensor's rows
    assert out["invalid_samples"]["total"] == 0
    assert own_samples(ds, "accx").sizes["time"] == acc_t.size
    assert own_samples(ds, "accx")["time"].values[1] == pytest.approx(0.02, abs=1e-12)
