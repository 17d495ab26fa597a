"""NI LabVIEW .lvm files (data/devices/labview: real files, MIT) read from their headers with no options.

Delta_X gives the rate, the column row the names, Y_Unit_Label the units (g, m/s^2, Newtons, Volts);
a decimal comma, empty channels and several segments under one file header are read as stated.
The expected values were read from the files by hand.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording
from vibkit.io.text.units import STANDARD_GRAVITY

LVM = Path(__file__).resolve().parents[2] / "data" / "devices" / "labview"


def test_decimal_comma_two_channels_in_newtons_and_m_s2():
    ds = read_recording(LVM / "short.lvm")
    assert ds.attrs["reader"] == "vibkit.io.lvm"
    assert ds.attrs["sample_rate_hz"] == pytest.approx(25600.0, rel=1e-12)  # Delta_X 3,906250E-5
    assert list(ds.data_vars) == ["excitation_trigger", "response_trigger"]
    assert ds["excitation_trigger"].attrs["long_name"] == "Excitation (Trigger)"
    assert ds["excitation_trigger"].attrs["units"] == "N" and ds["response_trigger"].attrs["units"] == "m/s^2"
    assert ds.sizes["time"] == 10
    assert ds["excitation_trigger"].values[0] == 0.914018 and ds["response_trigger"].values[-1] == 1.212775
    assert ds.attrs["start_time"].startswith("2013-02-19T09:51:40.727189")  # segment Time 09:51:40,72718906...


def test_g_channel_converted_and_rounded_delta_x_read_as_the_whole_rate():
    ds = read_recording(LVM / "long_single_header_first2048.lvm")
    assert list(ds.data_vars) == ["f", "m_1", "m_2"]
    assert [ds[v].attrs["units"] for v in ds.data_vars] == ["m/s^2"] * 3  # Y_Unit_Label g, m/s^2, m/s^2
    assert ds["f"].values[0] == pytest.approx(0.052530 * STANDARD_GRAVITY, rel=1e-12)
    assert ds["m_1"].values[0] == 0.234571
    assert ds.attrs["sample_rate_hz"] == 1024.0  # Delta_X 0.000977 = 1/1024 s to 6 decimals
    assert "1/1024 s written with 6 decimals" in ds.attrs["history"]
    assert ds.sizes["time"] == 2048 and "header says 8192 samples, the file holds 2048 rows" in ds.attrs["history"]


def test_empty_channels_dropped_and_multi_x_columns():
    ds = read_recording(LVM / "with_empty_fields.lvm")
    assert list(ds.data_vars) == ["dev0_ai0", "dev0_ai2", "dev0_ai0_1"]  # 'Untitled' ... have 0 samples
    assert ds.attrs["sample_rate_hz"] == 1000.0 and ds.sizes["time"] == 7
    assert ds["dev0_ai2"].values[0] == 7.254639
    assert ds["dev0_ai0"].attrs["units"] == "unknown"  # no Y_Unit_Label: kept as found, said so
    multi = read_recording(LVM / "multi_time_column.lvm")
    assert list(multi.data_vars) == ["voltage", "acceleration"]
    assert multi["voltage"].attrs["units"] == "V" and multi["acceleration"].attrs["units"] == "m/s^2"
    assert multi["acceleration"].values[0] == pytest.approx(0.532608 * STANDARD_GRAVITY, rel=1e-12)
    np.testing.assert_allclose(multi["time"].values, [0, 1.953125e-5, 3.90625e-5], rtol=0, atol=1e-15)


def test_irregular_x_values_kept_as_time_stamps_and_the_comment_column_dropped():
    ds = read_recording(LVM / "with_comments.lvm")
    assert list(ds.data_vars) == ["pressao_abs_mpa", "temperatura_c", "volume_ml"]
    np.testing.assert_allclose(ds["time"].values[:3], [0.0, 0.328878, 1.208397], rtol=0, atol=1e-12)
    assert "segment" not in ds  # Samples 1 per block with an X column: one record, not 9 segments


def _segment(n, fs, f0, t0, date="2024/03/05"):
    head = [
        "Channels\t2\t\t",
        f"Samples\t{n}\t{n}\t",
        f"Date\t{date}\t{date}\t",
        f"Time\t{t0}\t{t0}\t",
        "Y_Unit_Label\tg\tm/s^2\t",
        "X_Dimension\tTime\tTime\t",
        "X0\t0,0000000000000000E+0\t0,0000000000000000E+0\t",
        f"Delta_X\t{1 / fs:.6E}\t{1 / fs:.6E}\t".replace(".", ","),
        "***End_of_Header***\t\t\t",
        "X_Value\tacc z\tforce\tComment",
    ]
    t = np.arange(n) / fs
    rows = [f"\t{0.01 * np.sin(2 * np.pi * f0 * ti):.6f}\t{ti:.6f}".replace(".", ",") for ti in t]
    return head + rows


def test_two_segments_under_one_file_header(tmp_path, capsys):
    """Two bursts of 20 s at 200 Hz, 60 s apart, each with its segment header: segments, never bridged."""
    lines = [
        "LabVIEW Measurement\t",
        "Writer_Version\t2",
        "Reader_Version\t2",
        "Separator\tTab",
        "Decimal_Separator\t,",
        "Multi_Headings\tYes",
        "X_Columns\tNo",
        "Time_Pref\tAbsolute",
        "Date\t2024/03/05",
        "Time\t10:00:00,0",
        "***End_of_Header***\t",
        "",
    ]
    lines += _segment(4000, 200.0, 4.0, "10:00:00,5") + [""] + _segment(4000, 200.0, 4.0, "10:01:00,5")
    p = tmp_path / "bursts.lvm"
    p.write_text("\n".join(lines) + "\n", encoding="cp1252")
    ds = read_recording(p)
    assert ds.attrs["segment_count"] == 2 and ds.sizes["time"] == 8000
    np.testing.assert_array_equal(np.bincount(ds["segment"].values), [4000, 4000])
    second = ds["time"].values[ds["segment"].values == 1]
    assert second[0] == pytest.approx(60.0, abs=1e-9)  # its own Time, 60 s after the first
    assert ds["acc_z"].attrs["units"] == "m/s^2" and ds["force"].attrs["units"] == "m/s^2"
    written = round(0.01 * np.sin(2 * np.pi * 4.0 / 200), 6)  # the cell "0,001253" in g
    assert ds["acc_z"].values[1] == pytest.approx(written * STANDARD_GRAVITY, rel=1e-12)
    rc = main(["spectrum", str(p), "--channel", "acc z", "--json"])  # the name as the file writes it
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["fundamental_hz"] == pytest.approx(4.0, abs=0.01)


def test_unknown_channel_and_missing_end_of_header_refused_in_one_line(tmp_path):
    with pytest.raises(RecordingError, match=r"no channel 'G' \(channel=\); channels: F, m_1, m_2"):
        read_recording(LVM / "long_single_header_first2048.lvm", channel="G")
    p = tmp_path / "cut.lvm"
    p.write_text("LabVIEW Measurement\t\nWriter_Version\t2\n")
    with pytest.raises(RecordingError) as err:
        read_recording(p)
    assert str(err.value) == f"{p}: LabVIEW file header without '***End_of_Header***'; expected one"


def test_blocks_under_one_header_without_headings_become_segments(tmp_path):
    """Multi_Headings No: LabVIEW appends each block of Samples rows under the one header (upstream long.lvm
    holds 16,384 rows under 'Samples 8192'): two segments, end to end, never bridged."""
    text = (LVM / "long_single_header_first2048.lvm").read_text()
    head, rows = text.split("***End_of_Header***\t\t\t\t\n")
    rows = rows.splitlines()
    names, data = rows[0], rows[1:]
    head = head.replace("Samples\t8192\t8192\t8192", "Samples\t1024\t1024\t1024")
    p = tmp_path / "blocks.lvm"
    p.write_text(head + "***End_of_Header***\t\t\t\t\n" + "\n".join([names] + data) + "\n")
    ds = read_recording(p)
    assert ds.attrs["segment_count"] == 2 and np.bincount(ds["segment"].values).tolist() == [1024, 1024]
    assert ds["time"].values[1024] == pytest.approx(1024 / 1024.0, abs=1e-12)  # right after the first block
    assert "2 segments of 1024 rows, placed end to end" in ds.attrs["history"]
