"""Thin xarray wrappers that keep units, and per-segment processing of burst recordings.

A DataArray must have a ``time`` dimension with a uniform ``time`` coordinate [s]; its
``attrs["units"]`` give the output units.  ``dim=`` names another dimension to work along (its
coordinate in seconds): an N-D DataArray (``time`` x ``channel``) is processed column by column
along ``dim``, each result equal to the call on that column alone, joined along the other dims.  If ``segment`` is given (or the DataArray carries a
``segment`` coordinate), each burst is processed alone and the results combined: Welch spectra
averaged over all segments (weighted by their number of Welch segments), frequency estimates
combined by inverse-variance weighting.  Bursts are never bridged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats
import xarray as xr

from .bursts import split_segments
from .hampel import hampel
from .peaks import LinkPassEstimate, link_pass_estimate
from .spectral import amplitude_spectrum, spectrogram, welch_psd

__all__ = [
    "sample_rate",
    "split_segments",
    "amplitude_spectrum_da",
    "welch_psd_da",
    "spectrogram_da",
    "hampel_da",
    "link_pass_estimate_da",
    "CombinedEstimate",
]


def _units(da):
    return str(da.attrs.get("units", "1"))


def _squared(units):
    if units in ("", "1"):
        return "1"
    simple = all(ch.isalnum() or ch == "_" for ch in units)
    return f"{units}^2" if simple else f"({units})^2"


def sample_rate(da, *, rtol=1e-3, dim="time") -> float:
    """Sampling frequency [Hz] from a uniform coordinate ``dim`` [s] (default ``time``; within ``rtol``)."""
    if dim not in da.dims or dim not in da.coords:
        raise ValueError(
            f"DataArray {da.name!r} needs a {dim!r} dimension and coordinate [s] (dims {tuple(da.dims)}; "
            "name the time dimension with dim=)."
        )
    t = np.asarray(da[dim].values, dtype=float)
    if t.size < 2:
        raise ValueError(f"DataArray {da.name!r} has fewer than 2 time samples.")
    dt = np.diff(t)
    med = float(np.median(dt))
    if med <= 0 or np.any(np.abs(dt - med) > rtol * med):
        raise ValueError(
            f"DataArray {da.name!r} has a non-uniform time coordinate (steps {dt.min():.6g}..{dt.max():.6g} s); "
            "split it into segments or resample it first."
        )
    return 1.0 / med


def _as_time(da, dim):
    """``da`` with its dimension ``dim`` called ``time`` (what the 1-D wrappers work along)."""
    if dim == "time":
        return da
    if dim not in da.dims:
        raise ValueError(f"DataArray {da.name!r} has no dimension {dim!r} (dims {tuple(da.dims)}).")
    if "time" in da.dims or "time" in da.coords:
        raise ValueError(f"DataArray {da.name!r} has a 'time' besides dim={dim!r}; rename one of them.")
    return da.rename({dim: "time"})


def _per_column(da, fn, dim):
    """``fn`` (a 1-D wrapper along ``time``) on each column of ``da`` along ``dim``, joined along the other
    dims (their coordinates kept); ``time`` in the result is called ``dim`` again."""
    da = _as_time(da, dim)

    def apply(part, others):
        if not others:
            return fn(part)
        d = others[0]
        out = xr.concat([apply(part.isel({d: i}), others[1:]) for i in range(part.sizes[d])], dim=d)
        return out.assign_coords({d: part[d].values}) if d in part.coords else out

    out = apply(da, [d for d in da.dims if d != "time"])
    return out if dim == "time" else out.rename({"time": dim})


def amplitude_spectrum_da(da, *, dim="time", **kwargs):
    """:func:`vibkit.signal.amplitude_spectrum` of a continuous DataArray along ``dim`` (default ``time``),
    which becomes ``frequency`` [Hz]; other dims (channels) and their coordinates are kept."""
    fs = sample_rate(da, dim=dim)
    freqs = []

    def spectrum(x):
        f, a = amplitude_spectrum(x, fs, axis=-1, **kwargs)
        freqs.append(f)
        return a

    out = xr.apply_ufunc(
        spectrum, da, input_core_dims=[[dim]], output_core_dims=[["frequency"]], exclude_dims={dim}, keep_attrs=False
    )
    out = out.transpose(*["frequency" if d == dim else d for d in da.dims]).assign_coords(frequency=freqs[0])
    out["frequency"].attrs.update(units="Hz", long_name="frequency")
    out.attrs.update(units=_units(da), long_name=f"amplitude spectrum of {da.attrs.get('long_name', da.name)}")
    out.name = f"{da.name}_amplitude" if da.name else "amplitude"
    return out


def welch_psd_da(da, *, segment=None, nperseg=None, confidence=0.95, dim="time", **kwargs):
    """Welch PSD of a DataArray, averaged over bursts; returns a Dataset ``psd``, ``psd_lower``, ``psd_upper``.

    Bursts shorter than ``nperseg`` are an error naming the burst.  The interval uses the summed
    equivalent degrees of freedom of all bursts.  Along ``dim`` (default ``time``); an N-D
    DataArray gives one PSD per column, joined along its other dims.
    """
    if da.ndim != 1 or dim != "time":
        return _per_column(
            da, lambda c: welch_psd_da(c, segment=segment, nperseg=nperseg, confidence=confidence, **kwargs), dim
        )
    parts = split_segments(da, segment)
    fs = None
    acc = None
    weight = 0
    dof = 0.0
    for sid, part in parts:
        fs_p = sample_rate(part)
        if fs is not None and abs(fs_p - fs) > 1e-6 * fs:
            raise ValueError(f"Segment {sid} has a sampling rate {fs_p:g} Hz different from {fs:g} Hz.")
        fs = fs_p
        if da.ndim != 1:
            raise ValueError(f"DataArray {da.name!r} must be 1-D (time) for welch_psd_da.")
        n = part.sizes["time"]
        nps = nperseg if nperseg is not None else min(n, 256)
        if nps > n:
            raise ValueError(f"Segment {sid} has {n} samples, fewer than nperseg={nps}.")
        r = welch_psd(part.values, fs, nperseg=nps, confidence=confidence, **kwargs)
        acc = r.psd * r.nsegments if acc is None else acc + r.psd * r.nsegments
        weight += r.nsegments
        dof += r.dof
        f = r.frequency_hz
    psd = acc / weight
    alpha = 1 - confidence
    lower = dof * psd / scipy.stats.chi2.ppf(1 - alpha / 2, dof)
    upper = dof * psd / scipy.stats.chi2.ppf(alpha / 2, dof)
    units = f"{_squared(_units(da))}/Hz"
    name = da.attrs.get("long_name", da.name)
    ds = xr.Dataset(
        {
            "psd": ("frequency", psd, {"units": units, "long_name": f"Welch PSD of {name}"}),
            "psd_lower": ("frequency", lower, {"units": units, "long_name": f"lower {confidence:.0%} limit of PSD"}),
            "psd_upper": ("frequency", upper, {"units": units, "long_name": f"upper {confidence:.0%} limit of PSD"}),
        },
        coords={"frequency": ("frequency", f, {"units": "Hz", "long_name": "frequency"})},
        attrs={"dof": float(dof), "confidence": float(confidence), "n_bursts": len(parts)},
    )
    return ds


def spectrogram_da(da, *, dim="time", **kwargs):
    """:func:`vibkit.signal.spectrogram` (amplitude) of a DataArray along ``dim`` (default ``time``);
    dims ``frequency``, ``dim`` (frame centres), after the other dims of an N-D DataArray."""
    if da.ndim != 1 or dim != "time":
        return _per_column(da, lambda c: spectrogram_da(c, **kwargs), dim)
    fs = sample_rate(da)
    f, t, s = spectrogram(da.values, fs, **kwargs)
    t0 = float(da["time"].values[0])
    out = xr.DataArray(s, dims=("frequency", "time"), coords={"frequency": f, "time": t + t0})
    out["frequency"].attrs.update(units="Hz", long_name="frequency")
    out["time"].attrs.update(units="s", long_name="frame centre time")
    scaling = kwargs.get("scaling", "amplitude")
    units = _units(da) if scaling == "amplitude" else f"{_squared(_units(da))}/Hz"
    out.attrs.update(units=units, long_name=f"spectrogram of {da.attrs.get('long_name', da.name)}")
    return out


def hampel_da(da, half_window=3, n_sigma=None, *, dim="time", **kwargs):
    """:func:`vibkit.signal.hampel` of a DataArray along ``dim`` (default ``time``), burst by burst;
    Dataset ``filtered``, ``is_outlier`` (an N-D DataArray column by column)."""
    if da.ndim != 1 or dim != "time":
        return _per_column(da, lambda c: hampel_da(c, half_window, n_sigma, **kwargs), dim)
    filtered = np.empty(da.sizes["time"])
    mask = np.zeros(da.sizes["time"], dtype=bool)
    seg = da["segment"].values if "segment" in da.coords else np.zeros(da.sizes["time"], dtype=int)
    for s in np.unique(seg):
        idx = np.flatnonzero(seg == s)
        r = hampel(da.values[idx], half_window, n_sigma, **kwargs)
        filtered[idx] = r.filtered
        mask[idx] = r.is_outlier
    name = da.attrs.get("long_name", da.name)
    return xr.Dataset(
        {
            "filtered": ("time", filtered, {"units": _units(da), "long_name": f"{name}, Hampel filtered"}),
            "is_outlier": ("time", mask, {"units": "1", "long_name": "Hampel outlier flag"}),
        },
        coords={"time": da["time"]},
        attrs={
            "hampel_half_window": int(half_window),
            "hampel_threshold": (
                f"false_alarm_rate={kwargs['false_alarm_rate']}"
                if kwargs.get("false_alarm_rate") is not None
                else f"n_sigma={n_sigma if n_sigma is not None else 3.0}"
            ),
        },
    )


@dataclass(frozen=True)
class CombinedEstimate:
    """Link-pass estimate combined over bursts by inverse-variance weighting.

    Attributes
    ----------
    fundamental_hz, fundamental_sigma_hz : float
        [Hz]
    per_segment : list of (int, LinkPassEstimate)
    chi2_per_dof : float
        Scatter of the burst estimates about the combined value over their sigmas (about 1 when
        consistent; NaN for one burst).
    """

    fundamental_hz: float
    fundamental_sigma_hz: float
    per_segment: list
    chi2_per_dof: float


def link_pass_estimate_da(da, *, segment=None, dim="time", **kwargs):
    """:func:`vibkit.signal.link_pass_estimate` per burst along ``dim`` (default ``time``), combined by
    inverse-variance weighting.  One estimate: ``da`` must be 1-D (select a channel first)."""
    if da.ndim != 1:
        raise ValueError(
            f"DataArray {da.name!r} must be 1-D along {dim!r} for link_pass_estimate_da (one estimate); "
            f"got dims {tuple(da.dims)}: select one column first, e.g. da.isel(channel=0)."
        )
    da = _as_time(da, dim)
    results = []
    for sid, part in split_segments(da, segment):
        est: LinkPassEstimate = link_pass_estimate(part.values, sample_rate(part), **kwargs)
        results.append((sid, est))
    f = np.array([e.fundamental_hz for _, e in results])
    s = np.array([e.fundamental_sigma_hz for _, e in results])
    if np.any(s <= 0):
        raise ValueError("A burst gave a zero sigma (noise-free signal); inverse-variance weighting is undefined.")
    w = 1 / s**2
    f_hat = float(np.sum(w * f) / np.sum(w))
    sig = float(1 / np.sqrt(np.sum(w)))
    chi2 = float(np.sum(w * (f - f_hat) ** 2) / (f.size - 1)) if f.size > 1 else float("nan")
    return CombinedEstimate(f_hat, sig, results, chi2)
