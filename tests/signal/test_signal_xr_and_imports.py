"""xarray wrappers keep units and process bursts; the package imports only what it may."""

import ast
import pathlib
import sys

import numpy as np
import pytest
import xarray as xr

import vibkit.signal as vs

FS = 512.0


def recording(seconds=20.0, *, bursts=1, seed=0, f0=3.75):
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    t = np.arange(n) / FS
    x = np.cos(2 * np.pi * f0 * t) + 0.5 * np.cos(4 * np.pi * f0 * t) + 0.3 * rng.standard_normal(n)
    seg = np.repeat(np.arange(bursts), n // bursts)[:n]
    t = t + seg * 100.0  # gaps between bursts
    da = xr.DataArray(
        x,
        dims="time",
        coords={"time": ("time", t, {"units": "s"})},
        name="acc",
        attrs={"units": "m/s^2", "long_name": "step acceleration", "quantity": "acceleration"},
    )
    return da.assign_coords(segment=("time", seg.astype(np.int32)))


def test_amplitude_spectrum_da_units():
    da = recording().drop_vars("segment")
    out = vs.amplitude_spectrum_da(da)
    assert out.attrs["units"] == "m/s^2" and out["frequency"].attrs["units"] == "Hz"
    assert float(out.sel(frequency=3.75, method="nearest")) == pytest.approx(1.0, rel=0.02)


def test_welch_psd_da_over_bursts_integrates_to_variance():
    da = recording(bursts=4)
    ds = vs.welch_psd_da(da, nperseg=512)
    assert ds["psd"].attrs["units"] == "(m/s^2)^2/Hz"
    df = float(ds.frequency[1] - ds.frequency[0])
    assert float(ds.psd.sum()) * df == pytest.approx(float(da.var()), rel=0.05)
    assert ds.attrs["n_bursts"] == 4
    assert np.all(ds.psd_lower <= ds.psd) and np.all(ds.psd <= ds.psd_upper)


def test_link_pass_estimate_da_combines_bursts_by_inverse_variance():
    da = recording(seconds=40.0, bursts=4)
    comb = vs.link_pass_estimate_da(da, band=(2.0, 6.0), n_harmonics=2)
    sig = np.array([e.fundamental_sigma_hz for _, e in comb.per_segment])
    assert len(comb.per_segment) == 4
    assert comb.fundamental_sigma_hz == pytest.approx(1 / np.sqrt(np.sum(1 / sig**2)))
    assert abs(comb.fundamental_hz - 3.75) < 4 * comb.fundamental_sigma_hz


def test_hampel_da_and_spectrogram_da_keep_units():
    da = recording(bursts=2)
    h = vs.hampel_da(da, 3, 3.0)
    assert h["filtered"].attrs["units"] == "m/s^2" and h["is_outlier"].dtype == bool
    s = vs.spectrogram_da(da.isel(time=slice(0, 4000)), nperseg=1024)
    assert s.attrs["units"] == "m/s^2" and s["time"].attrs["units"] == "s"


def test_non_uniform_time_is_an_error():
    da = recording(bursts=2).drop_vars("segment")
    with pytest.raises(ValueError, match="non-uniform"):
        vs.amplitude_spectrum_da(da)


ALLOWED = {"numpy", "scipy", "xarray", "numba", "vibkit"}


def test_signal_package_imports_only_numpy_scipy_xarray_numba_stdlib():
    """numpy, scipy, xarray, numba and the standard library; matplotlib only inside a result's ``plot`` method (a
    figure asked for: never at import)."""
    root = pathlib.Path(vs.__file__).parent
    for path in root.glob("*.py"):
        tree = ast.parse(path.read_text(), filename=str(path))
        in_plot = {
            id(node)
            for fn in ast.walk(tree)
            if isinstance(fn, ast.FunctionDef) and fn.name == "plot"
            for node in ast.walk(fn)
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level > 0:
                    continue  # relative: inside vibkit.signal
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top == "matplotlib" and id(node) in in_plot:
                    continue
                assert top in ALLOWED or top in sys.stdlib_module_names, f"{path.name} imports {name}"
                if top == "vibkit":
                    assert name.startswith("vibkit.signal"), f"{path.name} imports {name}"
