"""Recordings built from arrays: the ``xarray.Dataset`` layout that ``vibkit.io.read_recording`` returns."""

from __future__ import annotations

import numpy as np
import xarray as xr


def recording(channels, fs=None, *, t=None, units="m/s^2", var_attrs=None, time_units="s", segment=None, attrs=None):
    """A recording of the channels ``{name: samples}`` on times ``t`` [s] or at the rate ``fs`` [Hz].

    Each channel gets the attributes ``{"units": units, **var_attrs}`` (no ``units`` where ``units`` is
    None), the time coordinate ``{"units": time_units}`` (none where None); ``segment`` (burst numbers, one
    per sample) is stored as int32; ``attrs`` are the dataset's.
    """
    n = len(next(iter(channels.values())))
    if t is None:
        t = np.arange(n) / fs
    va = ({} if units is None else {"units": units}) | (var_attrs or {})
    ds = xr.Dataset(
        {k: ("time", np.asarray(v, dtype=float), dict(va)) for k, v in channels.items()},
        coords={"time": ("time", t, {} if time_units is None else {"units": time_units})},
        attrs=attrs or {},
    )
    if segment is not None:
        ds["segment"] = ("time", segment.astype(np.int32))
    return ds
