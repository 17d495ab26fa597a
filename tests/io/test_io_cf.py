"""What vibkit writes follows CF-1.10 and other tools read it as written: ``Conventions``, ``time`` in
seconds (``units = "s"``, float) from the start, never dates from a stand-in epoch, whatever opens it
(plain ``xarray.open_dataset``, h5py, ``ncdump`` where installed); a recording's start instant is the
global attribute ``start_time``; ``units`` and ``long_name`` on every variable.  vibkit reads back
files of this version and of the earlier one (``time`` in ``seconds since`` an epoch) the same."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.io import write_result
from vibkit.io.netcdf import UNKNOWN_EPOCH, cf_attrs

h5py = pytest.importorskip("h5py")

ROOT = Path(__file__).resolve().parents[2]
ENDAQ = ROOT / "data" / "field" / "layouts" / "endaq.csv"  # states its start time: 2021-06-15T10:21:03
GCDC = ROOT / "data" / "field" / "layouts" / "gcdc-x16.csv"  # header 'Start time 2019-03-12, 10:25:14.000'


def _sim_like():
    t = np.arange(200) / 1000.0
    return xr.Dataset(
        {
            "delta": ("time", 1e-5 * np.sin(2 * np.pi * 3.75 * t), {"units": "m", "long_name": "tensioner"}),
            "link_tension": (("time", "link"), np.outer(1 + t, [1000.0, 1001.0]), {"units": "N"}),
        },
        coords={"time": ("time", t, {"units": "s", "long_name": "time"}), "link": ("link", [0, 1])},
        attrs={"scene": "[chain]\npitch = 0.1333\n"},
    )


def _check_seconds(path, expected):
    """``time`` in float seconds as plain xarray, h5py and (where installed) ncdump see it."""
    with xr.open_dataset(path) as plain:  # every default: decode_times=True, decode_timedelta
        assert plain["time"].dtype == np.float64, plain["time"].dtype
        assert plain["time"].attrs["units"] == "s"
        np.testing.assert_array_equal(plain["time"].values, expected)
        assert plain.attrs["Conventions"] == "CF-1.10"
        assert plain["time"].attrs["standard_name"] == "time" and plain["time"].attrs["axis"] == "T"
        for name, var in plain.variables.items():
            assert "long_name" in var.attrs, name
            if name not in ("time", "segment") and var.dtype.kind in "iuf":
                assert "units" in var.attrs, name
    with h5py.File(path, "r") as f:
        units = f["time"].attrs["units"]
        assert (units.decode() if isinstance(units, bytes) else units) == "s"
        assert "_FillValue" not in f["time"].attrs  # a coordinate has no missing values
        np.testing.assert_array_equal(f["time"][()], expected)
    if shutil.which("ncdump"):
        head = subprocess.run(["ncdump", "-h", str(path)], capture_output=True, text=True, check=True).stdout
        assert 'time:units = "s"' in head


def test_simulation_result_opens_in_seconds(tmp_path):
    ds = _sim_like()
    for suffix in (".nc", ".h5"):
        path = write_result(ds, tmp_path / f"sim{suffix}")
        _check_seconds(path, ds["time"].values)
        with xr.open_dataset(path) as plain:
            assert "since" not in str(plain["time"].attrs) and "1970" not in str(plain["time"].attrs)


def test_a_real_simulation_opens_in_seconds(tmp_path):
    ds = vibkit.simulate(vibkit.load_scene(ROOT / "sim" / "leon.toml"), duration=0.5, progress=False)
    path = write_result(ds, tmp_path / "leon.nc")
    _check_seconds(path, ds["time"].values)
    back = vibkit.read_recording(path)
    np.testing.assert_array_equal(back["time"].values, ds["time"].values)
    assert "start_time" not in back.attrs  # a simulation has no date, and none is invented


def test_recording_keeps_its_start_as_an_attribute(tmp_path):
    rec = vibkit.read_recording(ENDAQ)
    path = write_result(rec, tmp_path / "rec.nc")
    _check_seconds(path, rec["time"].values)
    with xr.open_dataset(path) as plain:
        assert plain.attrs["start_time"] == rec.attrs["start_time"]
        assert rec.attrs["start_time"].startswith("2021-06-15T10:21:03")
        assert "2021-06-15T10:21:03" in plain["time"].attrs["comment"]


def test_header_start_time_with_a_comma(tmp_path):
    rec = vibkit.read_recording(GCDC)
    path = write_result(rec, tmp_path / "gcdc.nc")
    _check_seconds(path, rec["time"].values)
    assert vibkit.read_recording(path).attrs["start_time"] == rec.attrs["start_time"]


def test_vibkit_reads_back_what_it_wrote(tmp_path):
    rec = vibkit.read_recording(ENDAQ)
    back = vibkit.read_recording(write_result(rec, tmp_path / "out.nc"))
    assert back["time"].attrs == {k: v for k, v in rec["time"].attrs.items() if k != "standard_name"}
    assert back["time"].attrs["units"] == "s"
    assert back.attrs["start_time"] == rec.attrs["start_time"]
    np.testing.assert_array_equal(back["time"].values, rec["time"].values)
    for name in rec.data_vars:
        np.testing.assert_array_equal(back[name].values, rec[name].values)
        assert back[name].attrs["units"] == rec[name].attrs["units"]
    assert back.attrs["Conventions"] == "CF-1.10"


def _earlier(ds, path, epoch, comment):
    """A file as the earlier version wrote it: ``time`` in ``seconds since EPOCH``."""
    out = cf_attrs(ds.copy(deep=True))  # long_name, units and Conventions as both versions write them
    out["time"].attrs.update(
        units=f"seconds since {epoch}", standard_name="time", calendar="proleptic_gregorian", axis="T", comment=comment
    )
    out.to_netcdf(path, engine="h5netcdf")
    return path


@pytest.mark.parametrize("start", [None, "2021-06-15T10:21:03"])
def test_earlier_files_read_as_new_ones(tmp_path, start):
    ds = _sim_like()
    if start:
        ds.attrs["start_time"] = start
    comment = (
        f"seconds from the recording's start time {start}"
        if start
        else f"t = 0 is the start of the simulation or recording, which states no date (or none in ISO 8601): "
        f"the epoch {UNKNOWN_EPOCH} stands for it"
    )
    old = vibkit.read_recording(_earlier(ds, tmp_path / "old.nc", start or UNKNOWN_EPOCH, comment))
    new = vibkit.read_recording(write_result(ds, tmp_path / "new.nc"))
    assert old["time"].attrs == new["time"].attrs == {"units": "s", "long_name": "time"}
    np.testing.assert_array_equal(old["time"].values, new["time"].values)
    assert old.attrs.get("start_time") == new.attrs.get("start_time") == start
    for name in ds.data_vars:
        assert old[name].identical(new[name])
