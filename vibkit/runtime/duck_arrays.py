"""A command-line process that never makes a dask array runs xarray as where dask is not installed.

dask is installed for sweeps and fleet scans; where it is, xarray imports it to ask of every array it wraps
whether it is a dask one: ``dask.base`` from the first index it builds (with dask's configuration, yaml, toolz
and more), ``dask.array`` for its table of array types.  Measured 2026-12-07 on the project's 2-core machine
(xarray 2026.9, dask 2026.8), after ``import numpy, scipy.signal, pandas, xarray``: 0.13-0.21 CPU-s for
``dask.base`` and 0.24-0.29 more for ``dask.array``: together about a sixth of what those four imports cost,
more than a 10 s ``vibkit spectrum`` spends on its own work.

A process whose command reads recordings and analyses them with numpy never makes a dask array, so the command
line marks ``dask`` as not importable (``sys.modules["dask"] = None``: Python's own way to stop an import, which
raises ``ModuleNotFoundError`` and makes ``importlib.util.find_spec`` answer None) before anything imports xarray.
xarray then takes the path it takes without dask, a configuration it supports and tests; nothing of xarray's is
changed.  Only :func:`vibkit.cli.main` does this, only for such commands, and only where it runs the process's
own command line (no ``argv`` given: the ``vibkit`` script, ``python -m vibkit``), never in a library user's
process (which may hold dask arrays), nor once xarray or dask is imported.
"""

from __future__ import annotations

import sys

__all__ = ["without_dask"]


def without_dask() -> bool:
    """Mark dask as not importable in this process, unless xarray or dask is imported already; True where it took.

    xarray decides once, when it is imported, whether dask is installed: once it is loaded the answer is its own
    and is left alone."""
    if any(name == "dask" or name.startswith(("dask.", "xarray")) for name in list(sys.modules)):
        return False
    sys.modules["dask"] = None  # type: ignore[assignment]
    return True
