"""ActiGraph ActiLife RAW CSV (data/devices/actigraph, real file, MIT), gzipped, read with no options.

The banner states the rate ('at 90 Hz') and the date format; 'Start Time' and 'Start Date' the start;
the values are in g.  Exports without the column row and other rates are written here in the same layout.
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import read_recording
from vibkit.io.text.units import STANDARD_GRAVITY

GZ = Path(__file__).resolve().parents[2] / "data" / "devices" / "actigraph" / "exampleRAW.csv.gz"


def test_gzipped_export_reads_rate_start_names_and_g():
    ds = read_recording(GZ)
    assert ds.attrs["reader"] == "vibkit.io.devices.actigraph" and ds.attrs["container_member"] == "exampleRAW.csv"
    assert ds.attrs["source_file"] == "exampleRAW.csv.gz"
    assert ds.attrs["sample_rate_hz"] == 90.0  # '... date format M/d/yyyy at 90 Hz ...'
    assert ds.attrs["start_time"] == "2019-02-14T08:58:00"  # 'Start Date 2/14/2019' read as M/d/yyyy
    assert list(ds.data_vars) == ["accelerometer_x", "accelerometer_y", "accelerometer_z"]
    assert ds.sizes["time"] == 10800  # 10,811 lines less 10 header lines and the column row: 120 s
    assert ds["accelerometer_x"].attrs["units"] == "m/s^2"
    # line 12: '-0.004,-0.008,0.961'; last line: '-0.016,-1.004,0.148'
    np.testing.assert_allclose(
        [ds[v].values[0] for v in ds.data_vars], np.array([-0.004, -0.008, 0.961]) * STANDARD_GRAVITY, rtol=1e-12
    )
    np.testing.assert_allclose(
        [ds[v].values[-1] for v in ds.data_vars], np.array([-0.016, -1.004, 0.148]) * STANDARD_GRAVITY, rtol=1e-12
    )
    assert ds["time"].values[-1] == pytest.approx(10799 / 90, abs=1e-12)
    assert "gzip file unpacked: exampleRAW.csv" in ds.attrs["history"]


def test_plain_and_gzipped_read_the_same(tmp_path):
    plain = tmp_path / "exampleRAW.csv"
    plain.write_bytes(gzip.decompress(GZ.read_bytes()))
    a, b = read_recording(plain), read_recording(GZ)
    for v in a.data_vars:
        np.testing.assert_array_equal(a[v].values, b[v].values)
    assert a.attrs["sample_rate_hz"] == b.attrs["sample_rate_hz"] and a.attrs["start_time"] == b.attrs["start_time"]


def _export(path, rows, *, rate=30, column_row=False, date="6/27/2012", fmt="M/d/yyyy"):
    head = [
        f"------------ Data File Created By ActiGraph GT3X+ ActiLife v6.7.1 Firmware v2.5.0 date format {fmt} "
        f"at {rate} Hz  Filter Normal -----------",
        "Serial Number: NEO1DXXXXXXXX",
        "Start Time 10:54:00",
        f"Start Date {date}",
        "Epoch Period (hh:mm:ss) 00:00:00",
        "Download Time 16:25:52",
        "Download Date 6/28/2012",
        "Current Memory Address: 0",
        "Current Battery Voltage: 4.22     Mode = 12",
        "--------------------------------------------------",
    ]
    if column_row:
        head.append("Accelerometer X,Accelerometer Y,Accelerometer Z")
    body = [f"{x:.3f},{y:.3f},{z:.3f}" for x, y, z in rows]
    data = ("\n".join(head + body) + "\n").encode()
    path.write_bytes(gzip.compress(data) if path.suffix == ".gz" else data)
    return path


def test_export_without_a_column_row_at_30_hz(tmp_path, capsys):
    """ActiLife 6.7 writes the data right after the dashed line; a 4 Hz sine on z is found by spectrum."""
    t = np.arange(1800) / 30
    rows = np.c_[np.zeros_like(t), np.zeros_like(t), 1 + 0.05 * np.sin(2 * np.pi * 4.0 * t)]
    p = _export(tmp_path / "sample_GT3X+.csv.gz", rows)
    ds = read_recording(p)
    assert ds.attrs["sample_rate_hz"] == 30.0 and ds.sizes["time"] == 1800
    assert ds.attrs["start_time"] == "2012-06-27T10:54:00"
    assert "no column-name row" in ds.attrs["history"]
    rc = main(["spectrum", str(p), "--channel", "Accelerometer Z", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["channel"] == "accelerometer_z"
    assert out["fundamental_hz"] == pytest.approx(4.0, abs=0.02)


def test_day_first_date_format_in_the_banner(tmp_path):
    p = _export(tmp_path / "dmy.csv", [(0, 0, 1)] * 10, date="14/2/2019", fmt="dd/MM/yyyy", column_row=True)
    assert read_recording(p).attrs["start_time"] == "2019-02-14T10:54:00"


def test_export_with_a_timestamp_column(tmp_path):
    """'Timestamp,Accelerometer X,...' exports: the stamps are not a channel; the rate is the banner's."""
    p = _export(tmp_path / "ts.csv", [(0.001 * k, 0, 1) for k in range(60)], column_row=True)
    lines = p.read_text().splitlines()
    head, body = lines[:10], lines[10:]
    body[0] = "Timestamp," + body[0]
    body[1:] = [f"6/27/2012 10:54:{k // 30:02d}.{round(1000 * (k % 30) / 30):03d},{r}" for k, r in enumerate(body[1:])]
    p.write_text("\n".join(head + body) + "\n")
    ds = read_recording(p)
    assert list(ds.data_vars) == ["accelerometer_x", "accelerometer_y", "accelerometer_z"]
    assert ds["accelerometer_x"].values[59] == pytest.approx(0.059 * STANDARD_GRAVITY, rel=1e-12)
    assert ds.attrs["sample_rate_hz"] == 30.0 and "Timestamp column is not read" in ds.attrs["history"]
