"""A comparison drawn (:func:`plot_comparison`): order spectra overlaid, amplitude spectra side by side with the
harmonics marked, spectrograms side by side.  :meth:`vibkit.diagnose.comparison.Comparison.plot` and the report's
comparison page draw it."""

from __future__ import annotations

import numpy as np

from ..runtime.constants import A4_LANDSCAPE_IN
from ..signal import amplitude_spectrum, spectrogram
from .rounding import length_scale

__all__ = ["plot_comparison"]


def plot_comparison(comp, fig=None, *, top=0.88):
    """Draw a :class:`vibkit.diagnose.comparison.Comparison` on one figure: order spectra overlaid, amplitude
    spectra side by side with harmonic markers, spectrograms side by side.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=A4_LANDSCAPE_IN)
    gs = fig.add_gridspec(
        3, 2, height_ratios=(1.0, 1.0, 1.1), hspace=0.55, wspace=0.25, left=0.07, right=0.97, top=top, bottom=0.07
    )
    meas = comp.signals["meas"]
    # lengths in um or mm as the tables give them, from the recording's largest value
    k, u = length_scale(
        comp.units, max((float(np.nanmax(np.abs(m[2]))) for m in meas if m[2].size), default=float("nan"))
    )
    ax = fig.add_subplot(gs[0, :])
    ax.semilogy(comp.orders, np.maximum(k * comp.order_amplitude_sim, 1e-30), label=f"simulation ({comp.variable})")
    ax.semilogy(
        comp.orders, np.maximum(k * comp.order_amplitude_meas, 1e-30), label=f"recording ({comp.channel})", alpha=0.8
    )
    top = k * max(comp.order_amplitude_sim.max(), comp.order_amplitude_meas.max())
    ax.set_ylim(top * 1e-4, top * 3)
    ax.set_xlabel("order of the link-pass frequency [-]")
    ax.set_ylabel(f"amplitude [{u}]")
    ax.set_title(
        f"Order spectra (each referred to its own link-pass); agreement score {comp.score:.2f} "
        "(1: all harmonics match, 0: none), "
        f"log-spectral distance {comp.log_spectral_distance_db:.1f} dB",
        fontsize=10,
    )
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    fs_s, x_s = comp.signals["sim"]
    longest = max(meas, key=lambda m: m[2].size)
    nh = len(comp.harmonics)
    fmax = min((nh + 1.5) * max(comp.fundamental_sim_hz, comp.fundamental_meas_hz), fs_s / 2, longest[1] / 2)
    specs = (
        ("simulation", fs_s, x_s, comp.fundamental_sim_hz, "C0"),
        ("recording", longest[1], longest[2], comp.fundamental_meas_hz, "C1"),
    )
    for j, (name, fs, x, f0, col) in enumerate(specs):
        a1 = fig.add_subplot(gs[1, j])
        f, a = amplitude_spectrum(x, fs)
        sel = f <= fmax
        a1.semilogy(f[sel], np.maximum(k * a[sel], 1e-30), color=col, lw=0.9)
        for h in range(1, nh + 1):
            a1.axvline(h * f0, color="0.5", ls=":", lw=0.8)
        a1.set_xlim(0, fmax)
        a1.set_xlabel("frequency [Hz]")
        a1.set_ylabel(f"amplitude [{u}]")
        a1.set_title(f"{name}: link-pass {f0:.4g} Hz (dotted: harmonics)", fontsize=9)
        a1.grid(alpha=0.3)
        a2 = fig.add_subplot(gs[2, j])
        frame = min(2.0, x.size / fs / 2)
        nper = max(16, int(round(frame * fs)))
        fr, tt, s = spectrogram(x, fs, nperseg=nper, noverlap=nper * 3 // 4)
        sel = fr <= fmax
        db = 20 * np.log10(np.maximum(k * s[sel], 1e-30))
        im = a2.pcolormesh(
            tt, fr[sel], db, shading="nearest", vmin=db.max() - 60, vmax=db.max(), cmap="viridis", rasterized=True
        )
        a2.set_xlabel("time from burst start [s]" if name == "recording" and len(meas) > 1 else "time [s]")
        a2.set_ylabel("frequency [Hz]")
        a2.set_title(f"{name} spectrogram ({frame:.2g} s frames)", fontsize=9)
        cb = fig.colorbar(im, ax=a2, pad=0.01)
        cb.set_label(f"dB re 1 {u}", fontsize=8)
    return fig
