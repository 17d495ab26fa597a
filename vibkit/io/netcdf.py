"""vibkit's own results on disk: netCDF4/HDF5 through h5netcdf (built on h5py).

``write_result`` writes any vibkit Dataset (simulation result or recording)
atomically: to a temporary file in the target's folder, then ``os.replace``,
so a reader never sees half a file.  ``read_netcdf`` opens one back, loads it
into memory and adds the provenance attrs of a recording.

What is written follows the CF conventions (``Conventions = "CF-1.10"``, see :func:`cf_attrs`):
``time`` is in seconds (``units = "s"``) from the start of the simulation or recording, so that
``xarray.open_dataset`` and every other netCDF/HDF5 tool read float seconds, never dates from a
stand-in epoch; a recording's start instant is the global attribute ``start_time`` (ISO 8601).  Every
variable has ``units`` and ``long_name``.  Files written before (``time`` in ``seconds since`` an
epoch) are read the same.
"""

from __future__ import annotations

import os
import re
import warnings
from datetime import datetime, timezone

import numpy as np
import xarray as xr

from ..runtime.safe_output import check_output_path, write_bytes
from .errors import RecordingError
from .recording import sha256_of
from .timebase import check_order

__all__ = ["read_netcdf", "write_result", "cf_attrs", "CONVENTIONS", "UNKNOWN_EPOCH"]

#: the CF version the written files follow
CONVENTIONS = "CF-1.10"
#: the epoch that earlier files wrote for a t = 0 without a date (a simulation, a recording that states no
#: start time); read back as no start time
UNKNOWN_EPOCH = "1970-01-01T00:00:00Z"
_SINCE = re.compile(r"^\s*(?:s|sec|secs|second|seconds)\s+since\s+(\S.*?)\s*$", re.IGNORECASE)

_ATTR_TYPES = (str, int, float, np.integer, np.floating)
#: netCDF's default fill value of float and double variables (NC_FILL_FLOAT/NC_FILL_DOUBLE), written by
#: loggers and netCDF libraries where no value was stored
NC_DEFAULT_FILL = 9.969209968386869e36


def _check_attrs(where: str, attrs: dict) -> None:
    for key, value in attrs.items():
        if isinstance(value, (bool, np.bool_)) or value is None:
            raise ValueError(
                f"attr {key!r} of {where} is {value!r}; netCDF attrs must be strings or numbers (write booleans as 0/1)"
            )
        if isinstance(value, _ATTR_TYPES):
            continue
        if isinstance(value, (list, tuple, np.ndarray)):
            arr = np.asarray(value)
            if arr.ndim == 1 and (arr.dtype.kind in "iuf" or arr.dtype.kind == "U"):
                continue
        raise ValueError(
            f"attr {key!r} of {where} has type {type(value).__name__}; netCDF attrs must be "
            "strings, numbers or 1-D arrays of them"
        )


def _epoch(start) -> str | None:
    """``start`` (ISO 8601, as the readers state a start time) as the epoch of a CF time unit, else None."""
    try:
        t = datetime.fromisoformat(str(start).strip().replace(", ", "T").replace("Z", "+00:00"))
    except ValueError:
        return None
    if t.tzinfo is not None:
        t = t.astimezone(timezone.utc).replace(tzinfo=None)
        return t.isoformat() + "Z"
    return t.isoformat()  # local time of the logger, as the file states it


def cf_attrs(ds: xr.Dataset) -> xr.Dataset:
    """A shallow copy of ``ds`` with the CF-1.10 attributes that :func:`write_result` writes.

    * ``Conventions = "CF-1.10"``;
    * a ``time`` coordinate in seconds keeps ``units = "s"`` (a duration from t = 0, which every tool
      reads as float seconds) and gets ``standard_name = "time"``, ``axis = "T"`` and a ``comment``
      saying what t = 0 is: the recording's ``start_time`` (a global attribute, ISO 8601), else the
      start of the simulation or recording, which states no date;
    * every variable gets ``long_name`` (its name where it has none) and ``units`` (``"1"``).
    """
    out = ds.copy(deep=False)
    out.attrs["Conventions"] = CONVENTIONS
    for name, var in out.variables.items():
        var.attrs.setdefault("long_name", str(name))
        if var.dtype.kind in "iuf" and name != "segment":
            var.attrs.setdefault("units", "1")
    if "time" in out.coords and out["time"].dtype.kind in "iuf" and out["time"].attrs.get("units", "s") == "s":
        epoch = _epoch(ds.attrs["start_time"]) if "start_time" in ds.attrs else None
        comment = (
            f"{_FROM_START} {ds.attrs['start_time']} (global attribute start_time)"
            if epoch
            else f"{_NO_DATE}, which states no date (or none in ISO 8601)"
        )
        attrs = out.variables["time"].attrs
        attrs.update(units="s", standard_name="time", axis="T")
        attrs.setdefault("comment", comment)
        out["time"].encoding["_FillValue"] = None  # a coordinate has no missing values (CF 5): no fill value
    return out


_FROM_START = "seconds from the recording's start time"
_NO_DATE = "seconds from the start of the simulation or recording"


def _from_cf_time(ds: xr.Dataset, history: list) -> None:
    """Undo :func:`cf_attrs` on ``time`` in place (``units`` ``s``), for files of both kinds.

    Files written before this version count ``seconds since`` an epoch: ``units`` back to ``s``, the
    epoch (unless it is :data:`UNKNOWN_EPOCH`) kept as ``start_time``.
    """
    if "time" not in ds.coords:
        return
    attrs = ds["time"].attrs
    m = _SINCE.match(str(attrs.get("units", "")))
    if m:
        epoch = m.group(1)
        attrs["units"] = "s"
        for key in ("standard_name", "calendar", "axis"):
            attrs.pop(key, None)
        if epoch != UNKNOWN_EPOCH and "start_time" not in ds.attrs:
            ds.attrs["start_time"] = epoch
            history.append(f"time in seconds since {epoch} (the start time)")
    elif attrs.get("units") == "s" and attrs.get("axis") == "T":
        for key in ("standard_name", "axis"):
            attrs.pop(key, None)
    else:
        return
    comment = str(attrs.get("comment", ""))
    if "stands for it" in comment or comment.startswith(("seconds from", _NO_DATE)):
        attrs.pop("comment")


def write_result(ds: xr.Dataset, path, *, overwrite: bool = False, inputs=()) -> str:
    """Write a Dataset to netCDF4/HDF5, atomically (see :mod:`vibkit.runtime.safe_output`).

    The file is built in memory and then written to a temporary file in the target's folder,
    flushed and renamed, so a reader never sees half a file, a full disk leaves nothing behind and
    no HDF5 handle is left open on a failed write.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation result or a recording; attrs must be strings or numbers.
    path : str or os.PathLike
        Target file (conventionally ``*.nc``). Its folder must exist.
    overwrite : bool
        Replace an existing regular file (default False: an existing file is an error, as ``vibkit simulate``
        refuses it without ``--force`` and :func:`vibkit.write_report` without ``overwrite=True``).
        Folders, devices, FIFOs and symbolic links are never written through or replaced.
    inputs : iterable of paths
        Files that must not be replaced (the command's inputs).

    Returns
    -------
    str
        The path written.

    Raises
    ------
    ValueError
        An attr that netCDF cannot store (named), a missing folder, or an unsafe target
        (:class:`vibkit.runtime.safe_output.OutputError`).
    OSError
        The write failed (disk full ...); nothing is left behind.
    """
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"ds must be an xarray.Dataset, got {type(ds).__name__}")
    path = os.fspath(path)
    check_output_path(path, overwrite=overwrite, inputs=inputs)
    _check_attrs("the dataset", ds.attrs)
    for name, var in ds.variables.items():
        _check_attrs(f"variable {name!r}", var.attrs)
    data = cf_attrs(ds).to_netcdf(engine="h5netcdf")  # in memory: the HDF5 library never holds a file of ours
    write_bytes(data, path, overwrite=overwrite, inputs=inputs)
    return path


def _mask_fill_values(ds, history):
    """Turn fill values into NaN, in place, and say how many per variable."""
    for name in list(ds.variables):
        var = ds[name]
        if var.dtype.kind != "f" or name == "time":
            continue
        declared = [var.encoding.get(k) for k in ("_FillValue", "missing_value") if var.encoding.get(k) is not None]
        vals = var.values
        nan_before = int(np.count_nonzero(np.isnan(vals)))
        default = np.isclose(np.abs(vals), NC_DEFAULT_FILL, rtol=1e-6, atol=0)
        ndef = int(np.count_nonzero(default))
        if ndef:
            vals = np.where(default, np.nan, vals)
            ds[name] = var.copy(data=vals)
            history.append(
                f"variable '{name}': {ndef} value(s) equal to netCDF's default fill value "
                f"{NC_DEFAULT_FILL:.6g} read as NaN (missing)"
            )
        if declared and nan_before:
            fills = ", ".join(f"{float(np.ravel(v)[0]):.6g}" for v in declared)
            history.append(
                f"variable '{name}': {nan_before} fill value(s) (_FillValue/missing_value {fills}) "
                "read as NaN (missing)"
            )


def _check_time(path, ds, repair, history):
    """The time coordinate's checks of the text reader: finite, increasing, no repeats (or repaired)."""
    t = ds["time"]
    if t.ndim != 1 or t.size < 2:
        return ds
    if t.dtype.kind not in "iuf":
        raise RecordingError(path, None, f"coordinate 'time' has type {t.dtype}; expected numbers of seconds")
    tv = np.asarray(t.values, dtype=float)
    tv = np.where(np.isclose(np.abs(tv), NC_DEFAULT_FILL, rtol=1e-6, atol=0), np.nan, tv)
    bad = np.flatnonzero(~np.isfinite(tv))
    if bad.size:
        raise RecordingError(
            path,
            None,
            f"time in variable 'time' is not a finite number at index {bad[0]} "
            f"({tv.size} samples; {bad.size} such); expected seconds",
        )
    try:
        keep, notes, tv = check_order(tv, None, path=path, column="time", repair=repair)
    except RecordingError as err:
        dt = np.diff(tv)
        i = int(np.flatnonzero(dt <= 0)[0]) + 1
        msg = err.message.replace("in column 'time'", "in variable 'time'")
        raise RecordingError(path, None, f"{msg} (at index {i})") from None
    history += notes
    if repair and not np.array_equal(tv, np.asarray(t.values, dtype=float)):  # clock jumps undone
        ds = ds.assign_coords(time=("time", tv, dict(t.attrs)))
    if keep.size != tv.size or np.any(keep != np.arange(tv.size)):
        ds = ds.isel(time=keep)
    return ds


def read_netcdf(path, data: bytes, *, channel=None, repair_time=False) -> xr.Dataset:
    """Read a netCDF4/HDF5 file (e.g. one written by :func:`write_result`).

    Parameters
    ----------
    path : str or os.PathLike
    data : bytes
        The file's bytes (for the sha256).
    channel : str or list of str, optional
        Keep only these data variables (plus ``segment``).
    repair_time : bool
        As in :func:`vibkit.io.read_recording`: time going backwards or
        repeated stamps are errors unless True (sorted, repeats dropped).

    Returns
    -------
    xarray.Dataset
        In memory, with ``source_file``, ``sha256``, ``reader``, ``history``
        and ``sample_rate_hz`` (when it has a ``time`` coordinate) set.

    Raises
    ------
    RecordingError
        The file is not netCDF/HDF5 that xarray can read, lacks the channel, or
        its time is not finite, goes backwards or repeats (``repair_time=False``).
    """
    is_hdf5 = data[:8] == b"\x89HDF\r\n\x1a\n"
    engine = "h5netcdf" if is_hdf5 else "scipy"
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with xr.open_dataset(path, engine=engine, decode_times=False, decode_timedelta=False) as f:
                ds = f.load()
    except Exception as exc:  # any failure of the backend means: not a readable netCDF file
        kind = "netCDF4/HDF5" if is_hdf5 else "netCDF"
        raise RecordingError(path, None, f"cannot read as {kind}: {type(exc).__name__}: {exc}") from None
    prior = str(ds.attrs.get("history", ""))
    history = [f"read with xarray ({engine}); {len(ds.data_vars)} variable(s)"]
    history += [f"backend warning: {w.message}" for w in caught]
    _mask_fill_values(ds, history)
    _from_cf_time(ds, history)
    if "time" in ds.coords:
        ds = _check_time(path, ds, repair_time, history)
    if channel is not None:
        wanted = [channel] if isinstance(channel, str) else list(channel)
        missing = [w for w in wanted if w not in ds.data_vars]
        if missing:
            raise RecordingError(
                path, None, f"no variable {missing[0]!r}; variables: " + ", ".join(repr(str(v)) for v in ds.data_vars)
            )
        keep = list(dict.fromkeys(wanted + (["segment"] if "segment" in ds.data_vars else [])))
        ds = ds[keep]
        history.append("kept variable(s) " + ", ".join(repr(w) for w in wanted))
    if not ds.data_vars:
        raise RecordingError(path, None, "holds no data variables")
    rate = ds.attrs.get("sample_rate_hz")
    if "time" in ds.coords and ds["time"].size > 1 and rate is None:
        t = np.asarray(ds["time"].values, dtype=float)
        dt = np.diff(t)
        if np.all(np.isfinite(dt)) and np.all(dt > 0):
            rate = float(1.0 / np.median(dt))
            history.append(f"sample rate {rate:.6g} Hz from the median time step")
    attrs = dict(ds.attrs)
    if "source_file" in attrs and attrs["source_file"] != os.path.basename(os.fspath(path)):
        attrs["original_source_file"] = attrs["source_file"]
        attrs["original_sha256"] = attrs.get("sha256", "")
    attrs["source_file"] = os.path.basename(os.fspath(path))
    attrs["sha256"] = sha256_of(data)
    attrs["reader"] = "vibkit.io.netcdf"
    if rate is not None:
        attrs["sample_rate_hz"] = float(rate)
    attrs["history"] = "\n".join(([prior] if prior else []) + history)
    ds.attrs = attrs
    return ds
