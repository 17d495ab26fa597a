"""Reader inputs: channel names as the file writes them, sample counters, epoch times,
UTF-16 text, non-regular files, the size limit, netCDF time checks and fill values."""

import os
import stat

import numpy as np
import pytest
import xarray as xr

from vibkit.diagnose.pitch import pick_channel
from vibkit.io import (
    DEFAULT_MAX_RECORDING_BYTES,
    max_recording_bytes,
    read_recording,
    resolve_channel,
    write_result,
)

from support.contracts import recording_error

FS = 200.0
T = np.arange(400) / FS


def write(tmp_path, text, name="rec.csv", encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return p


# ----------------------------------------------------------------------------------- channel names


def test_channel_named_as_the_file_writes_it(tmp_path):
    p = write(tmp_path, "time,vz_ms,Acceleration x (m/s^2)\n" + "".join(f"{a},{-k},{2 * k}\n" for k, a in enumerate(T)))
    ds = read_recording(p)
    assert list(ds.data_vars) == ["vz", "acceleration_x"]
    assert ds["vz"].attrs["source_name"] == "vz_ms"
    assert ds["acceleration_x"].attrs["source_name"] == "Acceleration x (m/s^2)"
    for name in ("vz_ms", "VZ_MS", "vz"):
        assert resolve_channel(ds, name) == "vz" == pick_channel(ds, name)
    for name in ("Acceleration x (m/s^2)", "acceleration  x  (m/s^2)", "Acceleration x", "acceleration_x"):
        assert pick_channel(ds, name) == "acceleration_x"
    with pytest.raises(ValueError) as info:
        pick_channel(ds, "vy_ms")
    assert str(info.value) == (
        "rec.csv: channel 'vy_ms' is not in the recording (channels: vz (file: 'vz_ms'), "
        "acceleration_x (file: 'Acceleration x (m/s^2)'))"
    )


def test_source_name_survives_a_netcdf_round_trip(tmp_path):
    p = write(tmp_path, "time,vz_ms\n" + "".join(f"{a},{np.sin(a)}\n" for a in T))
    back = read_recording(write_result(read_recording(p), tmp_path / "r.nc"))
    assert pick_channel(back, "vz_ms") == "vz"


@pytest.mark.parametrize("counter", ["index", "#", "n", "Sample number", "sample", "No.", "idx"])
def test_sample_counter_is_never_the_default_channel(tmp_path, counter):
    x = np.sin(2 * np.pi * 3.5 * T)
    p = write(
        tmp_path,
        f"{counter},time (s),displacement (mm)\n"
        + "".join(f"{k + 1},{a:.4f},{v:.6f}\n" for k, (a, v) in enumerate(zip(T, x))),
    )
    ds = read_recording(p)
    assert list(ds.data_vars) == ["displacement"]  # a counter is no channel (a coordinate along time)
    var = [v for v in ds.coords if v != "time"][0]
    assert ds[var].attrs["sample_counter"] == 1
    assert pick_channel(ds) == "displacement"
    assert pick_channel(ds, counter) == var  # still there when asked for by name
    assert "counts samples" in ds.attrs["history"]


def test_an_unnamed_plus_one_ramp_is_a_counter_but_a_signal_is_not(tmp_path):
    x = np.sin(2 * np.pi * 3.5 * T)
    p = write(
        tmp_path,
        "a,time (s),b (mm),c (mm)\n"
        + "".join(f"{k + 100},{a:.4f},{v:.6f},{2 * k}\n" for k, (a, v) in enumerate(zip(T, x))),
    )
    ds = read_recording(p)
    assert ds["a"].attrs.get("sample_counter") == 1
    assert "sample_counter" not in ds["b"].attrs and "sample_counter" not in ds["c"].attrs  # step 2 is no counter
    assert pick_channel(ds) == "b"


def test_only_a_counter_is_an_error_naming_the_file(tmp_path):
    p = write(tmp_path, "index,time (s)\n" + "".join(f"{k},{a}\n" for k, a in enumerate(T)))
    ds = read_recording(p)
    with pytest.raises(ValueError, match=r"^rec.csv: the only channel\(s\) 'index' count samples"):
        pick_channel(ds)
    assert pick_channel(ds, "index") == "index"


def test_a_counter_named_n_with_fractions_is_a_channel(tmp_path):
    p = write(tmp_path, "time (s),n\n" + "".join(f"{a},{np.sin(a):.4f}\n" for a in T))
    ds = read_recording(p)
    assert "sample_counter" not in ds["n"].attrs and pick_channel(ds) == "n"


# ----------------------------------------------------------------------------------------- epoch times

EPOCH_S = 1_623_751_263  # 2021-06-15T10:01:03Z


@pytest.mark.parametrize("unit, per_s", [("ms", 10**3), ("us", 10**6), ("ns", 10**9)])
def test_unitless_epoch_times_detected_by_size_and_spacing(tmp_path, unit, per_s):
    stamps = [EPOCH_S * per_s + k * per_s // 200 for k in range(400)]  # exact integers, 200 Hz
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{s},{np.sin(k)}\n" for k, s in enumerate(stamps)))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, np.arange(400) / 200.0, rtol=0, atol=1e-12)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(200.0, rel=1e-12)
    assert ds.attrs["time_offset_s"] == pytest.approx(EPOCH_S, abs=1e-6)
    assert ds.attrs["start_time"] == "2021-06-15T10:01:03+00:00"
    assert f"Unix epoch times in {unit}" in ds.attrs["history"] and f"read as {unit}" in ds.attrs["history"]


def test_epoch_seconds_with_fractions(tmp_path):
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{EPOCH_S + k / 8:.3f},{k % 5}\n" for k in range(40)))
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, np.arange(40) / 8, atol=1e-6)
    assert "Unix epoch times in s" in ds.attrs["history"]


def test_epoch_unit_override_and_absurd_spacing(tmp_path):
    stamps = [EPOCH_S * 1000 + 5 * k for k in range(50)]
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{s},{k % 3}\n" for k, s in enumerate(stamps)))
    ds = read_recording(p, time_unit="ms")
    assert ds.attrs["sample_rate_hz"] == pytest.approx(200.0)
    assert "in ms (given)" in ds.attrs["history"]
    # epoch ms by size, but a step of 1e9 ms (11 days) per sample: not a recording vibkit can guess
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{EPOCH_S * 1000 + 10**9 * k},{k}\n" for k in range(5)), "far.csv")
    recording_error(p, lambda: read_recording(p), "Unix epoch time in ms", "pass time_unit=", line=2)


def test_non_epoch_large_times_are_not_rescaled(tmp_path):
    # an uptime clock in seconds (2e7 s, 231 days): below the epoch range, read as s and shifted as before
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{2e7 + k / 100:.2f},{k}\n" for k in range(30)))
    ds = read_recording(p)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=1e-6)
    assert "epoch times in" not in ds.attrs["history"]


# ----------------------------------------------------------------------------------------- encodings


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le", "utf-16-be", "utf-32"])
def test_utf16_and_utf32_text(tmp_path, codec):
    text = "Tiempo (s);Aceleración (g)\n" + "".join(f"{a:.3f};{k % 7}\n".replace(".", ",") for k, a in enumerate(T))
    p = write(tmp_path, text, encoding=codec)
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, np.round(T, 3), atol=1e-12)
    np.testing.assert_allclose(ds["aceleracion"].values, (np.arange(400) % 7) * 9.80665, rtol=1e-15)
    assert ds.attrs["history"].splitlines()[0].startswith("encoding UTF-")


def test_broken_utf16_is_a_clear_error(tmp_path):
    p = write(tmp_path, b"\xff\xfe" + "time,x\n0,1\n".encode("utf-16-le") + b"\x00\xd8")  # lone surrogate
    recording_error(p, lambda: read_recording(p), "UTF-16 byte-order mark", "cannot be decoded")


# ------------------------------------------------------------------------------------ files and limits


def test_fifo_is_refused_without_opening_it(tmp_path):
    fifo = tmp_path / "logger.csv"
    os.mkfifo(fifo)
    recording_error(fifo, lambda: read_recording(fifo), "named pipe (FIFO)", "not a regular file")


@pytest.mark.parametrize("dev", ["/dev/zero", "/dev/null", "/dev/urandom"])
def test_devices_are_refused(dev):
    if not os.path.exists(dev) or not stat.S_ISCHR(os.stat(dev).st_mode):
        pytest.skip(f"{dev} is not a character device here")
    recording_error(dev, lambda: read_recording(dev), "character device")


def test_symlink_to_a_device_and_a_broken_symlink(tmp_path):
    link = tmp_path / "rec.csv"
    link.symlink_to("/dev/zero")
    recording_error(link, lambda: read_recording(link), "character device")
    dangling = tmp_path / "gone.csv"
    dangling.symlink_to(tmp_path / "nowhere.csv")
    recording_error(dangling, lambda: read_recording(dangling), "cannot be read")


def test_size_limit_by_keyword_and_environment(tmp_path, monkeypatch):
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a},{a}\n" for a in T))
    size = p.stat().st_size
    monkeypatch.delenv("VIBKIT_MAX_RECORDING_BYTES", raising=False)
    assert max_recording_bytes() == DEFAULT_MAX_RECORDING_BYTES == 4 * 1024**3
    assert read_recording(p, max_bytes=size).sizes["time"] == 400
    recording_error(
        p,
        lambda: read_recording(p, max_bytes=size - 1),
        f"is {size} bytes",
        f"larger than the {size - 1} bytes limit",
        "max_bytes=",
        "VIBKIT_MAX_RECORDING_BYTES",
    )
    monkeypatch.setenv("VIBKIT_MAX_RECORDING_BYTES", str(size - 1))
    recording_error(p, lambda: read_recording(p), "limit")
    assert read_recording(p, max_bytes=size).sizes["time"] == 400  # the keyword wins
    monkeypatch.setenv("VIBKIT_MAX_RECORDING_BYTES", "4GiB")
    with pytest.raises(ValueError, match="VIBKIT_MAX_RECORDING_BYTES='4GiB'"):
        read_recording(p)
    with pytest.raises(ValueError, match="max_bytes"):
        read_recording(p, max_bytes=-5)


def test_time_column_out_of_range_names_the_file(tmp_path):
    p = write(tmp_path, "time (s),x (m)\n0,1\n1,2\n")
    recording_error(p, lambda: read_recording(p, time_column=5), "time_column=5 is out of range", line=1)


# ------------------------------------------------------------------------------------------ netCDF


def nc(tmp_path, t, x, name="r.nc", encoding=None):
    ds = xr.Dataset(
        {"x": ("time", np.asarray(x, float), {"units": "m"})},
        coords={"time": ("time", np.asarray(t, float), {"units": "s"})},
    )
    p = tmp_path / name
    ds.to_netcdf(p, engine="h5netcdf", encoding=encoding or {})
    return p


@pytest.mark.parametrize(
    "t, words",
    [
        ([0.0, 0.1, 0.1, 0.3], ["repeats the previous row", "variable 'time'", "index 2", "repair_time=True"]),
        ([0.0, 0.2, 0.1, 0.3], ["time goes backwards", "index 2"]),
        ([0.0, 0.1, np.inf, 0.3], ["not a finite number at index 2"]),
        ([0.0, 0.1, np.nan, 0.3], ["not a finite number at index 2"]),
        ([0.0, 0.1, 9.969209968386869e36, 0.3], ["not a finite number at index 2"]),
    ],
)
def test_netcdf_time_checks_as_for_text(tmp_path, t, words):
    p = nc(tmp_path, t, [1, 2, 3, 4])
    recording_error(p, lambda: read_recording(p), *words)


def test_netcdf_repair_time(tmp_path):
    p = nc(tmp_path, [0.0, 0.2, 0.1, 0.1, 0.3], [0, 2, 1, 9, 3])
    ds = read_recording(p, repair_time=True)
    np.testing.assert_array_equal(ds["time"].values, [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_array_equal(ds["x"].values, [0, 1, 2, 3])
    assert "time repaired" in ds.attrs["history"]


def test_netcdf_fill_values_become_nan_with_a_note(tmp_path):
    x = np.array([1.0, 9.969209968386869e36, 3.0, -999.0, 5.0])
    p = nc(tmp_path, np.arange(5) * 0.1, x)
    ds = read_recording(p)
    np.testing.assert_array_equal(np.isnan(ds["x"].values), [False, True, False, False, False])
    note = "variable 'x': 1 value(s) equal to netCDF's default fill value 9.96921e+36 read as NaN"
    assert note in ds.attrs["history"]
    p = nc(tmp_path, np.arange(5) * 0.1, x, "fill.nc", encoding={"x": {"_FillValue": -999.0}})
    ds = read_recording(p)
    np.testing.assert_array_equal(np.isnan(ds["x"].values), [False, True, False, True, False])
    assert "(_FillValue/missing_value -999) read as NaN" in ds.attrs["history"]


# ------------------------------------------------------------------------------ clock jumps (repair_time)


def hms(s):
    s %= 86400
    return f"{int(s // 3600):02d}:{int(s // 60 % 60):02d}:{s % 60:06.3f}"


def test_midnight_crossing_refused_then_unwrapped(tmp_path):
    t = 86400 - 1.0 + np.arange(400) / FS  # 23:59:59.000 for 2 s
    p = write(tmp_path, "time,x (m)\n" + "".join(f"{hms(a)},{k}\n" for k, a in enumerate(t)))
    recording_error(
        p, lambda: read_recording(p), "time goes backwards", "crossing midnight", "repair_time=True", line=202
    )
    ds = read_recording(p, repair_time=True)
    np.testing.assert_allclose(ds["time"].values, np.arange(400) / FS, atol=1e-9)  # order kept, nothing sorted
    np.testing.assert_array_equal(ds["x"].values, np.arange(400))
    assert "the clock went back by 86400 s at line 202 (crossing midnight)" in ds.attrs["history"]


def test_dst_fall_back_unwrapped_and_other_backward_steps_sorted(tmp_path):
    t = np.arange(400) / FS
    local = np.where(t < 1.0, 3599.0 + t, t - 1.0)  # 00:59:59 ... then back to 00:00:00
    p = write(tmp_path, "time (s),x (m)\n" + "".join(f"{a:.3f},{k}\n" for k, a in enumerate(local)))
    ds = read_recording(p, repair_time=True)
    np.testing.assert_allclose(ds["time"].values, 3599.0 + t, atol=1e-9)  # stamps as found, jump undone
    assert "(set back by an hour (daylight saving))" in ds.attrs["history"]
    # a plain swap of two rows is no clock jump: sorted as before
    p = write(tmp_path, "time (s),x (m)\n0,0\n0.2,2\n0.1,1\n0.3,3\n", "swap.csv")
    ds = read_recording(p, repair_time=True)
    np.testing.assert_array_equal(ds["x"].values, [0, 1, 2, 3])
    assert "backward step(s)" in ds.attrs["history"] and "clock went back" not in ds.attrs["history"]
