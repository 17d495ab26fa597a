"""Recording inputs as a stranger brings them, through ``vibkit.cli.main``: one clear line naming the
file and exit 1, or the right result; never a traceback, a hang or a made-up number.

Fixtures live in this file (tests/reliability/ is shared with other suites).
"""

import json
import os
import stat
import threading

import numpy as np
import pytest

from vibkit.cli import main

from support.cli import one_line_error

FS = 200.0
F0 = 3.5  # link-pass frequency of the test signals [Hz]


def signal(n=4000, fs=FS):
    t = np.arange(n) / fs
    x = np.sin(2 * np.pi * F0 * t) + 0.3 * np.sin(2 * np.pi * 2 * F0 * t + 0.5)
    return t, x


def spectrum_json(run, *argv):
    rc, out, err = run("spectrum", *argv, "--json")
    assert rc == 0, err
    return json.loads(out)


# --------------------------------------------------------------------------------- not a regular file


def test_dev_zero_is_refused_at_once(run):
    if not stat.S_ISCHR(os.stat("/dev/zero").st_mode):
        pytest.skip("no /dev/zero character device")
    one_line_error(run("pitch", "/dev/zero", "--speed", "0.5"), "/dev/zero", "character device")


def test_fifo_is_refused_without_hanging(run, tmp_path):
    fifo = tmp_path / "logger.csv"
    os.mkfifo(fifo)
    result = {}

    def go():
        try:
            result["r"] = run("spectrum", fifo)
        except BaseException as exc:  # noqa: BLE001 - reported below
            result["r"] = exc

    th = threading.Thread(target=go, daemon=True)
    th.start()
    th.join(60)
    if th.is_alive():  # unblock the reader so that the test process can end, then fail
        with open(fifo, "w"):
            pass
        pytest.fail("reading a FIFO blocked")
    one_line_error(result["r"], fifo, "named pipe (FIFO)")


def test_folder_missing_and_empty_files(run, tmp_path):
    one_line_error(run("spectrum", tmp_path), tmp_path, "folder")
    one_line_error(run("spectrum", tmp_path / "nope.csv"), tmp_path / "nope.csv", "file not found")
    empty = tmp_path / "empty.csv"
    empty.write_bytes(b"")
    one_line_error(run("spectrum", empty), empty, "empty (0 bytes)")


def test_size_limit_from_the_environment(run, tmp_path, monkeypatch):
    p = tmp_path / "rec.csv"
    t, x = signal()
    p.write_text("time (s),x (mm)\n" + "".join(f"{a:.4f},{v:.5f}\n" for a, v in zip(t, x)))
    monkeypatch.setenv("VIBKIT_MAX_RECORDING_BYTES", "1000")
    one_line_error(run("spectrum", p), p, "larger than the 1000 bytes limit", "VIBKIT_MAX_RECORDING_BYTES")


def test_binary_garbage(run, tmp_path):
    p = tmp_path / "garbage.csv"
    p.write_bytes(np.random.default_rng(3).integers(0, 256, 5000, dtype=np.uint8).tobytes())
    one_line_error(run("spectrum", p), p, "binary content")


# --------------------------------------------------------------------------------- text from other apps


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le"])
def test_utf16_export_is_read(run, tmp_path, codec):
    t, x = signal()
    p = tmp_path / "excel.csv"
    p.write_bytes(
        ("Tiempo (s)\tDesplazamiento (mm)\n" + "".join(f"{a:.4f}\t{v:.6f}\n" for a, v in zip(t, x))).encode(codec)
    )
    d = spectrum_json(run, p)
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)
    assert d["channel"] == "desplazamiento"


@pytest.mark.parametrize("per_s", [10**3, 10**6, 10**9])
def test_epoch_stamps_without_unit(run, tmp_path, per_s):
    t, x = signal()
    p = tmp_path / "epoch.csv"
    start = 1_700_000_000 * per_s
    p.write_text(
        "timestamp,acc (m/s^2)\n" + "".join(f"{start + k * per_s // int(FS)},{v:.6f}\n" for k, v in enumerate(x))
    )
    d = spectrum_json(run, p)
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)


def test_sample_counter_column_is_not_analysed(run, tmp_path):
    t, x = signal()
    p = tmp_path / "logger.csv"
    p.write_text(
        "index,time (s),displacement (mm)\n" + "".join(f"{k},{a:.4f},{v:.6f}\n" for k, (a, v) in enumerate(zip(t, x)))
    )
    d = spectrum_json(run, p)
    assert d["channel"] == "displacement" and d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)


def test_channel_named_as_the_file_writes_it(run, tmp_path):
    t, x = signal()
    p = tmp_path / "v.csv"
    p.write_text("time,vx_ms,vz_ms\n" + "".join(f"{a:.4f},0,{v:.6f}\n" for a, v in zip(t, x)))
    d = spectrum_json(run, p, "--channel", "vz_ms")
    assert d["channel"] == "vz" and d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)
    one_line_error(
        run("spectrum", p, "--channel", "vy_ms"),
        "v.csv",
        "channel 'vy_ms' is not in the recording",
        "vz (file: 'vz_ms')",
    )


# ----------------------------------------------------------------------------- clocks: midnight and DST


def tod(seconds):
    s = seconds % 86400
    return f"{int(s // 3600):02d}:{int(s // 60 % 60):02d}:{s % 60:06.3f}"


def test_recording_across_midnight(run, tmp_path):
    t, x = signal()
    p = tmp_path / "night.csv"
    start = 86400 - 5.0  # 23:59:55, 20 s long
    p.write_text(
        "Hora;Aceleracion (g)\n"
        + "".join(f"{tod(start + a)};{v:.6f}\n".replace(".", ",", 1).replace(".", ",") for a, v in zip(t, x))
    )
    msg = one_line_error(run("spectrum", p), p, "time goes backwards", "crossing midnight", "--repair-time")
    assert ", line 1002:" in msg  # 23:59:59.995 on line 1001, then 00:00:00.000
    d = spectrum_json(run, p, "--repair-time")
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)


def test_daylight_saving_change(run, tmp_path):
    t, x = signal()
    p = tmp_path / "dst.csv"
    # local time: 02:59:55 ... 02:59:59.995, then the clock goes back to 02:00:00
    stamps = [f"2024-10-27 {tod(2 * 3600 + 3595 + a if a < 5 else 2 * 3600 + a - 5)}" for a in t]
    p.write_text("datetime,x (mm)\n" + "".join(f"{s},{v:.6f}\n" for s, v in zip(stamps, x)))
    one_line_error(run("spectrum", p), p, "time goes backwards", "daylight saving")
    d = spectrum_json(run, p, "--repair-time")
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)


def test_repeated_stamps_repaired_only_when_asked(run, tmp_path):
    t, x = signal()
    p = tmp_path / "rep.csv"
    rows = [f"{a:.4f},{v:.6f}" for a, v in zip(t, x)]
    rows.insert(500, rows[499])
    p.write_text("time (s),x (mm)\n" + "\n".join(rows) + "\n")
    one_line_error(run("spectrum", p), p, "line 502", "repeats the previous row")
    assert spectrum_json(run, p, "--repair-time")["fundamental_hz"] == pytest.approx(F0, abs=1e-3)


def test_time_column_and_unit_options(run, tmp_path):
    t, x = signal()
    p = tmp_path / "clock.csv"
    p.write_text("clock,x (mm)\n" + "".join(f"{1000 * a:.1f},{v:.6f}\n" for a, v in zip(t, x)))
    # 'clock' is not a time name: without --time-column there is no time base
    one_line_error(run("spectrum", p), p, "no time column")
    assert spectrum_json(run, p, "--time-column", "clock", "--time-unit", "ms")["fundamental_hz"] == pytest.approx(
        F0, abs=1e-3
    )
    assert spectrum_json(run, p, "--time-column", "0", "--time-unit", "ms")["fundamental_hz"] == pytest.approx(
        F0, abs=1e-3
    )
    d = spectrum_json(run, p, "--time-column", "none", "--sample-rate", "200", "--channel", "x")
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)
    one_line_error(run("spectrum", p, "--time-column", "7"), p, "--time-column 7 is out of range")
    one_line_error(run("spectrum", p, "--time-column", "tick"), p, "no time column 'tick'")


def test_bad_time_unit_is_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["spectrum", str(tmp_path / "x.csv"), "--time-unit", "fortnight"])
    assert info.value.code == 2
    assert "--time-unit" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------- netCDF


def test_netcdf_with_fill_values_and_reversed_time(run, tmp_path):
    xr = pytest.importorskip("xarray")
    t, x = signal()
    x = x.copy()
    x[100:110] = 9.969209968386869e36  # netCDF's default fill: no data there
    p = tmp_path / "logger.nc"
    xr.Dataset({"x": ("time", x, {"units": "m"})}, coords={"time": ("time", t, {"units": "s"})}).to_netcdf(
        p, engine="h5netcdf"
    )
    d = spectrum_json(run, p)
    assert d["fundamental_hz"] == pytest.approx(F0, abs=1e-2)
    bad = tmp_path / "reversed.nc"
    xr.Dataset({"x": ("time", x[::-1])}, coords={"time": ("time", t[::-1])}).to_netcdf(bad, engine="h5netcdf")
    one_line_error(run("spectrum", bad), bad, "time goes backwards", "variable 'time'")
