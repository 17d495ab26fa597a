"""The figure of a ride's quality: the per-axis table and each axis's weighted acceleration.

:func:`plot_ride` is what :meth:`vibkit.diagnose.ride.RideQuality.plot` draws and what the report's
ride-quality page holds (:mod:`vibkit.diagnose.report.ride_pages` adds the page's header and notes).
"""

from __future__ import annotations

import math

from ...runtime.constants import A4_PORTRAIT_IN

__all__ = ["plot_ride"]

_PAGE = A4_PORTRAIT_IN


#: the table's columns as fractions of its width: the axis column holds "tangential" (a simulation's
#: accel_step), the channel column a simulated step roller's "roller_acceleration[59, z] + g"
_COLUMN_WIDTHS = [0.1, 0.3, 0.09, 0.09, 0.08, 0.08, 0.14, 0.1]


def _num(v, digits=3) -> str:
    """A table value to three digits (a ride statistic over a few hundred half-cycles is not known to four), ``n/a``
    where the ride has none (a constant channel: no half-cycles), never ``nan``."""
    return f"{v:.{digits}g}" if v is not None and math.isfinite(float(v)) else "n/a"


def plot_ride(rq, fig=None, *, bottom=0.07):
    """Draw a :class:`vibkit.diagnose.ride.RideQuality` on one figure: the per-axis table (weighted and 10 Hz
    max pk-pk, A95, r.m.s.) and each axis's weighted acceleration with the ride segment shaded and
    its largest peak-to-peak pair marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=_PAGE)
    seg = rq.segment
    n = len(rq.axes)
    tab_ax = fig.add_axes((0.06, 0.76, 0.88, 0.14))
    tab_ax.axis("off")
    head = ["axis", "channel", "weighting", "max pk-pk", "A95", "r.m.s.", "10 Hz max pk-pk", "10 Hz A95"]
    cells = rq.table_rows(channel_width=32)
    tab = tab_ax.table(
        cellText=cells,
        colLabels=head,
        loc="upper center",
        cellLoc="center",
        colWidths=_COLUMN_WIDTHS,
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(8)
    tab.scale(1, 1.3)
    fig.text(  # two lines: a long segment method ("whole simulated time") would run off the page in one
        0.06,
        0.755,
        f"values in m/s^2 over the ride {seg.start_s:.2f}-{seg.end_s:.2f} s ({seg.method})\n"
        "pk-pk: adjacent half-cycle peaks; A95: not exceeded by 95 % of them",
        fontsize=7.5,
        color="0.3",
        va="top",
        linespacing=1.3,
    )
    top = 0.7
    h = (top - bottom) / max(n, 1)
    for j, a in enumerate(rq.axes):
        ax = fig.add_axes((0.1, top - (j + 1) * h + 0.04, 0.85, h - 0.06))
        y = rq.weighted[a.axis]
        ax.plot(rq.time, y, lw=0.5, color="C0")
        ax.axvspan(seg.start_s, seg.end_s, color="C2", alpha=0.12, lw=0)
        tm = seg.start_s + a.weighted.time_of_max_s
        if math.isfinite(tm):
            ax.axvline(tm, color="C3", ls=":", lw=1)
        ax.set_ylabel(f"{a.axis}, {a.weighting} [m/s^2]")
        ax.set_title(
            f"{a.axis}: weighted ({a.weighting}); max pk-pk {_num(a.weighted.max, 3)} m/s^2 (dotted), "
            f"A95 {_num(a.weighted.a95, 3)} m/s^2",
            fontsize=8.5,
        )
        ax.grid(alpha=0.3)
        if j == n - 1:
            ax.set_xlabel("time [s] (shaded: ride segment)")
    return fig
