"""The fleet report: page 1 the work list (a table ranked by urgency), then elongation against date per
unit: measurements, outliers and flagged ones marked, the fitted trend, the limits labelled, and the
next limit's forecast date with its 2-sigma interval drawn (:func:`write_fleet_report`)."""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass, field

import numpy as np

from ... import __version__
from ..decision import DEFAULT_LIMITS_PERCENT
from .common import _WIDE, PageSink, Report, atomic_path, fmt_pm
from .fleet_links import fleet_links_pages

__all__ = [
    "FLEET_PAGE_MAX_UNITS",
    "FleetContext",
    "WORK_LIST_HEADER",
    "fleet_page",
    "work_list_rows",
    "fmt_elongation",
    "OVERDUE_MEANING",
    "write_fleet_report",
]

#: units drawn (the most urgent ones; the work list on page 1 lists them all)
FLEET_PAGE_MAX_UNITS = 24
_PER_PAGE = 4  # unit panels per page
_ROWS_PER_TABLE = 22
_LIMIT_NAMES = ("watch", "plan", "replace")
_LIMIT_COLORS = ("#d4a017", "#e0661b", "#b2182b")

#: the work list's columns (``vibkit fleet status`` and page 1 of the fleet report)
WORK_LIST_HEADER = [
    "rank",
    "unit",
    "elongation [%]",
    "measured",
    "rate [%/year]",
    "verdict",
    "next",
    "reached on (2-sigma)",
    "flags",
]


#: what an overdue forecast means (the work list's note, ``fleet status``)
OVERDUE_MEANING = (
    "OVERDUE: the forecast date has passed: re-measure, the chain is probably over that limit now (a 'not before' "
    "date that has passed: it may be)"
)
#: row colours of the work list: a unit over watch, plan, replace; flags only
_ROW_COLORS = ("#fff3cd", "#fcd9b6", "#f4c2c2")
_FLAG_COLOR = "#e4ecf7"


def fmt_forecast(f, today_unix_s=None):
    """A limit forecast in a few words (year-month dates); ``OVERDUE`` when its date has passed on
    ``today_unix_s``; an interval under a month is not drawn as ``(07..07)``."""
    if f is None:
        return "all reached"
    if f.status == "reached":
        return "reached"
    if f.status == "forecast":
        if f.date_utc is None:
            return "after 9999"
        lo, hi = (f.earliest_utc or "?")[:7], (f.latest_utc or "after 9999")[:7]
        if lo[:4] == hi[:4] == f.date_utc[:4]:  # one year: the months alone, '2027-09 (07..10)'
            lo, hi = lo[5:], hi[5:]
        elif lo[:4] != hi[:4] and hi[:2] != "af":  # years apart: the years alone, '2050-05 (2043..2063)'
            lo, hi = lo[:4], hi[:4]
        interval = "" if lo == hi else f" ({lo}..{hi})"
        overdue = "OVERDUE " if today_unix_s is not None and f.overdue(today_unix_s) else ""
        return f"{overdue}{f.date_utc[:7]}{interval}"
    if f.status == "not before":
        if not f.earliest_utc:
            return "-"
        overdue = "OVERDUE " if today_unix_s is not None and f.overdue(today_unix_s) else ""
        return f"{overdue}not before {f.earliest_utc[:7]}"
    if f.status == "implausible":
        return "none (implausible rate)"
    return "-"


def fmt_elongation(t) -> str:
    """The latest elongation of a unit, rounded to its sigma; without a stated speed uncertainty, no +-; a unit
    without a usable measurement shows its latest one marked as flagged (the column is the latest usable one)."""
    said = [] if t.speed_sigma_stated else ["speed unc. not stated"]
    said += [] if t.n_used else ["flagged"]
    if not t.speed_sigma_stated:
        text = f"{t.latest_elongation_percent:+.2f}"
    else:
        text = fmt_pm(t.latest_elongation_percent, t.latest_elongation_sigma_percent, sign=True)
    return f"{text} ({', '.join(said)})" if said else text


WORK_LIST_FLAGS_WIDTH = 45  # characters of a unit's flags in the PDF's work list (the whole text: fleet status)


def work_list_rows(trends, *, flags_width=None, today_unix_s=None):
    """The work list's rows (:data:`WORK_LIST_HEADER`) of ranked :class:`vibkit.fleet.trends.UnitTrend`;
    a forecast whose date has passed on ``today_unix_s`` reads ``OVERDUE`` (:func:`fmt_forecast`)."""
    rows = []
    for t in trends:
        slope = (
            "-"
            if t.slope_percent_per_year is None
            else fmt_pm(t.slope_percent_per_year, t.slope_sigma_percent_per_year, sign=True)
        )
        nxt = t.next_limit()
        verdict = t.latest_verdict if t.rate_verdict != "implausible" else f"{t.latest_verdict}; rate implausible"
        flags = "; ".join(t.flags) or "-"
        if flags_width and len(flags) > flags_width:
            flags = flags[: flags_width - 3] + "..."
        rows.append(
            [
                str(t.rank),
                t.unit,
                fmt_elongation(t),
                t.latest_date_utc[:10],
                slope,
                verdict,
                "-" if nxt is None else f"{nxt.limit_percent:g} %",
                fmt_forecast(nxt, today_unix_s),
                flags,
            ]
        )
    return rows


@dataclass
class FleetContext:
    """What the fleet pages draw: ``trends`` (all, ranked), ``shown`` (drawn), ``measurements``, ``by_unit``,
    ``limits`` [%], ``database`` and ``date`` (of the report), ``links`` (``{unit: UnitLinks}`` of
    :func:`vibkit.fleet.links_history`; empty: no links pages)."""

    trends: list
    shown: list
    measurements: list
    by_unit: dict
    limits: tuple
    database: str
    date: _dt.datetime
    links: dict = field(default_factory=dict)


def _utc(text):
    return _dt.datetime.fromisoformat(text.replace("Z", "+00:00"))


def _dt_of(sec):
    return _dt.datetime.fromtimestamp(sec, tz=_dt.timezone.utc)


def _title(fig, title, subtitle):
    fig.text(0.04, 0.975, title, fontsize=14, fontweight="bold", ha="left", va="top")
    fig.text(0.04, 0.93, subtitle, fontsize=8, color="0.3", ha="left", va="top")


def _subtitle(ctx):
    return (
        f"{len(ctx.trends)} unit(s), {len(ctx.measurements)} measurement(s); limits "
        f"{' / '.join(f'{v:g}' for v in ctx.limits)} % ({' / '.join(_LIMIT_NAMES)}); database "
        f"{os.path.basename(str(ctx.database)) or ctx.database}; {ctx.date:%Y-%m-%d %H:%M} UTC, vibkit {__version__}"
    )


def work_list_page(doc, ctx, rows, part, parts):
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=_WIDE)
    _title(fig, "Fleet work list: most urgent first" + (f" ({part}/{parts})" if parts > 1 else ""), _subtitle(ctx))
    ax = fig.add_axes([0.04, 0.10, 0.92, 0.80])
    ax.axis("off")
    widths = [0.03, 0.055, 0.16, 0.07, 0.095, 0.10, 0.045, 0.19, 0.255]  # "OVERDUE 2024-02 (01..05)" whole
    tab = ax.table(cellText=rows, colLabels=WORK_LIST_HEADER, colWidths=widths, loc="upper left", cellLoc="left")
    tab.auto_set_font_size(False)
    tab.set_fontsize(7)
    tab.scale(1.0, 1.3)
    by_unit = {t.unit: t for t in ctx.trends}
    for (r, _c), cell in tab.get_celld().items():
        cell.set_linewidth(0.3)
        if r == 0:
            cell.set_text_props(fontweight="bold")
            cell.set_facecolor("0.9")
        elif by_unit[rows[r - 1][1]].over_limit_percent is not None:  # over a limit now: its colour
            over = by_unit[rows[r - 1][1]].over_limit_percent
            k = max((i for i, lim in enumerate(ctx.limits) if over >= lim), default=0)
            cell.set_facecolor(_ROW_COLORS[k])
        elif by_unit[rows[r - 1][1]].flags:
            cell.set_facecolor(_FLAG_COLOR)  # something to look at
    fig.text(
        0.04,
        0.05,
        "elongation: the latest usable measurement +- 1 sigma (the latest, marked flagged, where none is usable); rate: weighted least squares over the "
        "current chain (after the last replacement), +- 1 sigma; over a limit now: yellow watch, orange plan, red "
        "replace; blue: flags (outliers, flagged measurements, replacements, an implausible rate) - left out of the "
        f"trend. {OVERDUE_MEANING}. Flags longer than the cell end in '...': vibkit fleet status prints them whole.",
        fontsize=7,
        color="0.3",
        wrap=True,
    )
    doc.emit(fig, "work list")


def _draw_unit(ax, tr, ms, limits, ctx):
    labels = dict(tr.point_labels)
    styles = {
        "ok": dict(fmt="o", color="k", ms=3, label="measurement (1 sigma)"),
        "earlier segment": dict(fmt="o", color="0.65", ms=3, label="before the chain was replaced"),
        "outlier": dict(fmt="x", color="#c00000", ms=6, label="outlier, left out"),
        "inconclusive": dict(fmt="s", color="#8a6d00", ms=3.5, mfc="none", label="inconclusive, left out"),
        "implausible": dict(fmt="D", color="#7a1fa2", ms=3.5, mfc="none", label="implausible, left out"),
    }
    # the scale follows the plausible points; an implausible one off that scale is drawn at the edge
    scaled = [m for m in ms if labels.get(m.id, "ok") != "implausible"] or ms
    vals = [m.elongation_percent + s * m.elongation_sigma_percent for m in scaled for s in (-1, 1)]
    ymin = min(min(vals) - 0.15, -0.1)
    ymax = max(max(vals) + 0.15, limits[-1] + 0.35)
    for lab, st in styles.items():
        sel = [m for m in ms if labels.get(m.id, "ok") == lab]
        if not sel:
            continue
        y = np.array([m.elongation_percent for m in sel])
        off = (y > ymax) | (y < ymin)
        if off.any():
            st = {**st, "label": st["label"] + f" ({int(off.sum())} off scale, at the edge)"}
        ax.errorbar(
            [_utc(m.date_utc) for m in sel],
            np.clip(y, ymin + 0.02 * (ymax - ymin), ymax - 0.02 * (ymax - ymin)),
            yerr=np.where(off, 0.0, [m.elongation_sigma_percent for m in sel]),
            elinewidth=0.7,
            capsize=1.5,
            lw=0,
            **st,
        )
    t0 = min(m.date_unix_s for m in ms)
    t_end = max(m.date_unix_s for m in ms)
    fit, nxt = tr.fit, tr.next_limit()
    has_interval = nxt is not None and nxt.status == "forecast" and nxt.earliest_utc and nxt.latest_utc
    not_before = nxt is not None and nxt.status == "not before" and nxt.earliest_utc
    horizon = t_end + 6 * 365.25 * 86400  # a forecast further off is drawn at the panel's edge
    if has_interval:
        t_end = max(t_end, min(_utc(nxt.latest_utc).timestamp(), horizon))
    elif not_before:
        t_end = max(t_end, min(_utc(nxt.earliest_utc).timestamp(), horizon) + 0.5 * 365.25 * 86400)
    if fit is not None:
        used = [m for m in ms if labels.get(m.id, "ok") == "ok"]
        tt = np.linspace(min(m.date_unix_s for m in used), t_end, 60)
        ax.plot(
            [_dt_of(v) for v in tt],
            fit.elongation_at(tt),
            color="tab:blue",
            lw=1.0,
            label=f"trend {fmt_pm(tr.slope_percent_per_year, tr.slope_sigma_percent_per_year, sign=True)} %/yr",
        )
    for lim, c, _name in zip(limits, _LIMIT_COLORS, _LIMIT_NAMES):
        ax.axhline(lim, color=c, lw=0.9, ls="--")
    if has_interval:
        lo, hi = _utc(nxt.earliest_utc), _utc(nxt.latest_utc)
        ax.plot(
            [lo, hi],
            [nxt.limit_percent] * 2,
            color="tab:blue",
            lw=4.0,
            alpha=0.45,
            solid_capstyle="butt",
            label=f"{nxt.limit_percent:g} % reached {nxt.date_utc[:7]} (2-sigma {nxt.earliest_utc[:7]}.."
            f"{nxt.latest_utc[:7]})",
        )
        ax.plot([_utc(nxt.date_utc)], [nxt.limit_percent], "|", color="tab:blue", ms=9)
    elif not_before:  # only the earliest date is known: drawn from it on, open to the right
        lo = min(_utc(nxt.earliest_utc).timestamp(), horizon)
        ax.plot(
            [_dt_of(lo), _dt_of(t_end)],
            [nxt.limit_percent] * 2,
            color="tab:blue",
            lw=4.0,
            alpha=0.25,
            solid_capstyle="butt",
            label=f"{nxt.limit_percent:g} % reached not before {nxt.earliest_utc[:7]} (2-sigma; no latest date)",
        )
        ax.plot([_dt_of(lo)], [nxt.limit_percent], ">", color="tab:blue", ms=5)
    elif fit is not None and nxt is not None and nxt.status in ("none", "implausible"):
        ax.plot(
            [],
            [],
            " ",
            label=f"no forecast of {nxt.limit_percent:g} %: "
            + ("the rate is implausible" if nxt.status == "implausible" else "no growth within the uncertainty"),
        )
    today = ctx.date.timestamp()
    t_end = max(t_end, today)
    ax.axvline(_dt_of(today), color="0.25", lw=0.9, ls=":", label=f"today {ctx.date:%Y-%m-%d}")
    ax.set_ylim(ymin, ymax)
    span = max(t_end - t0, 30 * 86400)
    ax.set_xlim(_dt_of(t0 - 0.04 * span), _dt_of(t_end + 0.04 * span))
    for lim, c, name in zip(limits, _LIMIT_COLORS, _LIMIT_NAMES):  # labelled outside, right of the panel
        ax.text(
            1.01,
            lim,
            f"{lim:g} %\n{name}",
            color=c,
            fontsize=6.5,
            ha="left",
            va="center",
            transform=ax.get_yaxis_transform(),
        )


def _limit_colour(tr, limits):
    """The colour of the highest limit a unit is over (watch, plan, replace: three colours)."""
    k = max((i for i, lim in enumerate(limits) if tr.over_limit_percent >= lim), default=0)
    return _LIMIT_COLORS[k]


def unit_pages(doc, ctx):
    import matplotlib.dates as mdates
    import matplotlib.pyplot as plt

    shown = ctx.shown
    for p0 in range(0, len(shown), _PER_PAGE):
        fig = plt.figure(figsize=_WIDE)
        _title(fig, "Fleet: step-chain elongation against date", _subtitle(ctx))
        gs = fig.add_gridspec(2, 2, left=0.06, right=0.95, top=0.87, bottom=0.07, hspace=0.42, wspace=0.22)
        for i, tr in enumerate(shown[p0 : p0 + _PER_PAGE]):
            ax = fig.add_subplot(gs[i // 2, i % 2])
            ms = sorted(ctx.by_unit.get(tr.unit, []), key=lambda m: (m.date_unix_s, m.id or 0))
            _draw_unit(ax, tr, ms, ctx.limits, ctx)
            over = tr.over_limit_percent is not None
            head = f"#{tr.rank} {tr.unit}: {fmt_elongation(tr)} %, {tr.latest_verdict}"
            if over:
                head += f" - OVER {tr.over_limit_percent:g} %"
            elif tr.overdue(ctx.date.timestamp()):
                nxt = tr.next_limit()
                when = (
                    f"forecast {nxt.date_utc[:7]}" if nxt.status == "forecast" else f"not before {nxt.earliest_utc[:7]}"
                )
                head += f" - OVERDUE: {nxt.limit_percent:g} % {when}"
            if tr.rate_verdict == "implausible":
                head += " - rate implausible: re-measure"
            colour = _limit_colour(tr, ctx.limits) if over else "k"
            ax.set_title(head, loc="left", fontsize=8, color=colour, fontweight="bold" if over else "normal")
            if over:
                for sp in ax.spines.values():
                    sp.set_color(colour)
                    sp.set_linewidth(1.4)
            loc = mdates.AutoDateLocator(minticks=2, maxticks=6)
            ax.xaxis.set_major_locator(loc)
            ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(loc))
            ax.set_ylabel("elongation [%]")
            ax.grid(True, lw=0.3, alpha=0.5)
            ax.legend(loc="best", fontsize=6, framealpha=0.85)
        if p0 + _PER_PAGE >= len(shown) and len(ctx.trends) > len(shown):
            fig.text(
                0.06,
                0.015,
                f"{len(ctx.trends) - len(shown)} less urgent unit(s) not drawn; the work list "
                "(page 1) and `vibkit fleet status` list all of them",
                fontsize=8,
                color="0.3",
            )
        doc.emit(fig, "fleet units")


def fleet_page(doc, ctx) -> None:
    """The work list page(s), then the unit pages, then the links pages (where ``ctx.links`` holds any)."""
    rows = work_list_rows(ctx.trends, flags_width=WORK_LIST_FLAGS_WIDTH, today_unix_s=ctx.date.timestamp())
    parts = max(1, math.ceil(len(rows) / _ROWS_PER_TABLE))
    for k in range(parts):
        work_list_page(doc, ctx, rows[k * _ROWS_PER_TABLE : (k + 1) * _ROWS_PER_TABLE], k + 1, parts)
    unit_pages(doc, ctx)
    fleet_links_pages(doc, ctx, _title, _subtitle(ctx))


def fleet_report_date() -> _dt.datetime:
    """``SOURCE_DATE_EPOCH`` (for reproducible bytes) if set, else now (UTC, to the second)."""
    raw = os.environ.get("SOURCE_DATE_EPOCH")
    if raw:
        try:
            return _dt.datetime.fromtimestamp(int(raw), tz=_dt.timezone.utc)
        except ValueError:
            raise ValueError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {raw!r}") from None
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)


def write_fleet_report(
    trends,
    measurements,
    out_path,
    *,
    limits_percent=None,
    database="",
    max_units=FLEET_PAGE_MAX_UNITS,
    links=None,
) -> Report:
    """The fleet PDF: the work list (page 1), then elongation against date for the most urgent units, then
    the flagged links of each unit's latest visit.

    Parameters
    ----------
    trends : list of vibkit.fleet.trends.UnitTrend
        Ranked (most urgent first), as :meth:`vibkit.fleet.FleetDB.status` returns them.
    measurements : list of vibkit.fleet.measurement.Measurement
        The stored measurements (error bars: their elongation sigma).
    out_path : str or os.PathLike
        PDF written atomically (the caller decides whether an existing file may be replaced).
    limits_percent : (float, float, float), optional
        Elongation limits [%] (default 1.5, 2, 3).
    database : str
        Named in the subtitles.
    max_units : int
        Units drawn (the most urgent); the work list lists all of them.
    links : dict, optional
        ``{unit: UnitLinks}`` as :meth:`vibkit.fleet.FleetDB.links_history` gives them: the links pages say per
        unit which links the latest visit's scan flagged, which marked link came back worse or is new, and why a
        unit has no scan (none given: no links pages).

    Returns
    -------
    Report
        ``summary`` holds ``units`` and ``units_drawn``.  The date printed and stored is now, or
        ``SOURCE_DATE_EPOCH`` where set (reproducible bytes).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_pdf import PdfPages

    limits = tuple(limits_percent) if limits_percent is not None else DEFAULT_LIMITS_PERCENT
    out = os.fspath(out_path)
    shown = list(trends)[: int(max_units)]
    by_unit = {}
    for m in measurements:
        by_unit.setdefault(m.unit, []).append(m)
    date = fleet_report_date()
    ctx = FleetContext(
        trends=trends,
        shown=shown,
        measurements=measurements,
        by_unit=by_unit,
        limits=limits,
        database=database,
        date=date,
        links=dict(links or {}),
    )
    meta = {
        "Title": "vibkit fleet report",
        "Author": f"vibkit {__version__}",
        "Subject": "escalator step-chain elongation: work list and trends",
        "Creator": f"vibkit {__version__}",
        "CreationDate": date,
        "ModDate": date,
    }
    with matplotlib.rc_context(
        {
            "pdf.compression": 6,
            "font.size": 7,
            "axes.titlesize": 8,
            "svg.hashsalt": "vibkit",
            "path.simplify": True,
            "axes.unicode_minus": False,
        }
    ):
        with atomic_path(out, ".pdf") as tmp, PdfPages(tmp, metadata=meta) as pdf:
            doc = PageSink(pdf)
            fleet_page(doc, ctx)
    return Report(out, doc.pages, summary={"units": len(trends), "units_drawn": len(shown)})
