"""Plain HDF5 files written by h5py: datasets of samples with a sample_rate (or fs) attribute.

Known sines in known units; vibkit's own netCDF-4 files (HDF5 too) still go to the netCDF reader.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from vibkit.io import RecordingError, read_recording, write_result
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

h5py = pytest.importorskip("h5py")

FS = 1000.0
T = np.arange(2000) / FS
X = np.sin(2 * np.pi * 12.5 * T)


def test_one_dataset_with_a_sample_rate_attribute(tmp_path):
    p = tmp_path / "logger.h5"
    with h5py.File(p, "w") as f:
        d = f.create_dataset("acc", data=X.astype(np.float32))
        d.attrs["sample_rate"] = FS
        d.attrs["units"] = "g"
    assert detect_format(p, p.read_bytes()).name == "hdf5"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.hdf5" and list(ds.data_vars) == ["acc"]
    assert ds.attrs["sample_rate_hz"] == FS and ds.sizes["time"] == T.size
    np.testing.assert_allclose(ds["time"].values, T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds["acc"].values, X.astype(np.float32).astype(np.float64) * STANDARD_GRAVITY, rtol=1e-12)
    assert ds["acc"].attrs["units"] == "m/s^2"


def test_several_datasets_in_a_group_with_fs_on_the_file(tmp_path):
    p = tmp_path / "run.hdf5"
    with h5py.File(p, "w") as f:
        f.attrs["fs"] = FS
        g = f.create_group("run1")
        g.create_dataset("x", data=X).attrs["units"] = "mm"
        g.create_dataset("xyz", data=np.column_stack([X, 2 * X, 3 * X]))  # samples x channels
    ds = read_recording(p)
    assert list(ds.data_vars) == ["run1_x", "run1_xyz_1", "run1_xyz_2", "run1_xyz_3"]
    np.testing.assert_allclose(ds["run1_x"].values, X * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(ds["run1_xyz_3"].values, 3 * X, rtol=1e-12)
    assert ds["run1_xyz_1"].attrs["units"] == "unknown"  # no units attribute: said, not guessed
    assert "no unit in the file" in ds.attrs["history"]
    one = read_recording(p, channel="run1/x")
    assert list(one.data_vars) == ["run1_x"]


def test_a_time_dataset_gives_the_time_base(tmp_path):
    p = tmp_path / "t.h5"
    with h5py.File(p, "w") as f:
        f.create_dataset("time", data=T + 5.0)
        f.create_dataset("v", data=X).attrs["units"] = np.bytes_("m/s")
    ds = read_recording(p)
    np.testing.assert_allclose(ds["time"].values, T + 5.0, rtol=0, atol=1e-12)
    assert ds["v"].attrs["quantity"] == "velocity"


def test_no_rate_is_an_error_naming_the_file_and_what_was_expected(tmp_path):
    p = tmp_path / "norate.h5"
    with h5py.File(p, "w") as f:
        f.create_dataset("acc", data=X)
    with pytest.raises(RecordingError, match=r"norate\.h5: no time base: expected .*sample rate.*datasets \(acc\)"):
        read_recording(p)


def test_vibkit_netcdf_still_read_as_netcdf(tmp_path):
    p = tmp_path / "r.h5"
    write_result(xr.Dataset({"a": ("time", X, {"units": "m"})}, coords={"time": ("time", T, {"units": "s"})}), p)
    assert detect_format(p, p.read_bytes()).name == "netcdf"
    assert read_recording(p).attrs["reader"] == "vibkit.io.netcdf"
    assert read_recording(p, format="hdf5").attrs["reader"] == "vibkit.io.netcdf"  # handed on by the HDF5 reader
