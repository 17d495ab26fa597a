"""The report's comparison pages, drawn only when a scene was given: the simulation against the recording
(:func:`plot_comparison`) and the table of harmonics with their intervals."""

from __future__ import annotations

import textwrap

from ..comparison import amplitude_diff_text
from ..comparison_figure import plot_comparison
from .common import (
    _PAGE,
    _WIDE,
    FREQUENCY_RATIO,
    PITCH_RATIO,
    _page_title,
    fmt_pm,
    fmt_value,
    pitch_figure,
    speed_figure,
)

__all__ = ["plot_comparison", "simulation_page", "harmonics_page"]


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
