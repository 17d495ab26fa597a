"""Empatica E4 exports (data/devices/empatica_e4, real files, MIT): what rows 1 and 2 state, read with no options.

Row 1 is the start time (Unix epoch s, once per column), row 2 the sample rate [Hz]; ACC.csv then
holds x, y, z in 1/64 g.  The expected values below were read from the files by hand.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

E4 = Path(__file__).resolve().parents[2] / "data" / "devices" / "empatica_e4"


def test_acc_rate_start_and_units_from_the_two_header_rows():
    ds = read_recording(E4 / "ACC.csv")
    assert detect_format(E4 / "ACC.csv", (E4 / "ACC.csv").read_bytes()).name == "e4"
    assert ds.attrs["reader"] == "vibkit.io.devices.e4"
    assert ds.attrs["sample_rate_hz"] == 32.0  # row 2: '32.000000, 32.000000, 32.000000'
    assert ds.attrs["start_time"] == "2023-04-05T09:23:40+00:00"  # row 1: 1680686620.000000
    assert list(ds.data_vars) == ["x", "y", "z"]
    assert ds.sizes["time"] == 1920  # 1,922 lines less the two header rows: 60 s
    assert all(ds[v].attrs["units"] == "m/s^2" for v in ("x", "y", "z"))
    g64 = STANDARD_GRAVITY / 64
    # line 3: '-34,-23,45'; last line: '23,-10,59'
    np.testing.assert_allclose([ds[v].values[0] for v in "xyz"], np.array([-34, -23, 45]) * g64, rtol=1e-12)
    np.testing.assert_allclose([ds[v].values[-1] for v in "xyz"], np.array([23, -10, 59]) * g64, rtol=1e-12)
    np.testing.assert_allclose(ds["time"].values, np.arange(1920) / 32.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "name, var, fs, n, first, units, start",
    [
        ("BVP.csv", "bvp", 64.0, 1280, -0.0, "unknown", "2023-04-05T09:23:40+00:00"),  # start with 2 decimals
        ("EDA.csv", "eda", 4.0, 400, 0.0, "uS", "2023-04-05T09:23:40+00:00"),
        ("TEMP.csv", "temp", 4.0, 400, 31.61, "degC", "2023-04-05T09:23:40+00:00"),
        ("HR.csv", "hr", 1.0, 100, 90.0, "bpm", "2023-04-05T09:23:50+00:00"),  # HR starts 10 s later
    ],
)
def test_single_column_streams(name, var, fs, n, first, units, start):
    ds = read_recording(E4 / name)
    assert list(ds.data_vars) == [var]
    assert ds.attrs["sample_rate_hz"] == fs and ds.sizes["time"] == n
    assert ds[var].values[0] == first and ds[var].attrs["units"] == units
    assert ds.attrs["start_time"] == start


def test_ibi_is_refused_in_one_line_as_not_a_sampled_signal():
    with pytest.raises(RecordingError) as err:
        read_recording(E4 / "IBI.csv")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{E4 / 'IBI.csv'}, line 1: ") and "not a sampled signal" in msg


def test_the_header_rows_are_never_samples(tmp_path, capsys):
    """The two header rows are the start time and the rate, not the first two samples."""
    ds = read_recording(E4 / "ACC.csv")
    assert np.abs(ds["x"]).max() < 16 * STANDARD_GRAVITY  # 1680686620 or 32 would be far out
    rc = main(["spectrum", str(E4 / "ACC.csv"), "--json"])
    out = json.loads(capsys.readouterr().out)
    # a wrist at rest carries no chain: every axis analysed, no link pass (exit 1)
    assert rc == 1 and out["status"] == "no link-pass found"
    assert [c["channel"] for c in out["channels"]] == ["x", "y", "z"]


def test_a_file_named_otherwise_with_three_columns_is_the_accelerometer(tmp_path):
    p = tmp_path / "session_acc.csv"
    p.write_text("1642471872.000000, 1642471872.000000, 1642471872.000000\n32.000000, 32.000000, 32.000000\n")
    with open(p, "a") as f:
        for k in range(64):
            f.write(f"{k % 5},{-k % 3},64\n")
    ds = read_recording(p)
    assert ds.attrs["start_time"] == "2022-01-18T02:11:12+00:00"
    assert ds["z"].values[0] == pytest.approx(STANDARD_GRAVITY)  # 64/64 g
