"""Layouts of loggers and apps read right with no options, each from a file of that layout.

The corpus in data/thirdparty has no MetaWear, Arduino or phyphox-with-a-repeated-stamp file, so these
files are written here in the layout their makers document: MetaWear MetaBase CSV headers
(``epoc (ms),timestamp (-0500),elapsed (s),x-axis (g),...``, the text stamp ``2022-08-05T15.26.13.153``),
Sensor Logger (``time,seconds_elapsed,z,y,x``, time in Unix ns), Arduino ``micros()``/``millis()``
loggers (an integer clock column with no unit), PicoQuake (its ``# Config: data_rate = ...`` comment,
PLab's docs/acquisition_data.md), phyphox (``"Time (s)","Acceleration x (m/s^2)"``...), Physics
Toolbox Sensor Suite (leading empty line, trailing comma, values held between updates).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.text.units import STANDARD_GRAVITY
from vibkit.runtime.reader_options import READER_OPTIONS

F0 = 3.5  # test signal [Hz]


def sine(t):
    return np.sin(2 * np.pi * F0 * t)


# ------------------------------------------------------------------------------------------ MetaWear


@pytest.mark.parametrize("header", ["epoc (ms),timestamp (-0500),elapsed (s)", "epoch (ms),time (-13:00),elapsed (s)"])
def test_metawear_numeric_clock_preferred_over_the_text_stamp(tmp_path, header):
    fs, n = 100.0, 800
    epoch_ms = 1659731173153 + np.round(np.arange(n) * 1000 / fs).astype(np.int64)
    rows = []
    for k, ms in enumerate(epoch_ms):
        s, frac = divmod(int(ms) - 1659731173153 + 13153, 1000)
        stamp = f"2022-08-05T15.26.{s:02d}.{frac:03d}" if s < 60 else f"2022-08-05T15.27.{s - 60:02d}.{frac:03d}"
        rows.append(f"{ms},{stamp},{k / fs:.3f},{0.5 * sine(k / fs):.4f},0.010,-0.998\n")
    p = tmp_path / "MetaWear_2022-08-05T15.26.13.153_C8D2AB32F6E1_Accelerometer.csv"
    p.write_text(f"{header},x-axis (g),y-axis (g),z-axis (g)\n" + "".join(rows))
    ds = read_recording(p)
    assert ds["time"].attrs["column"] == header.split(",")[0]
    assert ds.attrs["start_time"] == "2022-08-05T20:26:13.153000+00:00"  # epoch 1659731173153 ms, UTC
    assert ds.attrs["sample_rate_hz"] == pytest.approx(fs, rel=0.01)
    assert list(ds.data_vars) == ["x_axis", "y_axis", "z_axis"]
    assert ds["z_axis"].attrs["units"] == "m/s^2" and ds["z_axis"].attrs["original_units"] == "g"
    assert ds["z_axis"].values[0] == pytest.approx(-0.998 * STANDARD_GRAVITY)
    assert f"'{header.split(',')[1]}' is another clock, not a channel" in ds.attrs["history"]
    assert "'elapsed (s)' is another clock, not a channel" in ds.attrs["history"]
    # with the epoch column gone, the elapsed seconds are chosen over the text stamps
    q = tmp_path / "cut.csv"
    q.write_text("\n".join(",".join(line.split(",")[1:]) for line in p.read_text().splitlines()) + "\n")
    cut = read_recording(q)
    assert cut["time"].attrs["column"] == "elapsed (s)" and "(numbers) chosen over" in cut.attrs["history"]
    assert cut.attrs["sample_rate_hz"] == pytest.approx(fs, rel=0.01)


# ------------------------------------------------------------------------------------------ Sensor Logger


def sensor_logger(path, n=1000, fs=100.0):
    t_ns = 1760565906248623000 + np.round(np.arange(n) * 1e9 / fs).astype(np.int64)
    el = (t_ns - t_ns[0]) / 1e9 + 0.1036
    path.write_text(
        "time,seconds_elapsed,z,y,x\n"
        + "".join(f"{a},{float(e)!r},{float(sine(k / fs))!r},0.1,-0.2\n" for k, (a, e) in enumerate(zip(t_ns, el)))
    )
    return path


def test_sensor_logger_clock_is_no_channel_and_axes_in_m_s2(tmp_path, run):
    p = sensor_logger(tmp_path / "Accelerometer.csv")
    ds = read_recording(p)
    assert list(ds.data_vars) == ["z", "y", "x"]  # never 'seconds_elapsed'
    assert all(ds[v].attrs["units"] == "m/s^2" for v in ("x", "y", "z"))
    assert ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=1e-6)
    assert "as the app documents for Accelerometer.csv" in ds.attrs["history"]
    rc, out, _ = run("spectrum", p, "--json")  # the default channel is an axis, not the clock
    d = json.loads(out)
    assert rc == 0 and d["channel"] == "z" and d["fundamental_hz"] == pytest.approx(F0, abs=0.01)


def test_sensor_logger_file_of_an_unknown_sensor_keeps_no_unit(tmp_path):
    ds = read_recording(sensor_logger(tmp_path / "Magnetometer.csv"))
    assert list(ds.data_vars) == ["z", "y", "x"] and ds["x"].attrs["units"] == "unknown"
    assert "does not say the sensor" in ds.attrs["history"]


# ------------------------------------------------------------------------------------------ Arduino


def arduino(path, start, step, n=600, name="Time", seed=1):
    rng = np.random.default_rng(seed)
    t = start + np.cumsum(rng.integers(step - step // 200, step + step // 200 + 1, size=n))
    v = np.round(2048 + 1000 * sine((t - t[0]) * (1e-6 if step > 1000 else 1e-3))).astype(int)
    path.write_text(f"{name},AcX,AcY,AcZ\n" + "".join(f"{a},{b},{-b},16384\n" for a, b in zip(t, v)))
    return path


def test_arduino_micros_clock_read_as_microseconds(tmp_path):
    ds = read_recording(arduino(tmp_path / "LOG00042.CSV", 25_894_704, 3400))
    assert ds.attrs["sample_rate_hz"] == pytest.approx(1e6 / 3400, rel=0.01)
    assert "read as us" in ds.attrs["history"] and "microcontroller clock" in ds.attrs["history"]


def test_arduino_millis_clock_read_as_milliseconds(tmp_path):
    ds = read_recording(arduino(tmp_path / "log.csv", 120_311, 10))
    assert ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=0.01)
    assert "read as ms" in ds.attrs["history"]
    named = read_recording(arduino(tmp_path / "named.csv", 5_000_000, 50, name="micros"))  # the name says it
    assert named.attrs["sample_rate_hz"] == pytest.approx(2e4, rel=0.01)


def test_arduino_clock_of_unclear_unit_is_refused_naming_time_unit(tmp_path, run):
    p = arduino(tmp_path / "log.csv", 120_000, 50)  # 20 Hz in ms, 20 kHz in us: both plausible
    with pytest.raises(RecordingError, match=r"cannot tell its unit; pass time_unit="):
        read_recording(p)
    for cmd in (["spectrum"], ["report", "-o", tmp_path / "r.pdf"], ["ride"]):
        rc, _, err = run(cmd[0], p, *cmd[1:])
        assert rc == 1 and "pass --time-unit (s, ms, us)" in err and "time_unit=" not in err, err
    assert read_recording(p, time_unit="ms").attrs["sample_rate_hz"] == pytest.approx(20.0, rel=0.01)


# ------------------------------------------------------------------------------------------ PicoQuake


def test_picoquake_rate_from_the_config_comment(tmp_path):
    n = 2000
    p = tmp_path / "car.csv"
    p.write_text(
        "# PLab PicoQuake Data\n# Time: 2024-04-21 15:54:46.333682, Device: D4E9 (E6632891E36F2029)\n"
        "# Num. samples: 2000, Duration: 1.0 s\n"
        "# Config: data_rate = 2000.0 Hz, filter = 488 Hz, acc_range = 4 g, gyro_range = 250.0 dps\n"
        "# Integrity: True, Skipped samples: 0\ncount,a_x,a_y,a_z,g_x,g_y,g_z\n"
        + "".join(f"{k},{0.1 * sine(k / 2000):.5f},0.0,1.0,0.5,-0.5,180.0\n" for k in range(n))
    )
    ds = read_recording(p)
    assert ds.attrs["sample_rate_hz"] == 2000.0
    assert list(ds.data_vars) == ["a_x", "a_y", "a_z", "g_x", "g_y", "g_z"]  # 'count' is no channel
    assert ds["a_z"].values[0] == pytest.approx(STANDARD_GRAVITY) and ds["a_z"].attrs["units"] == "m/s^2"
    assert ds["g_z"].values[0] == pytest.approx(np.pi) and ds["g_z"].attrs["units"] == "rad/s"


def test_no_rate_error_names_the_flags(tmp_path, run):
    p = tmp_path / "x.csv"
    p.write_text("a_x,a_y\n" + "".join(f"{k * 0.1},{k * 0.2}\n" for k in range(50)))
    rc, _, err = run("spectrum", p)
    assert rc == 1 and "(--time-column) or a sample rate (--sample-rate)" in err and "sample_rate=" not in err


# ------------------------------------------------------------------------------------------ phyphox


def phyphox(path, t):
    path.write_text(
        '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)",'
        '"Absolute acceleration (m/s^2)"\n'
        + "".join(f"{a:.9E},{sine(a):.9E},0.000000000E0,9.806650000E0,9.8E0\n" for a in t)
    )
    return path


def test_phyphox_repeated_first_stamp_dropped_with_a_note(tmp_path):
    t = np.r_[0.0, np.arange(999) * 0.01]  # t = 0 twice, then every 10 ms
    ds = read_recording(phyphox(tmp_path / "Raw Data.csv", t))
    assert ds.sizes["time"] == 999 and ds["time"].values[0] == 0.0
    assert "a known phyphox artefact at the start); the first row (line 2) dropped" in ds.attrs["history"]
    assert ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=1e-6)


def test_a_repeated_stamp_elsewhere_is_still_refused_naming_the_flag(tmp_path, run):
    t = np.r_[np.arange(500) * 0.01, 4.99, 5.0 + np.arange(300) * 0.01]
    p = phyphox(tmp_path / "Raw Data.csv", t)
    with pytest.raises(RecordingError, match="repeats the previous row"):
        read_recording(p)
    rc, _, err = run("pitch", p, "--speed", "0.5")
    assert rc == 1 and "pass --repair-time to drop repeats" in err
    rc, _, err = run("ride", p)  # ride suggests --repair-time, and takes it
    assert rc == 1 and "pass --repair-time to drop repeats" in err
    rc, out, err = run("ride", p, "--repair-time", "--segment", "0.5:7", "--json")
    assert rc == 0, err
    assert json.loads(out)["sample_rate_hz"] == pytest.approx(100.0, rel=0.01)


# ------------------------------------------------------------------------------------------ Physics Toolbox


def test_physics_toolbox_held_samples_give_the_true_update_rate(tmp_path):
    rng = np.random.default_rng(7)
    rows_t = np.cumsum(rng.uniform(0.005, 0.040, size=1500))  # rows ~44 Hz whenever any sensor updates
    upd = np.arange(0.0, rows_t[-1], 1 / 15.0)  # g-force sensor updates at 15 Hz
    idx = np.searchsorted(upd, rows_t, side="right") - 1
    g = np.round(0.3 * sine(upd[idx]) + 1e-4 * idx, 4)  # held between its updates
    p = tmp_path / "multi.csv"
    p.write_text(
        "\ntime,gFx,gFy,gFz,ax,ay,az,wx,wy,wz,\n"
        + "".join(
            f"{a:.6f},{b:.4f},{b:.4f},{b:.4f},{r:.4f},0.0,0.0,{r:.4f},0.0,0.0,\n"
            for a, b, r in zip(rows_t, g, rng.normal(size=rows_t.size))
        )
    )
    ds = read_recording(p)
    n_upd = np.unique(idx).size
    true_rate = (n_upd - 1) / (upd[idx[-1]] - upd[idx[0]])
    assert ds["gfx"].attrs["update_rate_hz"] == pytest.approx(15.0, rel=0.02)
    assert ds["gfx"].attrs["nyquist_hz"] == pytest.approx(7.5, rel=0.02)
    assert abs(true_rate - 15.0) < 0.3
    assert "update_rate_hz" not in ds["ax"].attrs  # a fresh value on every row
    assert ds["ax"].attrs["units"] == "m/s^2" and ds["wx"].attrs["units"] == "rad/s"
    assert "held samples" in ds.attrs["history"]
    assert ds.attrs["sample_rate_hz"] == pytest.approx(1 / np.mean(np.diff(rows_t)), rel=0.01)


# ------------------------------------------------------------------------------------------ waveform files


def mseed(path, traces):
    obspy = pytest.importorskip("obspy")
    st = obspy.Stream(
        [
            obspy.Trace(
                data=np.asarray(d, dtype=np.int32),
                header={
                    "network": "CH",
                    "station": "BALST",
                    "channel": ch,
                    "sampling_rate": fs,
                    "starttime": obspy.UTCDateTime(2024, 1, 1) + t0,
                },
            )
            for ch, d, fs, t0 in traces
        ]
    )
    st.write(str(path), format="MSEED")
    return path


def test_units_option_scales_raw_counts(tmp_path):
    fs = 100.0
    counts = np.round(2048 * sine(np.arange(3000) / fs)).astype(int)
    p = mseed(tmp_path / "one.mseed", [("HNZ", counts, fs, 0.0)])
    raw = read_recording(p)
    assert raw["ch_balst_hnz"].attrs["units"] == "counts"
    ds = read_recording(p, units="g/2048")
    np.testing.assert_allclose(ds["ch_balst_hnz"].values, counts * STANDARD_GRAVITY / 2048)
    assert ds["ch_balst_hnz"].attrs["units"] == "m/s^2"


def test_two_channel_miniseed_with_different_starts_read_with_channel(tmp_path, run):
    fs = 100.0
    t = np.arange(6000) / fs
    p = mseed(
        tmp_path / "two.mseed",
        [
            ("LHE", np.round(1000 * np.cos(t)), fs, 0.0),
            ("LHZ", np.round(1000 * (sine(t) + 0.3 * sine(2 * t))), fs, 0.37),
        ],
    )
    with pytest.raises(RecordingError, match="read one trace at a time with channel="):
        read_recording(p)
    rc, _, err = run("spectrum", p)
    assert rc == 1 and "--channel LHZ" in err.replace("--channel LHE", "--channel LHZ") and "channel=" not in err
    rc, out, err = run("spectrum", p, "--channel", "LHZ", "--json")
    assert rc == 0, err
    assert json.loads(out)["fundamental_hz"] == pytest.approx(F0, abs=0.01)


# ------------------------------------------------------------------------------------------ the CLI


#: the reader's flags as vibkit.runtime.reader_options declares them (--channel: checked per command below)
READER_FLAGS = {o.flag for o in READER_OPTIONS if o.flag and o.name != "channel"}


def _options(argv):
    from vibkit.cli.app import _parser

    p = _parser()
    sub = next(a for a in p._actions if a.dest == "command")
    sp = sub.choices[argv[0]]
    if len(argv) > 1:
        sp = next(a for a in sp._actions if a.dest == "fleet_command").choices[argv[1]]
    return {o for a in sp._actions for o in a.option_strings}


@pytest.mark.parametrize(
    "cmd", [["spectrum"], ["pitch"], ["compare"], ["report"], ["ride"], ["fleet", "add"], ["fleet", "scan"]]
)
def test_every_command_that_reads_a_recording_takes_the_reader_options(cmd):
    opts = _options(cmd)
    assert READER_FLAGS <= opts, READER_FLAGS - opts
    # ride names its axes with --channels, a fleet scan's catalogue names each file's channel
    assert ("--channel" in opts) == (cmd not in (["ride"], ["fleet", "scan"]))


def test_units_option_on_the_command_line(tmp_path, run):
    p = tmp_path / "raw.csv"
    t = np.arange(4000) / 200.0
    # raw counts of a link-pass family (a lone quantised tone is refused by the decision: see the note there)
    fam = lambda a: sine(a) + 0.5 * np.sin(4 * np.pi * F0 * a) + 0.3 * np.sin(6 * np.pi * F0 * a)  # noqa: E731
    p.write_text("time,az\n" + "".join(f"{a:.4f},{round(2048 * fam(a))}\n" for a in t))
    rc, out, err = run("spectrum", p, "--units", "az=g/2048", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["units"] == "m/s^2" and d["fundamental_hz"] == pytest.approx(F0, abs=1e-3)
    rc, _, err = run("spectrum", p, "--units", "furlongs")
    assert rc == 1 and "not a unit vibkit knows" in err


def test_reader_messages_name_flags_on_the_command_line_and_arguments_in_python():
    """The reader writes an option as the caller gives it: ``time_unit=`` in Python, ``--time-unit`` within the
    command line's :func:`flag_spelling`; nothing rewrites the text afterwards."""
    from vibkit.runtime.reader_options import either, flag_spelling, spell

    said = lambda: [  # noqa: E731
        f"pass {spell('time_unit')} (s, ms, us)",
        f"({spell('time_column')}) or ({spell('sample_rate')})",
        f"pass {spell('repair_time', True)} to repair",
        f"kept (pass {spell('units', {'ax': 'g/<counts per g>'})})",
        f"no time column ({spell('time_column', False)} given)",
        f"raise it with {either('max_bytes', 'the environment variable V')}",
    ]
    assert said() == [
        "pass time_unit= (s, ms, us)",
        "(time_column=) or (sample_rate=)",
        "pass repair_time=True to repair",
        "kept (pass units={'ax': 'g/<counts per g>'})",
        "no time column (time_column=False given)",
        "raise it with max_bytes= or the environment variable V",
    ]
    with flag_spelling():
        assert said() == [
            "pass --time-unit (s, ms, us)",
            "(--time-column) or (--sample-rate)",
            "pass --repair-time to repair",
            "kept (pass --units ax=g/<counts per g>)",
            "no time column (--time-column none given)",
            "raise it with the environment variable V",
        ]
    assert spell("time_unit") == "time_unit="  # the spelling is the command line's only while it runs


def test_fleet_scan_applies_the_reader_options_to_every_file(tmp_path, run):
    (tmp_path / "visits").mkdir()
    for k, name in enumerate(("a.csv", "b.csv")):
        arduino(tmp_path / "visits" / name, 120_000 + 7 * k, 50, n=200)  # unit unclear without --time-unit
    (tmp_path / "cat.csv").write_text("file,unit,speed_m_s,date,nominal_pitch_m\n*.csv,E1,0.5,2026-01-01,0.13333\n")
    db = tmp_path / "f.sqlite"
    rc, _, err = run(
        "fleet", "scan", tmp_path / "visits", "--catalogue", tmp_path / "cat.csv", "--db", db, "--workers", "0"
    )
    assert rc == 1 and err.count("pass --time-unit (s, ms, us)") == 2, err
    rc, _, err = run(
        "fleet",
        "scan",
        tmp_path / "visits",
        "--catalogue",
        tmp_path / "cat.csv",
        "--db",
        db,
        "--workers",
        "0",
        "--time-unit",
        "ms",
    )
    assert "--time-unit" not in err and "cannot tell its unit" not in err, err  # read; no link-pass is fine
