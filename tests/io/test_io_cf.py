"""What vibkit writes follows CF-1.10: ``Conventions``, a ``time`` in seconds since a stated epoch that
xarray decodes to the right instants, ``units`` and ``long_name`` on every variable; vibkit reads it back
as it wrote it (``time`` in s, the epoch as ``start_time``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

import vibkit
from vibkit.io import write_result
from vibkit.io.netcdf import UNKNOWN_EPOCH

ROOT = Path(__file__).resolve().parents[2]
ENDAQ = ROOT / "data" / "field" / "layouts" / "endaq.csv"  # states its start time: 2021-06-15T10:21:03
GCDC = ROOT / "data" / "field" / "layouts" / "gcdc-x16.csv"  # header 'Start time 2019-03-12, 10:25:14.000'


def _written(ds, tmp_path):
    return write_result(ds, tmp_path / "out.nc")


def test_recording_time_decodes_to_its_instants(tmp_path):
    rec = vibkit.read_recording(ENDAQ)
    path = _written(rec, tmp_path)
    with xr.open_dataset(path, engine="h5netcdf") as cf:  # decode_times=True: CF's reading
        assert cf.attrs["Conventions"] == "CF-1.10"
        assert cf["time"].attrs["standard_name"] == "time"
        assert cf["time"].encoding["units"] == "seconds since 2021-06-15T10:21:03"
        expected = pd.Timestamp("2021-06-15T10:21:03") + pd.to_timedelta(rec["time"].values, unit="s")
        got = pd.DatetimeIndex(cf["time"].values)
        assert np.max(np.abs((got - expected).total_seconds())) < 1e-6  # to the microsecond
        for name, var in cf.variables.items():
            assert "long_name" in var.attrs, name
            if name not in ("time", "segment"):
                assert "units" in var.attrs, name


def test_header_start_time_with_a_comma_is_the_epoch(tmp_path):
    rec = vibkit.read_recording(GCDC)
    with xr.open_dataset(_written(rec, tmp_path), engine="h5netcdf") as cf:
        assert cf["time"].encoding["units"] == "seconds since 2019-03-12T10:25:14"
        t0 = pd.Timestamp("2019-03-12T10:25:14") + pd.to_timedelta(float(rec["time"][0]), unit="s")
        assert abs((pd.Timestamp(cf["time"].values[0]) - t0).total_seconds()) < 1e-6


def test_utc_start_time_written_in_utc(tmp_path):
    ds = xr.Dataset(
        {"a": ("time", np.zeros(4), {"units": "m/s^2"})},
        coords={"time": ("time", np.arange(4) * 0.5, {"units": "s"})},
        attrs={"start_time": "2024-03-31T03:30:00+02:00"},
    )
    with xr.open_dataset(_written(ds, tmp_path), engine="h5netcdf") as cf:
        assert cf["time"].encoding["units"] == "seconds since 2024-03-31T01:30:00Z"
        assert pd.Timestamp(cf["time"].values[3]) == pd.Timestamp("2024-03-31T01:30:01.5")


def test_no_start_time_states_the_stand_in_epoch(tmp_path):
    ds = xr.Dataset({"a": ("time", np.ones(3))}, coords={"time": ("time", np.array([0.0, 0.25, 0.5]), {"units": "s"})})
    path = _written(ds, tmp_path)
    with xr.open_dataset(path, engine="h5netcdf", decode_times=False) as raw:
        assert raw["time"].attrs["units"] == f"seconds since {UNKNOWN_EPOCH}"
        assert "states no date" in raw["time"].attrs["comment"]
        assert raw["a"].attrs == {"long_name": "a", "units": "1"}
    back = vibkit.read_recording(path)  # vibkit's reader: time in s as written, no invented start time
    assert back["time"].attrs["units"] == "s" and "start_time" not in back.attrs
    np.testing.assert_array_equal(back["time"].values, ds["time"].values)
    assert "comment" not in back["time"].attrs


def test_vibkit_reads_back_what_it_wrote(tmp_path):
    rec = vibkit.read_recording(ENDAQ)
    back = vibkit.read_recording(_written(rec, tmp_path))
    assert back["time"].attrs["units"] == "s"
    assert back.attrs["start_time"] == rec.attrs["start_time"]
    np.testing.assert_array_equal(back["time"].values, rec["time"].values)
    for name in rec.data_vars:
        np.testing.assert_array_equal(back[name].values, rec[name].values)
        assert back[name].attrs["units"] == rec[name].attrs["units"]
    assert back.attrs["Conventions"] == "CF-1.10"
