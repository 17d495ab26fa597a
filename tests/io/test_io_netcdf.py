"""vibkit results on disk: atomic netCDF4/HDF5 write, exact round trip, provenance on read."""

import json
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
        write_result(bad, p, overwrite=True)
    bad = sim_like()
    bad["delta"].attrs["meta"] = {"a": 1}
    with pytest.raises(ValueError, match="attr 'meta' of variable 'delta'"):
        write_result(bad, p, overwrite=True)
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


def test_a_component_of_a_variable_is_a_channel(tmp_path, capsys):
    """``link_tension[2]`` (or ``roller_acceleration[59, z]``) names one component of a result's variable
    along time and other dimensions: what `vibkit spectrum --channel` analyses."""
    from vibkit.cli import main
    from vibkit.io.channels import resolve_channel, with_component

    path = tmp_path / "sim.nc"
    t = np.arange(4000) / 200.0
    ds = xr.Dataset(
        {
            "delta": ("time", 1e-5 * np.sin(2 * np.pi * 3.75 * t), {"units": "m"}),
            "roller_acceleration": (
                ("time", "roller", "axis"),
                np.stack(
                    [
                        np.stack([0.1 * np.sin(2 * np.pi * 3.75 * t), 0.2 * np.sin(2 * np.pi * 4.1 * t)], axis=-1),
                        np.zeros((t.size, 2)),
                    ],
                    axis=1,
                ),
                {"units": "m/s^2"},
            ),
        },
        coords={"time": t, "roller": [59, 60], "axis": ["x", "z"]},
    )
    write_result(ds, path)
    rec = with_component(read_recording(path), "roller_acceleration[59, z]")
    assert resolve_channel(rec, "roller_acceleration[59, z]") == "roller_acceleration[59, z]"
    assert np.array_equal(rec["roller_acceleration[59, z]"].values, ds.roller_acceleration.values[:, 0, 1])
    assert rec["roller_acceleration[59, z]"].attrs["units"] == "m/s^2"
    with pytest.raises(ValueError, match=r"has no roller '61' \(roller: 59, 60\)"):
        with_component(rec, "roller_acceleration[61, z]")
    with pytest.raises(ValueError, match="components: roller_acceleration\\[roller, axis\\]"):
        resolve_channel(read_recording(path), "roller_acceleration")
    # the command line: the 4.1 Hz line of roller 59's z axis, not the 3.75 Hz of its x axis
    assert main(["spectrum", str(path), "--channel", "roller_acceleration[59, z]", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["channel"] == "roller_acceleration[59, z]"
    assert out["fundamental_hz"] == pytest.approx(4.1, abs=0.01)


def test_an_existing_file_is_not_replaced_unless_told(tmp_path):
    """A stranger's `write_result(r, "precious.nc")` replaced their file silently (the default was to overwrite),
    where the docs promise vibkit never replaces a file unless told, as `vibkit simulate` and `write_report` do."""
    p = tmp_path / "precious.nc"
    p.write_text("precious data")
    with pytest.raises(ValueError, match="already exists"):
        write_result(sim_like(), p)
    assert p.read_text() == "precious data"
    write_result(sim_like(), p, overwrite=True)
    assert p.read_bytes()[:8] == b"\x89HDF\r\n\x1a\n"
