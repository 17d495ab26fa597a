"""``dim=`` on the xarray wrappers: an N-D DataArray (time x channel) gives, for each channel, what the
call on that channel alone gives, joined along ``channel``; another dimension name works like ``time``."""

import numpy as np
import pytest
import xarray as xr

import vibkit.signal as vs

FS = 256.0


def two_channels(seconds=16.0, bursts=1):
    rng = np.random.default_rng(3)
    n = int(seconds * FS)
    t = np.arange(n) / FS
    x = np.stack([np.cos(2 * np.pi * 3.75 * t), 0.5 * np.sin(2 * np.pi * 7.5 * t)], axis=1)
    x = x + 0.2 * rng.standard_normal(x.shape)
    x[100, 1] = 40.0  # one outlier in the second channel
    seg = np.repeat(np.arange(bursts), n // bursts)[:n].astype(np.int32)
    da = xr.DataArray(
        x,
        dims=("time", "channel"),
        coords={"time": ("time", t + seg * 50.0, {"units": "s"}), "channel": ["az", "ay"]},
        name="acc",
        attrs={"units": "m/s^2", "long_name": "acceleration"},
    )
    return da.assign_coords(segment=("time", seg))


def test_amplitude_spectrum_along_time_of_two_channels():
    da = two_channels()
    out = vs.amplitude_spectrum_da(da)
    assert out.dims == ("frequency", "channel") and list(out["channel"].values) == ["az", "ay"]
    for ch in ("az", "ay"):
        xr.testing.assert_allclose(
            out.sel(channel=ch, drop=True), vs.amplitude_spectrum_da(da.sel(channel=ch, drop=True))
        )
    assert float(out.sel(channel="az").sel(frequency=3.75, method="nearest")) == pytest.approx(1.0, rel=0.03)
    assert float(out.sel(channel="ay").sel(frequency=7.5, method="nearest")) == pytest.approx(0.5, rel=0.05)


def test_welch_over_bursts_per_channel():
    da = two_channels(bursts=2)
    ds = vs.welch_psd_da(da, nperseg=256)
    assert ds["psd"].dims == ("channel", "frequency") and ds.attrs["n_bursts"] == 2
    for ch in ("az", "ay"):
        one = vs.welch_psd_da(da.sel(channel=ch, drop=True), nperseg=256)
        np.testing.assert_array_equal(ds["psd"].sel(channel=ch).values, one["psd"].values)
        np.testing.assert_array_equal(ds["psd_upper"].sel(channel=ch).values, one["psd_upper"].values)
    assert ds["psd"].attrs["units"] == "(m/s^2)^2/Hz"


def test_hampel_and_spectrogram_per_channel():
    da = two_channels()
    h = vs.hampel_da(da, 3, 3.0)
    assert h["filtered"].dims == ("channel", "time")
    assert bool(h["is_outlier"].sel(channel="ay").isel(time=100)) and not bool(
        h["is_outlier"].sel(channel="az").isel(time=100)
    )
    for ch in ("az", "ay"):
        one = vs.hampel_da(da.sel(channel=ch, drop=True), 3, 3.0)
        np.testing.assert_array_equal(h["filtered"].sel(channel=ch).values, one["filtered"].values)
    s = vs.spectrogram_da(da, nperseg=512)
    assert s.dims == ("channel", "frequency", "time")
    np.testing.assert_array_equal(
        s.sel(channel="ay").values, vs.spectrogram_da(da.sel(channel="ay", drop=True), nperseg=512).values
    )


def test_a_named_dimension_other_than_time():
    da = two_channels().drop_vars("segment").rename(time="t").transpose("channel", "t")
    ref = vs.amplitude_spectrum_da(two_channels().drop_vars("segment"))
    out = vs.amplitude_spectrum_da(da, dim="t")
    assert out.dims == ("channel", "frequency")
    np.testing.assert_allclose(out.transpose("frequency", "channel").values, ref.values)
    h = vs.hampel_da(da, 3, 3.0, dim="t")
    assert "t" in h.dims and "time" not in h.dims
    assert vs.sample_rate(da, dim="t") == pytest.approx(FS)
    est = vs.link_pass_estimate_da(da.sel(channel="az"), dim="t", band=(2.0, 6.0), n_harmonics=1)
    assert est.fundamental_hz == pytest.approx(3.75, abs=0.01)


def test_wrong_dim_and_many_columns_for_one_estimate_are_named():
    da = two_channels()
    with pytest.raises(ValueError, match="needs a 'sample' dimension"):
        vs.amplitude_spectrum_da(da, dim="sample")
    with pytest.raises(ValueError, match="must be 1-D along 'time' .* select one column"):
        vs.link_pass_estimate_da(da, band=(2.0, 6.0))
