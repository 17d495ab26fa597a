"""CSV reader features on small files written here, each checked against what was written."""

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording

G = 9.80665


def write(tmp_path, text, name="rec.csv", encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(text.encode(encoding))
    return p


def table(t, cols, sep=",", dec=".", fmt="{:.6f}"):
    out = []
    for i in range(len(t)):
        cells = [fmt.format(t[i])] + [fmt.format(c[i]) for c in cols]
        out.append(sep.join(c.replace(".", dec) for c in cells))
    return "\n".join(out) + "\n"


T = np.arange(50) / 100.0
X = np.sin(2 * np.pi * 3.0 * T)


@pytest.mark.parametrize(
    "sep, dec", [(s, d) for s in (",", ";", "\t", "|", " ") for d in (".", ",") if (s, d) != (",", ",")]
)
def test_delimiter_and_decimal_detected(tmp_path, sep, dec):
    head = sep.join(["time (s)", "acc (m/s^2)"]) if sep != " " else "time_s acc_g"
    p = write(tmp_path, head + "\n" + table(T, [X], sep, dec))
    ds = read_recording(p)
    var = "acc"
    factor = 1.0 if sep != " " else G
    np.testing.assert_allclose(ds["time"].values, T, atol=5e-7)
    np.testing.assert_allclose(ds[var].values, X * factor, atol=5e-7 * factor)
    assert ("decimal comma detected" in ds.attrs["history"]) == (dec == ",")


def test_decimal_commas_in_a_comma_separated_file_are_named(tmp_path):
    """A stranger's 'time_s,displacement_mm' over rows like '0,005,-54,88112' was read as a 4-column file with its
    header taken for metadata; the error asked for a time column, and --sample-rate analysed the digits."""
    text = "time_s,displacement_mm\n" + "".join(
        f"{t:.3f},{x:.5f}\n".replace(".", ",") for t, x in zip(T[1:], -54 + X[1:])
    )
    p = write(tmp_path, text)
    with pytest.raises(RecordingError, match=r"line 2: rows of 4 whole numbers under 2 column names .*decimal commas"):
        read_recording(p)
    # the same numbers with ';' between the columns read as they were written
    fixed = "time_s;displacement_mm\n" + "".join(
        f"{t:.3f};{x:.5f}\n".replace(".", ",") for t, x in zip(T[1:], -54 + X[1:])
    )
    ds = read_recording(write(tmp_path, fixed, name="ok.csv"))
    assert ds.sizes["time"] == T.size - 1


def test_single_column_decimal_comma_with_header(tmp_path):
    p = write(
        tmp_path, "Sample rate: 100 Hz\nDesplazamiento (mm)\n" + "\n".join(f"{v:.4f}".replace(".", ",") for v in X)
    )
    ds = read_recording(p)
    np.testing.assert_allclose(ds["desplazamiento"].values, np.round(X, 4) * 1e-3, rtol=1e-12)
    assert ds.attrs["sample_rate_hz"] == 100.0


@pytest.mark.parametrize("unit, factor", [("s", 1.0), ("ms", 1e-3), ("us", 1e-6)])
def test_time_units_from_header(tmp_path, unit, factor):
    ticks = np.arange(20) * 5  # integer ticks in the file's unit
    p = write(tmp_path, f"time ({unit}),x (mm)\n" + "".join(f"{k},{k % 3}\n" for k in ticks))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, ticks * factor, rtol=1e-15)
    np.testing.assert_allclose(ds["x"].values, (ticks % 3) * 1e-3, rtol=1e-15)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(1 / (5 * factor), rel=1e-12)


def test_time_unit_override(tmp_path):
    p = write(tmp_path, "time,x\n" + "".join(f"{k},{k}\n" for k in range(10)))
    ds = read_recording(p, time_unit="ms", units="mm")
    np.testing.assert_allclose(ds["time"].values, np.arange(10) * 1e-3)
    assert "time column 'time' in ms (given)" in ds.attrs["history"]


def test_unitless_time_read_as_ms_when_the_header_rate_says_so(tmp_path):
    p = write(tmp_path, "# Sample rate: 500 Hz\ntime,x (m)\n" + "".join(f"{2 * k},{k}\n" for k in range(10)))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, 2e-3 * np.arange(10), rtol=1e-15)
    assert "read as ms" in ds.attrs["history"]


@pytest.mark.parametrize(
    "stamps",
    [
        ["2021-06-15T10:00:00.000", "2021-06-15T10:00:00.250", "2021-06-15T10:00:00.500", "2021-06-15T10:00:01.000"],
        ["15/06/2021 10:00:00,000", "15/06/2021 10:00:00,250", "15/06/2021 10:00:00,500", "15/06/2021 10:00:01,000"],
        ["10:00:00:000", "10:00:00:250", "10:00:00:500", "10:00:01:000"],
        ["2021-06-15 10:00:00Z", "2021-06-15 10:00:00.25Z", "2021-06-15 10:00:00.5Z", "2021-06-15 10:00:01Z"],
    ],
)
def test_timestamp_time_columns(tmp_path, stamps):
    sep = ";" if "," in stamps[0] else ","
    p = write(tmp_path, f"Timestamp{sep}v (m/s)\n" + "".join(f"{s}{sep}{i}\n" for i, s in enumerate(stamps)))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, [0.0, 0.25, 0.5, 1.0], atol=1e-9)
    assert ds["v"].attrs["quantity"] == "velocity"
    # day/month/year stamps state their start as ISO 8601 (what reports and the fleet read); others as written
    assert ds.attrs["start_time"] == ("2021-06-15T10:00:00" if stamps[0].startswith("15/") else stamps[0])


def test_epoch_seconds_shifted_and_recorded(tmp_path):
    t0 = 1_623_751_263.0
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{t0 + k / 8:.3f},{k}\n" for k in range(16)))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, np.arange(16) / 8, atol=1e-6)
    assert ds.attrs["time_offset_s"] == t0


def test_metadata_block_kept_as_attrs(tmp_path):
    text = (
        "# Site: Leon\n# chain_speed_m_s = 0.49\n# free text about the test\nOperator;Ana\n"
        "Steps;34\ntime (s);x (mm)\n" + table(T, [X], ";")
    )
    ds = read_recording(write(tmp_path, text))
    assert ds.attrs["site"] == "Leon"
    assert ds.attrs["chain_speed_m_s"] == 0.49
    assert ds.attrs["operator"] == "Ana"
    assert ds.attrs["steps"] == 34
    assert "free text about the test" in ds.attrs["comment"]


def test_reserved_metadata_keys_do_not_overwrite_provenance(tmp_path):
    text = "history: forged\nsha256: abc\ntime (s),x (m)\n" + table(T, [X])
    p = write(tmp_path, text)
    ds = read_recording(p)
    assert ds.attrs["meta_history"] == "forged" and ds.attrs["meta_sha256"] == "abc"
    assert ds.attrs["sha256"] != "abc" and "forged" not in ds.attrs["history"]


def test_channel_selection_by_header_name_or_variable(tmp_path):
    p = write(tmp_path, "time (s),acc x (g),acc z (g)\n" + table(T, [X, 2 * X]))
    for key in ("acc z (g)", "acc z", "ACC_Z"):
        ds = read_recording(p, channel=key)
        assert list(ds.data_vars) == ["acc_z"]
        np.testing.assert_allclose(ds["acc_z"].values, np.round(2 * X, 6) * G, rtol=1e-12)
    ds = read_recording(p, channel=["acc_z", "acc_x"])
    assert list(ds.data_vars) == ["acc_z", "acc_x"]
    with pytest.raises(RecordingError, match=r"no channel 'acc y'; channels: 'acc x \(g\)', 'acc z \(g\)'"):
        read_recording(p, channel="acc y")


def test_unit_overrides(tmp_path):
    p = write(tmp_path, "time,a,b\n" + "".join(f"{k / 10},{k},{k}\n" for k in range(10)))
    ds = read_recording(p, units={"a": "g/2048", "b": "mm"})
    np.testing.assert_allclose(ds["a"].values, np.arange(10) * G / 2048, rtol=1e-15)
    np.testing.assert_allclose(ds["b"].values, np.arange(10) * 1e-3, rtol=1e-15)
    assert ds["b"].attrs["quantity"] == "displacement"
    with pytest.raises(ValueError, match="units\\['a'\\]='furlong'"):
        read_recording(p, units={"a": "furlong"})
    with pytest.raises(ValueError, match="units: no column 'c'"):
        read_recording(p, units={"c": "g"})


def test_column_without_unit_is_flagged(tmp_path):
    p = write(tmp_path, "time,a\n" + "".join(f"{k / 10},{k}\n" for k in range(10)))
    ds = read_recording(p)
    assert ds["a"].attrs["units"] == "unknown" and ds["a"].attrs["quantity"] == "other"
    assert "column 'a' has no unit" in ds.attrs["history"]


def test_bursts_become_segments_not_bridged(tmp_path):
    fs, n = 100.0, 50
    t = np.concatenate([k * 3.0 + np.arange(n) / fs for k in range(4)])
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a:.4f},{a:.4f}\n" for a in t))
    ds = read_recording(p)
    assert ds["segment"].dtype == np.int32
    np.testing.assert_array_equal(ds["segment"].values, np.repeat(np.arange(4), n))
    np.testing.assert_allclose(ds["time"].values, t, atol=1e-9)  # nothing filled in the gaps
    assert ds.attrs["sample_rate_hz"] == pytest.approx(fs, rel=1e-9)
    assert ds.attrs["segment_count"] == 4
    assert "4 segments split at gaps > 5 sample periods" in ds.attrs["history"]


def test_gap_factor_option(tmp_path):
    t = np.r_[np.arange(10), 13 + np.arange(10)] / 10.0  # one step of 4 periods
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a:.3f},1\n" for a in t))
    assert "segment" not in read_recording(p).data_vars
    assert int(read_recording(p, gap_factor=3)["segment"].max()) == 1


def test_jitter_measured_exactly(tmp_path):
    # steps alternate T(1+e), T(1-e): mean T, rms deviation exactly e
    e, period = 0.04, 0.01
    steps = period * (1 + e * np.where(np.arange(200) % 2 == 0, 1, -1))
    t = np.r_[0.0, np.cumsum(steps)]
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a:.9f},0.5\n" for a in t))
    ds = read_recording(p)
    assert ds.attrs["time_jitter_rms_percent"] == pytest.approx(100 * e, rel=1e-5)
    np.testing.assert_allclose(ds["time"].values, t, atol=1e-9)  # kept as is


def test_resample_linear_per_segment(tmp_path):
    rng = np.random.default_rng(1)
    t = np.r_[
        np.cumsum(0.01 * (1 + 0.1 * rng.uniform(-1, 1, 100))), 5 + np.cumsum(0.01 * (1 + 0.1 * rng.uniform(-1, 1, 100)))
    ]
    x = 3.0 * t + 1.0  # linear: interpolation is exact
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a:.9f},{b:.9f}\n" for a, b in zip(t, x)))
    ds = read_recording(p, resample="linear", sample_rate=100.0)
    for s in (0, 1):
        ts = ds["time"].values[ds["segment"].values == s]
        np.testing.assert_allclose(np.diff(ts), 0.01, rtol=1e-9)
        assert ts[0] == pytest.approx(t[0 if s == 0 else 100], abs=1e-9)  # grid starts at the segment
    np.testing.assert_allclose(ds["x"].values, 3.0 * ds["time"].values + 1.0, atol=1e-8)
    assert "resampled linearly to 100 Hz, each segment on its own" in ds.attrs["history"]


def test_repeated_stamps_and_backward_time_repaired_only_when_asked(tmp_path):
    text = "time (s),x (m)\n0.0,0\n0.1,1\n0.1,2\n0.3,3\n0.2,4\n0.4,5\n"
    p = write(tmp_path, text)
    with pytest.raises(RecordingError, match="line 4: time stamp 0.1 s"):
        read_recording(p)
    ds = read_recording(p, repair_time=True)
    np.testing.assert_allclose(ds["time"].values, [0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_allclose(ds["x"].values, [0, 1, 4, 3, 5])  # first of repeats kept
    assert "time repaired" in ds.attrs["history"]


def test_sample_rate_option_without_time_column(tmp_path):
    p = write(tmp_path, "acc (g)\n" + "\n".join(str(v) for v in range(10)) + "\n")
    with pytest.raises(RecordingError, match="no time column and no sample rate"):
        read_recording(p)
    ds = read_recording(p, sample_rate=250)
    np.testing.assert_allclose(ds["time"].values, np.arange(10) / 250)
    assert ds.attrs["sample_rate_hz"] == 250.0


def test_time_column_option(tmp_path):
    p = write(tmp_path, "clock,x (m)\n" + "".join(f"{k * 0.5},{2 * k}\n" for k in range(6)))  # (a +1 ramp counts)
    ds = read_recording(p, time_column="clock")
    np.testing.assert_allclose(ds["time"].values, np.arange(6) * 0.5)
    ds = read_recording(p, time_column=False, sample_rate=10)
    assert list(ds.data_vars) == ["clock", "x"]
    np.testing.assert_allclose(ds["time"].values, np.arange(6) / 10)


def test_missing_values_kept_as_nan_and_text_columns_skipped(tmp_path):
    text = "time (s),x (m),note,y (m)\n0,1,start,\n0.1,,ok,2\n0.2,3,ok,3\n"
    ds = read_recording(write(tmp_path, text))
    assert list(ds.data_vars) == ["x", "y"]
    np.testing.assert_array_equal(ds["x"].values, [1, np.nan, 3])
    assert "column 'note' holds text, not numbers; skipped" in ds.attrs["history"]
    assert "column 'x (m)': 1 missing value(s) kept as NaN" in ds.attrs["history"]


def test_crlf_bom_and_trailing_delimiters(tmp_path):
    text = "\ufefftime (s);x (mm);\r\n0;1;\r\n0,5;2;\r\n1;3;\r\n"
    ds = read_recording(write(tmp_path, text))
    np.testing.assert_allclose(ds["time"].values, [0, 0.5, 1])
    np.testing.assert_allclose(ds["x"].values, [1e-3, 2e-3, 3e-3])


def test_options_are_validated():
    for kwargs, word in [
        ({"sample_rate": -1}, "sample_rate"),
        ({"resample": "cubic"}, "resample"),
        ({"gap_factor": 0.5}, "gap_factor"),
        ({"delimiter": "x"}, "delimiter"),
        ({"decimal": ";"}, "decimal"),
    ]:
        with pytest.raises(ValueError, match=word):
            read_recording("whatever.csv", **kwargs)


def test_units_row_below_the_header(tmp_path):
    text = "Time;Accel;Disp\n[ms];[g];[mm]\n0;0,5;1\n10;1,0;2\n20;1,5;3\n"
    ds = read_recording(write(tmp_path, text))
    np.testing.assert_allclose(ds["time"].values, [0, 0.01, 0.02])
    np.testing.assert_allclose(ds["accel"].values, np.array([0.5, 1.0, 1.5]) * G)
    np.testing.assert_allclose(ds["disp"].values, [1e-3, 2e-3, 3e-3])
    assert "units row on line 2" in ds.attrs["history"]


def test_a_time_stamp_without_a_zone_is_said_to_be_taken_as_utc(tmp_path):
    """A logger's naive stamps: the start is taken as UTC (a report dates the recording so) and the reader's
    history says it; a stamp with its zone says nothing of the kind."""
    import vibkit

    naive = tmp_path / "naive.csv"
    naive.write_text(
        "Timestamp,x\n" + "".join(f"2026-11-20T09:15:{i // 10:02d}.{i % 10}00,{i % 3}\n" for i in range(200))
    )
    zoned = tmp_path / "zoned.csv"
    zoned.write_text(
        "Timestamp,x\n" + "".join(f"2026-11-20T09:15:{i // 10:02d}.{i % 10}00+01:00,{i % 3}\n" for i in range(200))
    )
    assert "no time zone in the file: taken as UTC" in vibkit.read_recording(naive).attrs["history"]
    assert "taken as UTC" not in vibkit.read_recording(zoned).attrs["history"]
