"""vibkit results on disk: atomic netCDF4/HDF5 write, exact round trip, provenance on read."""

import os

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.io import RecordingError, read_recording, write_result


def sim_like():
    t = np.arange(100) / 1000.0
    link = np.arange(3)
    return xr.Dataset(
        {
            "delta": (
                "time",
                0.037 + 1e-5 * np.sin(2 * np.pi * 3.75 * t),
                {"units": "m", "long_name": "tensioner displacement"},
            ),
            "link_tension": (
                ("time", "link"),
                np.outer(1 + t, 1000.0 + link),
                {"units": "N", "long_name": "link tension"},
            ),
        },
        coords={
            "time": ("time", t, {"units": "s", "long_name": "time"}),
            "link": ("link", link, {"long_name": "link"}),
        },
        attrs={
            "link_pitch_m": 0.1333,
            "chain_speed_m_s": 0.5,
            "sprocket_teeth": 28,
            "scene": "[chain]\npitch = 0.1333\n",
            "vibkit_version": vibkit.__version__,
        },
    )


def test_simulation_result_round_trip(tmp_path):
    ds = sim_like()
    p = write_result(ds, tmp_path / "result.nc")
    back = read_recording(p)
    xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())
    for k, v in ds.attrs.items():
        assert back.attrs[k] == v
    assert isinstance(back.attrs["sprocket_teeth"], (int, np.integer)) and back.attrs["sprocket_teeth"] == 28
    assert back.attrs["reader"] == "vibkit.io.netcdf" and back.attrs["source_file"] == "result.nc"
    assert back.attrs["sample_rate_hz"] == pytest.approx(1000.0)
    assert not [f for f in os.listdir(tmp_path) if f != "result.nc"]  # no temp file left


def test_recording_round_trip_keeps_values_segments_and_history(tmp_path):
    src = tmp_path / "rec.csv"
    t = np.r_[np.arange(20), 100 + np.arange(20)] / 100.0
    src.write_text("# Site: Leon\ntime (s),x (mm)\n" + "".join(f"{a:.2f},{a * 3:.3f}\n" for a in t))
    rec = read_recording(src)
    back = read_recording(write_result(rec, tmp_path / "rec.nc"))
    xr.testing.assert_identical(back[["x", "segment"]].drop_attrs(), rec[["x", "segment"]].drop_attrs())
    assert back["segment"].dtype == np.int32
    assert back.attrs["site"] == "Leon"
    assert back.attrs["original_source_file"] == "rec.csv" and back.attrs["original_sha256"] == rec.attrs["sha256"]
    assert back.attrs["history"].startswith(rec.attrs["history"])


def test_channel_selection(tmp_path):
    p = write_result(sim_like(), tmp_path / "r.nc")
    assert list(read_recording(p, channel="delta").data_vars) == ["delta"]
    with pytest.raises(RecordingError, match="no variable 'speed'"):
        read_recording(p, channel="speed")


def test_overwrite_is_atomic_and_a_failed_write_leaves_the_old_file(tmp_path):
    p = tmp_path / "r.nc"
    write_result(sim_like(), p)
    before = p.read_bytes()
    bad = sim_like()
    bad.attrs["flag"] = True
    with pytest.raises(ValueError, match="attr 'flag' of the dataset"):
        write_result(bad, p)
    bad = sim_like()
    bad["delta"].attrs["meta"] = {"a": 1}
    with pytest.raises(ValueError, match="attr 'meta' of variable 'delta'"):
        write_result(bad, p)
    assert p.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["r.nc"]


def test_write_into_a_missing_folder(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        write_result(sim_like(), tmp_path / "nope" / "r.nc")


def test_hdf5_that_is_not_netcdf(tmp_path):
    h5py = pytest.importorskip("h5py")
    p = tmp_path / "plain.h5"
    with h5py.File(p, "w") as f:
        f.create_group("a").create_group("b")
    with pytest.raises(RecordingError, match="plain.h5: "):
        read_recording(p)
