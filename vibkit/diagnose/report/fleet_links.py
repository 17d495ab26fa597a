"""The fleet report's links pages: per unit, the links that the latest visit's scan flagged (number, excess pitch
with its sigma, the loops that show it), which marked link came back worse or is new since the previous visit, and
the statement of what the numbers can be matched with; units without any link scan are listed by the reason.

The page reads what ``vibkit fleet status`` prints (:func:`vibkit.fleet.links_history`, one ``UnitLinks`` per
unit, passed in by the caller: this layer does not import the fleet) and lays it out in lines of text, one block
per unit, a block never split across two pages.
"""

from __future__ import annotations

import textwrap

from ..rounding import fmt_pm
from .common import _WIDE

__all__ = ["fleet_links_pages", "scan_advice", "LINKS_HEADER"]

#: the columns of a unit's links (the fleet report's links pages)
LINKS_HEADER = ("link", "verdict", "excess pitch [mm]", "loops", "since the previous visit")
_COLUMNS_X = (0.06, 0.125, 0.215, 0.345, 0.435)  # figure x of each column (a link may read "155 or 110")
_VERDICT_COLORS = {"worse": "#b2182b", "new": "#e0661b"}
_TOP, _BOTTOM, _STEP = 0.89, 0.08, 0.0175  # figure y of the first and last line, and the line step
_WRAP = 175  # characters of a wrapped line at 7 pt across the page
_DETAIL_WRAP = 110  # characters of a row's detail column at 7 pt
_MEANING = (
    "worse: the link's excess pitch grew by more than 2 combined sigmas since the previous visit that counts from "
    "the marked link; new: flagged now, not then (none of its numbers). '55 or 10': the recording cannot tell which of "
    "the two it is (look at both); an earlier flag sharing a number is the same link. A link number names a physical link only when the recordings "
    "count from a marked link (the catalogue's marker_s): without one, link 1 is whichever link was at the sensor "
    "when the recording started, and the numbers of two visits cannot be matched."
)


def _mm(v, s):
    """An excess pitch [m] in mm: to two significant digits of its sigma (the one rule of every +-), else 0.01 mm."""
    if v is None:
        return "-"
    return fmt_pm(1e3 * v, 1e3 * s, sign=True) if s else f"{1e3 * v:+.2f}"


def _block(hist):
    """The lines of one unit: (kind, payload) with kind ``head``, ``text``, ``header`` or ``row``."""
    m, s = hist.visits[-1]
    scanned = [(mm, ss) for mm, ss in hist.visits if ss.scanned]
    if scanned:
        m_s, s_s = scanned[-1]
        one = "from the marked link" if s_s.marker_s is not None else "from the link at the sensor at the start"
        head = (
            f"{hist.unit}: latest link scan {m_s.date_utc[:10]}: {s_s.loops} loops of {s_s.n_links} links, "
            f"{len(s_s.flagged)} flagged, numbered {one}"
        )
    else:
        head = f"{hist.unit}: no link scan; latest visit {m.date_utc[:10]}: {s.status}"
    lines = [("head", head)]
    lines += [("text", t) for t in textwrap.wrap(hist.statement, _WRAP)]
    if hist.links:
        lines.append(("header", LINKS_HEADER))
        for h in hist.links:
            now = h.visits[-1] if h.visits else None
            flagged_now = now is not None and now.flagged
            excess = _mm(now.excess_pitch_m, now.sigma_m) if flagged_now else "-"
            loops = ",".join(str(i) for i in now.loops) if flagged_now and now.loops else "-"
            # the detail whole: what does not fit its column goes on lines under it
            detail, *more = textwrap.wrap(h.detail, _DETAIL_WRAP) or [""]
            lines.append(("row", (h.label, h.verdict, excess, loops, detail)))
            lines += [("detail", t) for t in more]
    elif scanned:
        lines.append(("text", "no link flagged on the latest scan"))
    for mm, ss in hist.visits:  # stored numbers read otherwise (numbers of an older vibkit), said once a visit
        if ss.note:
            lines += [("text", t) for t in textwrap.wrap(f"{mm.date_utc[:10]}: {ss.note}", _WRAP)]
    return lines


def _draw(fig, y, kind, payload):
    if kind == "head":
        fig.text(0.04, y, payload, fontsize=8, fontweight="bold", ha="left", va="top")
    elif kind == "text":
        fig.text(0.06, y, payload, fontsize=7, color="0.3", ha="left", va="top")
    elif kind == "detail":  # a row's detail, continued under its column
        fig.text(_COLUMNS_X[-1], y, payload, fontsize=7, ha="left", va="top")
    else:
        bold = kind == "header"
        for x, cell in zip(_COLUMNS_X, payload):
            colour = "k" if bold else _VERDICT_COLORS.get(cell if x == _COLUMNS_X[1] else "", "k")
            fig.text(x, y, cell, fontsize=7, fontweight="bold" if bold else "normal", color=colour, va="top")


def scan_advice(scan) -> str:
    """What to do about a visit whose link scan did not give a map ("" where it did, or nothing is to be done):
    the elongation of the visit is stored whatever the scan gave."""
    if scan.status == "failed":
        return (
            "the visit's elongation is stored; mend what the reason names (the profile's chain.n_links, its "
            "rise, the recording) and scan the recording alone with vibkit links RECORDING --escalator PROFILE"
        )
    if scan.status == "too few loops":
        return "record at least two loops of the chain at the next visit (vibkit links says how long)"
    return ""


def fleet_links_pages(doc, ctx, title, subtitle) -> None:
    """The links pages of the fleet report (none when ``ctx.links`` is empty).

    ``title(fig, text, subtitle)`` draws a page's title; units come in the work list's order.  A unit whose
    visits have no link scan is listed under the reason of its latest visit."""
    links = getattr(ctx, "links", None) or {}
    if not links:
        return
    blocks, unscanned = [], {}
    for t in ctx.trends:
        hist = links.get(t.unit)
        if hist is None or not hist.visits:
            continue
        if hist.scanned:
            blocks.append(_block(hist))
        else:
            _, s = hist.visits[-1]
            advice = scan_advice(s)
            unscanned.setdefault(f"{s.status}: {s.reason}" + (f"; {advice}" if advice else ""), []).append(t.unit)
    if unscanned:
        lines = [("head", f"{sum(map(len, unscanned.values()))} unit(s) without a link scan on any visit")]
        for why, units in unscanned.items():
            lines += [("text", t) for t in textwrap.wrap(f"{', '.join(units)}: latest visit {why}", _WRAP)]
        blocks.append(lines)
    pages, page, used = [], [], 0
    room = int((_TOP - _BOTTOM) / _STEP)
    for b in blocks:
        need = len(b) + (1 if page else 0)
        if page and used + need > room:
            pages.append(page)
            page, used = [], 0
            need = len(b)
        page.append(b[:room])  # a block longer than a page is cut at its end (its unit's rows, worse first)
        used += need
    if page:
        pages.append(page)
    import matplotlib.pyplot as plt

    for k, page in enumerate(pages, 1):
        fig = plt.figure(figsize=_WIDE)
        part = f" ({k}/{len(pages)})" if len(pages) > 1 else ""
        title(fig, "Fleet: flagged links of the latest visit, worse or new since the previous one" + part, subtitle)
        y = _TOP
        for i, b in enumerate(page):
            if i:
                y -= _STEP
            for kind, payload in b:
                _draw(fig, y, kind, payload)
                y -= _STEP
        for j, line in enumerate(textwrap.wrap(_MEANING, _WRAP + 25)):
            fig.text(0.04, 0.05 - j * 0.016, line, fontsize=6.5, color="0.3", ha="left", va="top")
        doc.emit(fig, "fleet links")
