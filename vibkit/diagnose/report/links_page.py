"""The report's "links" page: the per-link map of a tensioner recording over two loops or more, with its
threshold and the flagged links (:func:`vibkit.diagnose.links.find_worn_links`)."""

from __future__ import annotations

import numpy as np

from ..rounding import fmt_pm
from .common import _WIDE, _page_title

__all__ = ["flag_label", "links_page"]


def flag_label(f) -> str:
    """``"link 55 or 115: +1.504 +- 0.017 mm"`` of one flag of :func:`vibkit.diagnose.links.find_worn_links`."""
    label = "link " + " or ".join(str(k) for k in [f["link"], *f.get("alternatives", ())])
    if f.get("excess_pitch_mm") is not None:
        label += ": " + fmt_pm(f["excess_pitch_mm"], f["sigma_mm"], "mm", sign=True)
    return label


def links_page(doc, ctx) -> None:
    """The absolute t of every link against the threshold; the flagged links marked with their excess pitch."""
    res = ctx.links
    if res is None:
        return
    import matplotlib.pyplot as plt

    residual = res.residual_statistic if res.flagged else None
    if residual is None:
        fig, ax = plt.subplots(figsize=_WIDE)
        axes = [ax]
    else:
        fig, axes = plt.subplots(2, 1, figsize=_WIDE, sharex=True, gridspec_kw={"height_ratios": [2, 1]})
        ax = axes[0]
    fig.subplots_adjust(left=0.08, right=0.97, top=0.84, bottom=0.1, hspace=0.12)
    _page_title(
        fig,
        "Links",
        f"{res.loops} loops of {res.n_links} links, channel {res.channel}; {res.method}; a chain without a worn "
        f"link passes the threshold |t| = {res.threshold:.2f} in at most {100 * res.false_alarm:g} % of its "
        "recordings; "
        + (
            f"link 1: the link marked at {res.marker_s:g} s (--marker), numbers in passing order. "
            if res.marker_s is not None
            else "link 1: the link at the sensor at the start, numbers in passing order. "
        )
        + (
            "Above: each link's fit before any flagged link is taken out (a worn link's change fits its neighbours "
            "too, so many bars may pass the line); below: each link's fit once the flagged links' change is taken "
            "out, which no other link passes"
            if residual is not None
            else "Bars: each link's fit"
        ),
    )
    links = np.arange(1, res.n_links + 1)
    ax.vlines(links, 0, res.statistic, color="C0", lw=1.0)
    for f in res.flagged:
        label = flag_label(f)
        ax.plot([f["link"]], [f["t"]], "o", color="C3", ms=6)
        ax.annotate(label, (f["link"], f["t"]), textcoords="offset points", xytext=(6, -4), fontsize=8)
    if not res.flagged:
        ax.text(0.02, 0.92, "no link flagged", transform=ax.transAxes, fontsize=9)
    ax.set_ylim(0, 1.15 * max(float(np.max(res.statistic)), res.threshold))
    ax.set_ylabel("|t| of the link's fit")
    if residual is not None:
        axes[1].vlines(links, 0, residual, color="C0", lw=1.0)
        axes[1].set_ylim(0, 1.3 * max(float(np.max(residual)), res.threshold))
        axes[1].set_ylabel("|t|, flagged\nlinks taken out")
    for a in axes:
        a.axhline(res.threshold, color="C3", lw=1.0, ls="--", label=f"threshold {res.threshold:.2f}")
        a.set_xlim(0, res.n_links + 1)
        a.grid(alpha=0.3)
    axes[-1].set_xlabel("link number")
    ax.legend(loc="upper right", fontsize=8)
    doc.emit(fig, "links")
