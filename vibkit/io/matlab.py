"""MATLAB MAT-files: v4/v5/v7 (read by scipy.io.loadmat) and v7.3 (HDF5 with a 512-byte header, read by h5py).

Layouts (MathWorks, "MAT-File Format"): a v5/v7 file opens with 116 bytes of text
(``MATLAB 5.0 MAT-file, Platform: ...``), then tagged data elements; a v7.3 file is an HDF5 file
whose 512-byte user block opens with ``MATLAB 7.3 MAT-file``, each variable a dataset with a
``MATLAB_class`` attribute (``double``, ``single``, ``char`` as UTF-16 code units, ``struct`` as a
group, ``cell`` as object references), stored in column-major order (an N x 3 matrix is a 3 x N
dataset, transposed back here).

What a recording is made of (see :func:`vibkit.io.sampled.pick_arrays`): the time base is a time
vector ``t``/``time`` [s], or a scalar ``fs``/``sample_rate`` [Hz] or ``dt`` [s]; every numeric
vector or matrix as long as the time base is a channel (a matrix: one per column, named
``data[1]``, ``data[2]`` ...); a char variable ``<name>_units`` or ``units`` (one unit, or a cell
array with one per column) gives the units.  Struct fields are read as ``struct.field`` (the time
base and units found inside the struct as beside it).
"""

from __future__ import annotations

import io

import numpy as np

from .errors import RecordingError
from .sampled import Named, assemble, pick_arrays

__all__ = ["sniff_matlab", "read_matlab"]

_NUMERIC = {
    "double",
    "single",
    "int8",
    "uint8",
    "int16",
    "uint16",
    "int32",
    "uint32",
    "int64",
    "uint64",
    "logical",
}


def sniff_matlab(probe) -> bool:
    return probe.head.startswith(b"MATLAB ") or probe.suffix == ".mat"


def _header(data: bytes) -> str:
    return data[:116].split(b"\x00")[0].decode("ascii", errors="replace").strip()


def _walk_v5(prefix, obj, out, history):
    if isinstance(obj, dict):
        for k, v in obj.items():
            if not k.startswith("__"):
                _walk_v5(f"{prefix}{k}." if isinstance(v, dict) else f"{prefix}{k}", v, out, history)
        return
    name = prefix
    if isinstance(obj, str):
        out.append(Named(name, obj))
    elif isinstance(obj, (list, tuple)) or (isinstance(obj, np.ndarray) and obj.dtype == object):
        items = list(np.ravel(obj)) if isinstance(obj, np.ndarray) else list(obj)
        if items and all(isinstance(x, str) for x in items):
            out.append(Named(name, [str(x) for x in items]))
        else:
            history.append(f"{name}: cell array skipped (channels are numeric vectors or matrices)")
    elif isinstance(obj, (int, float, np.number, np.ndarray)):
        a = np.asarray(obj)
        if a.dtype.kind == "c":
            history.append(f"{name}: complex values skipped (a recording is real)")
        elif a.dtype.kind in "iufb":
            out.append(Named(name, a))


def _v5(path, data, history):
    from scipy.io import loadmat

    try:
        mat = loadmat(io.BytesIO(data), simplify_cells=True)
    except Exception as exc:  # scipy raises ValueError/TypeError/MatReadError for what it cannot parse
        raise RecordingError(
            path, None, f"cannot read as a MATLAB MAT-file (v4, v5 or v7): {type(exc).__name__}: {exc}"
        ) from None
    out = []
    _walk_v5("", mat, out, history)
    return out


def _cls(obj) -> str:
    c = obj.attrs.get("MATLAB_class", b"")
    return c.decode() if isinstance(c, bytes) else str(c)


def _chars(arr) -> str:
    return "".join(chr(int(c)) for c in np.asarray(arr).T.ravel() if int(c))


def _walk_v73(f, group, prefix, out, history):
    import h5py

    for key in group:
        if key.startswith("#"):  # '#refs#', '#subsystem#': MATLAB's own bookkeeping
            continue
        obj, name = group[key], f"{prefix}{key}"
        cls = _cls(obj)
        if isinstance(obj, h5py.Group):
            _walk_v73(f, obj, name + ".", out, history)
        elif "MATLAB_empty" in obj.attrs and int(np.ravel(obj.attrs["MATLAB_empty"])[0]):
            continue
        elif cls == "char":
            out.append(Named(name, _chars(obj[()])))
        elif cls == "cell":
            items = [f[r] for r in np.ravel(obj[()].T)]
            if items and all(_cls(x) == "char" for x in items):
                out.append(Named(name, [_chars(x[()]) for x in items]))
            else:
                history.append(f"{name}: cell array skipped (channels are numeric vectors or matrices)")
        elif cls in _NUMERIC:
            a = obj[()]
            if a.dtype.names:
                history.append(f"{name}: complex values skipped (a recording is real)")
            else:
                out.append(Named(name, np.asarray(a).T))
        else:
            history.append(f"{name}: MATLAB class {cls or 'none'!r} skipped")


def _v73(path, data, history):
    import h5py

    try:
        with h5py.File(io.BytesIO(data), "r") as f:
            out = []
            _walk_v73(f, f, "", out, history)
    except RecordingError:
        raise
    except Exception as exc:  # h5py raises OSError/KeyError/ValueError for a damaged file
        raise RecordingError(
            path, None, f"cannot read as a MATLAB v7.3 MAT-file (HDF5): {type(exc).__name__}: {exc}"
        ) from None
    return out


def read_matlab(path, data, options):
    """A MATLAB MAT-file (see the module docstring)."""
    head = _header(data) if data.startswith(b"MATLAB ") else ""
    v73 = head.startswith("MATLAB 7.3") or data[512:520] == b"\x89HDF\r\n\x1a\n"
    history = [f"MATLAB MAT-file ({head or 'no header text: v4'})"]
    arrays = _v73(path, data, history) if v73 else _v5(path, data, history)
    if not arrays:
        raise RecordingError(path, None, "MAT-file holds no variables; expected channels and a time base")
    columns, time, rate, notes = pick_arrays(
        path, arrays, what="variables", given_rate=options.get("sample_rate"), channel=options.get("channel")
    )
    meta = [("format", "MATLAB 7.3" if v73 else "MATLAB 5.0" if head else "MATLAB 4")]
    return assemble(
        path,
        data,
        reader="vibkit.io.matlab",
        columns=columns,
        options=options,
        history=history + notes,
        time=time,
        rate=rate,
        metadata=meta,
    )
