"""Compressed recordings (.gz, .zip of one recording) read as the file inside; a WitMotion binary log
named, with what reads it, instead of 'binary content'."""

from __future__ import annotations

import gzip
import json
import struct
import zipfile

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format


def csv_bytes(f0=4.0, fs=200.0, n=4000):
    t = np.arange(n) / fs
    rows = "".join(
        f"{ti:.4f},{0.5 * np.sin(2 * np.pi * f0 * ti) + 0.1 * np.sin(4 * np.pi * f0 * ti):.6f}\n" for ti in t
    )
    return ("time (s),acc z (m/s^2)\n" + rows).encode()


def test_gzip_and_zip_read_like_the_file_inside(tmp_path, capsys):
    plain = tmp_path / "ride.csv"
    plain.write_bytes(csv_bytes())
    gz = tmp_path / "ride.csv.gz"
    gz.write_bytes(gzip.compress(plain.read_bytes()))
    zp = tmp_path / "ride.zip"
    with zipfile.ZipFile(zp, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("export/", "")  # a folder entry and macOS metadata are not recordings
        z.writestr("__MACOSX/export/._ride.csv", b"\x00\x05\x16\x07")
        z.writestr("export/ride.csv", plain.read_bytes())
    ref = read_recording(plain)
    for path, kind, member in ((gz, "gzip", "ride.csv"), (zp, "zip", "export/ride.csv")):
        assert detect_format(path, path.read_bytes()).name == kind
        ds = read_recording(path)
        np.testing.assert_array_equal(ds["acc_z"].values, ref["acc_z"].values)
        np.testing.assert_array_equal(ds["time"].values, ref["time"].values)
        assert ds.attrs["source_file"] == path.name and ds.attrs["container_member"] == member
        assert ds.attrs["container_sha256"] == ref.attrs["sha256"] != ds.attrs["sha256"]
        assert ds.attrs["history"].startswith(f"{kind} file unpacked: {member}")
    main(["pitch", str(zp), "--speed", "0.5", "--json"])  # exit status is the estimate's; the file is read
    out = json.loads(capsys.readouterr().out)
    assert out["file"] == str(zp) and out["channels"][0]["channel"] == "acc_z"


def test_zip_of_several_files_and_broken_containers_refused_in_one_line(tmp_path):
    zp = tmp_path / "session.zip"
    with zipfile.ZipFile(zp, "w") as z:
        for name in ("ACC.csv", "BVP.csv", "info.txt"):
            z.writestr(name, "1\n")
    with pytest.raises(RecordingError) as err:
        read_recording(zp)
    assert str(err.value) == (
        f"{zp}: zip archive holding 3 files (ACC.csv, BVP.csv, info.txt); expected exactly one recording: "
        "unpack it and name the file to read"
    )
    bad = tmp_path / "cut.csv.gz"
    bad.write_bytes(gzip.compress(csv_bytes())[:200])
    with pytest.raises(
        RecordingError, match=r"cut\.csv\.gz: gzip file that cannot be unpacked .*expected a whole \.gz"
    ):
        read_recording(bad)
    inner_bad = tmp_path / "bad.csv.gz"
    inner_bad.write_bytes(gzip.compress(b"time,a\n0,1\n1,x\n"))
    with pytest.raises(RecordingError) as err:
        read_recording(inner_bad)
    assert str(err.value).startswith(f"{inner_bad}/bad.csv, line 3: ")  # the member inside the file, its line


def witmotion_log(n_groups=40):
    """WT901SD packets as the SD card writes them: 0x55, type, four int16 LE, checksum (sum's low byte)."""
    out = b""
    for k in range(n_groups):
        for typ, words in (
            (0x51, (0, 0, int(32768 / 16), 2526)),  # acceleration (1 g on z), temperature 25.26 degC
            (0x52, (k, 0, 0, 2526)),
            (0x53, (0, 0, 100, 0)),
            (0x54, (10, 20, 30, 2526)),
        ):
            p = bytes([0x55, typ]) + struct.pack("<4h", *words)
            out += p + bytes([sum(p) & 0xFF])
    return out


def test_witmotion_binary_log_named_with_what_reads_it(tmp_path, capsys):
    p = tmp_path / "DATA.TXT"
    p.write_bytes(witmotion_log())
    assert detect_format(p, p.read_bytes()).name == "witmotion"
    with pytest.raises(RecordingError) as err:
        read_recording(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}: WitMotion WT901 binary log (0x55 packets: acceleration, angle, angular rate")
    assert "export it to CSV with WitMotion's own software" in msg and "\n" not in msg
    rc = main(["spectrum", str(p)])
    err_line = capsys.readouterr().err.strip()
    assert rc != 0 and "WitMotion" in err_line and "binary content" not in err_line
