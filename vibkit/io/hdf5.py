"""Plain HDF5 files (not netCDF): datasets of samples with a rate attribute, read by h5py.

A logger or a script writes its samples to HDF5 as one dataset per channel (``/acc_x``), one
matrix of channels (``/data``, samples x channels or channels x samples), or in groups
(``/run1/acc``).  What makes them a recording (see :func:`vibkit.io.sampled.pick_arrays`):

* the time base: a dataset ``time``/``t`` [s], or a sample rate [Hz] as an attribute
  ``sample_rate``, ``fs``, ``sampling_rate`` ... of a dataset, of its group or of the file (or a
  scalar dataset of that name), or a period ``dt`` [s];
* the channels: every numeric 1-D or 2-D dataset as long as the time base;
* the units: each dataset's ``units`` (or ``unit``) attribute.

netCDF4 files are HDF5 too; one that this entry's sniffer could not tell from its first bytes
(its dimension scales beyond them) is handed to :mod:`vibkit.io.netcdf`.
"""

from __future__ import annotations

import io

import numpy as np

from .errors import RecordingError
from .netcdf import read_netcdf
from .sampled import RATE_NAMES, Named, assemble, pick_arrays

__all__ = ["sniff_hdf5", "read_hdf5", "NETCDF_MARKERS"]

_SIGNATURE = b"\x89HDF\r\n\x1a\n"
#: attribute names netCDF-4 writes (netCDF-C, h5netcdf): an HDF5 file with one of them is netCDF
NETCDF_MARKERS = (b"_NCProperties", b"DIMENSION_SCALE", b"_Netcdf4Dimid", b"_Netcdf4Coordinates")
_NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf", ".cdf")


def sniff_hdf5(probe) -> bool:
    """HDF5 content that shows none of netCDF-4's attributes in its first bytes and has no netCDF suffix."""
    return (
        probe.head.startswith(_SIGNATURE)
        and probe.suffix not in _NETCDF_SUFFIXES
        and not any(m in probe.head for m in NETCDF_MARKERS)
    )


def _text(v):
    if isinstance(v, bytes):
        return v.decode("utf-8", errors="replace")
    if isinstance(v, np.ndarray) and v.size == 1:
        return _text(v.reshape(()).item())
    return v if isinstance(v, str) else None


def _rate_attr(attrs):
    for k, v in attrs.items():
        if k.lower() in RATE_NAMES:
            try:
                return float(np.ravel(v)[0]), k
            except (TypeError, ValueError, IndexError):
                return None
    return None


def _is_netcdf(f) -> bool:
    import h5py

    if "_NCProperties" in f.attrs:
        return True
    found = []

    def visit(_name, obj):
        if isinstance(obj, h5py.Dataset) and _text(obj.attrs.get("CLASS")) == "DIMENSION_SCALE":
            found.append(True)
            return True
        return None

    f.visititems(visit)
    return bool(found)


def read_hdf5(path, data, options):
    """A plain HDF5 file (see the module docstring)."""
    import h5py

    history, arrays, file_rate = [], [], None
    try:
        with h5py.File(io.BytesIO(data), "r") as f:
            if _is_netcdf(f):
                return read_netcdf(path, data, channel=options.get("channel"), repair_time=options.get("repair_time"))
            file_rate = _rate_attr(f.attrs)

            def visit(name, obj):
                if not isinstance(obj, h5py.Dataset):
                    return
                if obj.dtype.kind not in "iufb" or obj.dtype.names:
                    history.append(f"dataset /{name} of type {obj.dtype} skipped (channels are numbers)")
                    return
                unit = next((_text(obj.attrs[k]) for k in ("units", "unit", "Units") if k in obj.attrs), None)
                own = _rate_attr(obj.attrs) or (_rate_attr(obj.parent.attrs) if obj.parent.name != "/" else None)
                arrays.append(Named(name, obj[()], unit, own[0] if own else None))

            f.visititems(visit)
    except RecordingError:
        raise
    except Exception as exc:  # h5py raises OSError/KeyError/ValueError for a damaged file
        raise RecordingError(path, None, f"cannot read as HDF5: {type(exc).__name__}: {exc}") from None
    if not arrays:
        raise RecordingError(
            path, None, "HDF5 file without numeric datasets; expected datasets of samples with a sample_rate attribute"
        )
    history.insert(0, f"HDF5 file read with h5py: {len(arrays)} numeric dataset(s)")
    columns, time, rate, notes = pick_arrays(
        path,
        arrays,
        what="datasets",
        rate=file_rate[0] if file_rate else None,
        rate_source=f"the file's attribute {file_rate[1]!r}" if file_rate else "",
        given_rate=options.get("sample_rate"),
        channel=options.get("channel"),
    )
    return assemble(
        path,
        data,
        reader="vibkit.io.hdf5",
        columns=columns,
        options=options,
        history=history + notes,
        time=time,
        rate=rate,
        metadata=[("format", "HDF5")],
    )
