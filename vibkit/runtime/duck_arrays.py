"""xarray without its dask probe, in the command-line processes that never make a dask array.

xarray asks of every array it wraps whether it is a dask array, and to know it imports dask (and ``dask.array``)
the first time, whether or not the process ever makes one (measured 2026-12-07 on the project's 2-core machine with
xarray 2026.9 and dask 2026.8: `vibkit spectrum` of a 10 s file 3.62 CPU-s with the probe, 3.42 without, means of
5 interleaved pairs; xarray still imports ``dask.base`` to ask whether a value is a dask collection).  A command that reads recordings and analyses them with numpy never makes a dask array:
:func:`no_dask_arrays` gives xarray the answer it gives itself where dask is not installed ("no dask array type"),
if dask is not imported yet.  Only the command line calls it, and only for such commands (not `sweep`, which reads
and writes Zarr through dask, nor `fleet`, whose scans may start a Dask cluster): a library user's process, which
may hold dask arrays, keeps xarray's own probe.
"""

from __future__ import annotations

import sys

__all__ = ["no_dask_arrays"]


def no_dask_arrays() -> bool:
    """Tell xarray that this process has no dask arrays (unless dask is imported already); True where it took.

    Uses xarray's cache of array modules (``xarray.namedarray.pycompat``); where that is not there (another xarray),
    nothing is changed and xarray probes as before."""
    if "dask" in sys.modules:
        return False
    try:
        from xarray.namedarray import pycompat

        cache = pycompat._cached_duck_array_modules
        module = object.__new__(pycompat.DuckArrayModule)
        module.module, module.version, module.type, module.available = None, pycompat.Version("0.0.0"), (), False
    except (ImportError, AttributeError, TypeError):
        return False
    cache.setdefault("dask", module)
    return cache["dask"] is module
