"""The fleet report: one PDF page of elongation against date per unit, the limits as lines, the next
limit's forecast interval as a bar (:func:`write_fleet_report`, drawn by :func:`fleet_page`)."""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass

import numpy as np

from .common import _WIDE, PageSink, Report, _page_title, atomic_path, report_date

__all__ = ["FLEET_PAGE_MAX_UNITS", "FleetContext", "fleet_page", "write_fleet_report"]

#: units drawn on the fleet page (the most urgent ones; the rest are listed by ``vibkit fleet status``)
FLEET_PAGE_MAX_UNITS = 24


@dataclass
class FleetContext:
    """What the fleet page draws.

    Attributes
    ----------
    trends : list of vibkit.fleet.history.UnitTrend
        All units, ranked (most urgent first).
    shown : list of vibkit.fleet.history.UnitTrend
        The units drawn (the first ``max_units``).
    measurements : list of vibkit.fleet.history.Measurement
    by_unit : dict
        Unit name to its measurements.
    limits : tuple of float
        Elongation limits [%].
    database : str
    date : datetime.datetime
    """

    trends: list
    shown: list
    measurements: list
    by_unit: dict
    limits: tuple
    database: str
    date: _dt.datetime


def _utc(text):
    return _dt.datetime.fromisoformat(text.replace("Z", "+00:00"))


def fleet_page(doc, ctx) -> None:
    """Elongation against date, one panel per drawn unit, most urgent first."""
    import matplotlib.dates as mdates
    import matplotlib.pyplot as plt

    from ... import __version__

    trends, shown, measurements, by_unit, limits, date = (ctx.trends, ctx.shown, ctx.measurements, ctx.by_unit,
                                                          ctx.limits, ctx.date)
    utc = _utc
    n = len(shown)
    ncol = 1 if n <= 1 else 2 if n <= 4 else 3 if n <= 9 else 4
    nrow = max(1, math.ceil(n / ncol))
    colors = ("#d4a017", "#e0661b", "#b2182b")
    fig = plt.figure(figsize=_WIDE)
    _page_title(fig, "Fleet: step-chain elongation against date",
                f"{len(trends)} unit(s), {len(measurements)} measurement(s), most urgent first; limits "
                f"{' / '.join(f'{v:g}' for v in limits)} % (dashed); database "
                f"{os.path.basename(str(ctx.database))}; {date:%Y-%m-%d}, vibkit {__version__}")
    fig.text(0.06, 0.035, "points: measurements with 1-sigma error bars; line: weighted least-squares trend; "
             "bar: 2-sigma interval of the date the next limit is reached", fontsize=7.5, color="0.3")
    gs = fig.add_gridspec(nrow, ncol, left=0.06, right=0.98, top=0.90, bottom=0.08, hspace=0.55, wspace=0.25)
    for i, tr in enumerate(shown):
        ax = fig.add_subplot(gs[i // ncol, i % ncol])
        ms = sorted(by_unit.get(tr.unit, []), key=lambda m: m.date_unix_s)
        x = [utc(m.date_utc) for m in ms]
        ax.errorbar(x, [m.elongation_percent for m in ms], yerr=[m.elongation_sigma_percent for m in ms],
                    fmt="o", ms=2.5, color="k", elinewidth=0.8, capsize=1.5)
        t_end = ms[-1].date_unix_s
        fit = getattr(tr, "fit", None)
        if fit is not None and fit.slope_percent_per_year > 0:
            nxt = [f for f in tr.forecasts if f.status == "forecast" and f.date_utc]
            if nxt:
                t_end = max(t_end, min(utc(nxt[0].latest_utc or nxt[0].date_utc).timestamp(),
                                       t_end + 5 * 365.25 * 86400))
        if fit is not None:
            tt = np.linspace(ms[0].date_unix_s, t_end, 50)
            ax.plot([_dt.datetime.fromtimestamp(v, tz=_dt.timezone.utc) for v in tt], fit.elongation_at(tt),
                    color="tab:blue", lw=1.0)
        for lim, c in zip(limits, colors):
            ax.axhline(lim, color=c, lw=0.9, ls="--")
        # the next limit's forecast interval, as a bar on its line
        nxt = [f for f in tr.forecasts if f.status == "forecast" and f.earliest_utc and f.latest_utc]
        if nxt and utc(nxt[0].latest_utc).timestamp() <= t_end + 1.0:
            ax.plot([utc(nxt[0].earliest_utc), utc(nxt[0].latest_utc)], [nxt[0].limit_percent] * 2,
                    color="tab:blue", lw=3.0, alpha=0.5, solid_capstyle="butt")
        slope = ("no trend" if tr.slope_percent_per_year is None else
                 f"{tr.slope_percent_per_year:+.3f} +- {tr.slope_sigma_percent_per_year:.3f} %/yr")
        ax.set_title(f"#{tr.rank} {tr.unit}: {slope}", loc="left")
        loc = mdates.AutoDateLocator(minticks=2, maxticks=6)
        ax.xaxis.set_major_locator(loc)
        ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(loc))
        ax.set_ylim(min(-0.2, min(m.elongation_percent for m in ms) - 0.2),
                    max(limits[-1] * 1.15, max(m.elongation_percent for m in ms) + 0.2))
        if i % ncol == 0:
            ax.set_ylabel("elongation [%]")
        ax.grid(True, lw=0.3, alpha=0.5)
    if len(trends) > n:
        fig.text(0.06, 0.015, f"{len(trends) - n} less urgent unit(s) not drawn; `vibkit fleet status` lists "
                 "all of them", fontsize=8, color="0.3")
    doc.emit(fig, "fleet")


def write_fleet_report(trends, measurements, out_path, *, limits_percent=None, database="",
                       max_units=FLEET_PAGE_MAX_UNITS) -> Report:
    """One PDF page of a fleet: elongation against date per unit, with the limits as lines.

    Parameters
    ----------
    trends : list of vibkit.fleet.history.UnitTrend
        Ranked (most urgent first), as :meth:`vibkit.fleet.history.FleetDB.status` returns them.
    measurements : list of vibkit.fleet.history.Measurement
        The stored measurements (error bars: their elongation sigma).
    out_path : str or os.PathLike
        PDF written atomically (the caller decides whether an existing file may be replaced).
    limits_percent : (float, float, float), optional
        Elongation limits [%] (default 1.5, 2, 3).
    database : str
        Named in the page's subtitle.
    max_units : int
        Panels drawn (the most urgent units); the page says how many were left out.

    Returns
    -------
    Report
        ``summary`` holds ``units`` and ``units_drawn``.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_pdf import PdfPages

    from ... import __version__

    limits = tuple(limits_percent) if limits_percent is not None else (1.5, 2.0, 3.0)
    out = os.fspath(out_path)
    shown = list(trends)[: int(max_units)]
    by_unit = {}
    for m in measurements:
        by_unit.setdefault(m.unit, []).append(m)
    date = report_date()
    ctx = FleetContext(trends=trends, shown=shown, measurements=measurements, by_unit=by_unit, limits=limits,
                       database=database, date=date)

    meta = {"Title": "vibkit fleet report", "Author": f"vibkit {__version__}",
            "Subject": "escalator step-chain elongation trends", "Creator": f"vibkit {__version__}",
            "CreationDate": date, "ModDate": date}
    with matplotlib.rc_context({"pdf.compression": 6, "font.size": 7, "axes.titlesize": 8,
                                "svg.hashsalt": "vibkit", "path.simplify": True}):
        with atomic_path(out, ".pdf") as tmp, PdfPages(tmp, metadata=meta) as pdf:
            doc = PageSink(pdf)
            fleet_page(doc, ctx)
    return Report(out, doc.pages, summary={"units": len(trends), "units_drawn": len(shown)})
