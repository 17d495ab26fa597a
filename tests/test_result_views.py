"""Result objects show themselves: ``.plot()`` where a figure is the natural view, ``_repr_html_`` in notebooks.

Headless (matplotlib's Agg backend). The figures are checked for what they must draw (the PSD and its band
on the PSD's own numbers, one panel per axis of a ride with the weighted signal), the HTML for the numbers
the result holds and for escaping.
"""

import html

import matplotlib
import numpy as np
import pytest
import xarray as xr

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from vibkit.diagnose.html import result_table_html  # noqa: E402
from vibkit.diagnose.pitch import estimate_pitch  # noqa: E402
from vibkit.diagnose.ride.quality import ride_quality  # noqa: E402
from vibkit.signal import welch_psd  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _tone(f0=3.75, fs=200.0, seconds=40.0, noise=0.05, seed=0):
    t = np.arange(int(fs * seconds)) / fs
    rng = np.random.default_rng(seed)
    return t, np.sin(2 * np.pi * f0 * t) + 0.3 * np.sin(2 * np.pi * 2 * f0 * t) + noise * rng.standard_normal(t.size)


def test_welch_result_plots_its_psd_and_band():
    t, x = _tone()
    res = welch_psd(x, 200.0, nperseg=1024)
    ax = res.plot(units="m")
    line = ax.get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), res.frequency_hz)
    np.testing.assert_array_equal(line.get_ydata(), res.psd)
    assert ax.get_yscale() == "log" and ax.get_ylabel() == "PSD [m^2/Hz]"
    assert len(ax.collections) == 1  # the confidence band
    # the peak drawn is the tone's (within one bin)
    assert abs(line.get_xdata()[np.argmax(line.get_ydata())] - 3.75) <= 200.0 / 1024


def test_welch_plot_refuses_several_psds():
    _, x = _tone()
    res = welch_psd(np.vstack([x, x]), 200.0, nperseg=1024)
    with pytest.raises(ValueError, match="one PSD"):
        res.plot()


def _ride():
    fs = 200.0
    t = np.arange(int(10 * fs)) / fs
    rng = np.random.default_rng(1)
    acc = {
        "x": 0.02 * rng.standard_normal(t.size),
        "y": 0.02 * rng.standard_normal(t.size),
        "z": 0.3 * np.sin(2 * np.pi * 4.0 * t),
    }
    return t, acc


def test_ride_quality_plots_one_panel_per_axis_and_shows_html():
    t, acc = _ride()
    rq = ride_quality(acc, 200.0, segment=(1.0, 9.0), source="synthetic <step>")
    fig = rq.plot()
    panels = [ax for ax in fig.axes if ax.get_lines()]
    assert len(panels) == 3
    z = rq.axis("z")
    for ax, a in zip(panels, rq.axes):
        np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), rq.weighted[a.axis])
    text = rq._repr_html_()
    assert "synthetic &lt;step&gt;" in text and "<step>" not in text  # escaped
    assert f"{z.weighted.max:.3g}" in text and text.count("<tr>") == 1 + 3  # the heading row and one per axis


def test_pitch_estimate_html_gives_the_numbers_with_their_sigmas():
    fs, v, pitch = 200.0, 0.5, 0.13333
    t, x = _tone(f0=v / pitch, fs=fs)
    rec = xr.Dataset({"delta": ("time", x, {"units": "m"})}, coords={"time": t})
    est = estimate_pitch(rec, speed=v, speed_sigma=0.5e-3, nominal_pitch=pitch)
    text = est._repr_html_()
    assert "link-pass frequency" in text and "Hz" in text and "mm" in text
    f_text = html.unescape(text).split("link-pass frequency</th><td")[1]
    value = float(f_text.split(">", 1)[1].split(" +-")[0])
    assert abs(value - v / pitch) <= 3 * est.fundamental_sigma_hz + 1e-9


def test_result_table_escapes_and_lays_out_columns():
    out = result_table_html("a <b>", [("k&", ["1", "<2>"])], columns=["c1", "c2"])
    assert "a &lt;b&gt;" in out and "k&amp;" in out and "&lt;2&gt;" in out
    assert out.count("<th>") == 3  # the corner and two column headings
