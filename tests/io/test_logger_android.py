"""An Android SensorEvent log: 'timestamp' counts nanoseconds since boot, 'accuracy' is a constant status.

No licensed real file of this layout was found, so the file is written here in it.  The time column
is read as ns (the only unit giving a plausible rate), shifted to start at 0, and the status column is
never the channel analysed.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import read_recording, resolve_channel


def android_log(path, n=3000, fs=100.0, f0=3.75, boot_ns=81_234_567_890_123, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    stamps = boot_ns + np.round(t * 1e9).astype(np.int64) + rng.integers(-20_000, 20_000, n)
    with open(path, "w") as f:
        f.write("timestamp,x,y,z,accuracy\n")
        noise = 0.05 * rng.standard_normal((n, 3))
        for k in range(n):
            s = t[k]
            x = 0.2 * np.sin(2 * np.pi * f0 * s) + 0.05 * np.sin(4 * np.pi * f0 * s)
            f.write(f"{stamps[k]},{x + noise[k, 0]:.5f},{noise[k, 1]:.5f},{9.81 + noise[k, 2]:.5f},3\n")
    return stamps


def test_nanoseconds_since_boot_and_status_column(tmp_path, capsys):
    p = tmp_path / "android_accelerometer.csv"
    stamps = android_log(p)
    ds = read_recording(p)
    assert ds.sizes["time"] == 3000
    assert ds.attrs["time_offset_s"] == pytest.approx(stamps[0] * 1e-9, abs=1e-6)
    np.testing.assert_allclose(ds["time"].values, (stamps - stamps[0]) * 1e-9, rtol=0, atol=1e-9)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=1e-3)
    assert "nanoseconds (Android's SensorEvent.timestamp, since boot)" in ds.attrs["history"]
    assert [ds[v].attrs["units"] for v in ("x", "y", "z")] == ["m/s^2"] * 3
    assert ds["accuracy"].attrs["status_column"] == 1
    assert resolve_channel(ds) == "x"
    rc = main(["pitch", str(p), "--speed", "0.5", "--json"])  # 3.75 Hz at 0.5 m/s: a 133.3 mm pitch
    out = json.loads(capsys.readouterr().out)
    assert [c["channel"] for c in out["channels"]] == ["x", "y", "z"]  # never the status column
    assert rc == 0 and out["status"] == "ok" and out["channel"] == "x"


def test_a_status_column_first_is_still_not_the_default_channel(tmp_path):
    p = tmp_path / "log.csv"
    t = np.arange(200) / 50
    p.write_text("time,status,acc\n" + "".join(f"{ti:.3f},1,{np.sin(7 * ti):.4f}\n" for ti in t))
    ds = read_recording(p)
    assert resolve_channel(ds) == "acc" and resolve_channel(ds, "status") == "status"
