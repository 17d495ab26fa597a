"""The report's comparison pages, drawn only when a scene was given: the simulation against the recording
(:func:`plot_comparison`) and the table of harmonics with their intervals."""

from __future__ import annotations

import textwrap

import numpy as np

from ...signal import amplitude_spectrum, spectrogram
from ..comparison import amplitude_diff_text
from .common import (
    _PAGE,
    _WIDE,
    FREQUENCY_RATIO,
    PITCH_RATIO,
    _page_title,
    fmt_pm,
    fmt_value,
    length_scale,
    pitch_figure,
    speed_figure,
)

__all__ = ["plot_comparison", "simulation_page", "harmonics_page"]


def plot_comparison(comp, fig=None, *, top=0.88):
    """Draw a :class:`vibkit.diagnose.comparison.Comparison` on one figure: order spectra overlaid, amplitude
    spectra side by side with harmonic markers, spectrograms side by side.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=_WIDE)
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


def simulation_page(doc, ctx) -> None:
    """Simulation against recording (:func:`plot_comparison`); nothing without a scene."""
    import matplotlib.pyplot as plt

    comp, sc = ctx.comparison, ctx.scene
    if comp is None:
        return
    fig = plt.figure(figsize=_WIDE)
    pitch = f"; pitch {pitch_figure(ctx.pitch)} (page 1)" if ctx.pitch is not None else ""
    judged = {
        True: "the scene's chain has the recording's pitch",
        False: "the scene's chain pitch differs from the recording's (the scene is not this chain as worn today)",
    }.get(comp.pitch_consistent, "not judged (no speed)")
    _page_title(
        fig,
        "Simulation against recording",
        f"scene {sc.name}: {comp.variable} vs {comp.channel}; chain speed {speed_figure(ctx)}{pitch}; "
        f"{PITCH_RATIO} {fmt_pm(comp.pitch_ratio, comp.pitch_ratio_sigma)}: "
        f"{judged} (each signal's link-pass peak, "
        f"{comp.fundamental_meas_hz:.4g} Hz recorded and {comp.fundamental_sim_hz:.4g} Hz simulated)",
    )
    plot_comparison(comp, fig, top=0.82)  # under a two-line subtitle
    doc.emit(fig, "simulation against recording")


def harmonics_page(doc, ctx) -> None:
    """Harmonics of the recording against the simulation, with intervals; nothing without a scene."""
    import matplotlib.pyplot as plt

    comp = ctx.comparison
    if comp is None:
        return
    fig = plt.figure(figsize=_PAGE)
    _page_title(fig, "Harmonics: recording / simulation", f"{100 * comp.confidence:.0f} % intervals")
    ax = fig.add_axes((0.04, 0.45, 0.92, 0.45))
    ax.axis("off")
    head = ["order", "f sim [Hz]", "f rec [Hz]", FREQUENCY_RATIO, "amp. diff [dB]", "detected"]
    cells = [
        [
            str(h["order"]),
            f"{h['frequency_sim_hz']:.4f}",
            # the recording's harmonic to the digits its ratio's sigma gives it (a faint order 5 is not known to
            # 0.1 mHz), the simulation's to 0.1 mHz
            fmt_value(h["frequency_meas_hz"], h["frequency_ratio_sigma"] * h["frequency_sim_hz"], default_decimals=4),
            fmt_pm(h["frequency_ratio"], h["frequency_ratio_sigma"]),
            amplitude_diff_text(h),
            ("sim " if h["detected_sim"] else "") + ("rec" if h["detected_meas"] else ""),
        ]
        for h in comp.harmonics
    ]
    tab = ax.table(
        cellText=cells,
        colLabels=head,
        loc="upper center",
        cellLoc="center",
        colWidths=[0.08, 0.14, 0.14, 0.24, 0.26, 0.14],
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(8.5)
    tab.scale(1, 1.4)
    fig.text(
        0.06,
        0.1,
        "\n".join(
            textwrap.fill(m, 105)
            for m in [
                f"score rule: {comp.rule}",
                f"{FREQUENCY_RATIO}: each harmonic's frequency, recorded over simulated",
                "f rec: each harmonic's own peak, to the digits its ratio's sigma allows; the link pass on page 1"
                " is fitted to all harmonics at once, so order 1 here may differ from it within its sigma",
                "not detected (< X dB): the recording carries no line of that order above its noise; X is the level"
                " read at its frequency (the noise's) against the simulation's line, and the line is under it",
            ]
            + [n for n in comp.notes if not n.startswith("pitch implied")]  # page 1 states the pitch
        ),
        fontsize=7.5,
        va="bottom",
    )
    doc.emit(fig, "harmonics")
