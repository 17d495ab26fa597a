"""The report's opening pages: page 1, the verdict (the unit, the measurement date, the recording, the
verdict in large type and colour with its uncertainty, at the same size whatever makes it unreliable,
then the evidence), and page 2, the recording and the escalator (checksum, reader, scene, provenance).

Page 1 draws whatever verdict fields the estimate carries (``status``, ``verdict``, ``reason``,
``warnings``), so that a new status of :mod:`vibkit.diagnose.pitch` shows without a change here.
"""

from __future__ import annotations

import math
import textwrap

from ... import __version__
from ..decision import SIGMA_TOO_LARGE
from .common import (
    _PAGE,
    HARMONIC_SNR,
    HARMONIC_SNR_DEFINITION,
    PITCH_RATIO,
    PITCH_RATIO_DEFINITION,
    TextColumn,
    _page_title,
    elongation_figure,
    fmt_length,
    fmt_pm,
    pitch_figure,
    speed_figure,
)
from .links_page import flag_label
from .rides_pages import phone_rides_summary

__all__ = ["verdict_page", "recording_page", "VERDICT_COLOURS"]

#: colour of each verdict (anything else: dark grey)
VERDICT_COLOURS = {"ok": "#1a7f37", "watch": "#9a6700", "plan replacement": "#d1570b", "replace": "#c62828"}
_GREY = "#555555"
_BIG = 26  # the verdict's type size, and the warnings' header's [pt]


def _headline(ctx):
    """(big text, colour, line under it) of the verdict."""
    pitch = ctx.pitch
    if not ctx.found:  # the shared decision refused: no link pass, or implausible
        status = str(ctx.summary.get("status") or "no link-pass found")
        why = str(ctx.summary.get("reason") or "")
        return status.upper(), _GREY, why or "no frequency, pitch or elongation can be given"
    status = str(getattr(pitch, "status", "ok") or "ok") if pitch is not None else "ok"
    reason = str(getattr(pitch, "reason", "") or "") if pitch is not None else ""
    if pitch is None:
        return (  # without a speed nothing tells a chain's link pass from any other family in the band
            f"FAMILY AT {fmt_pm(ctx.f0, None, 'Hz')}",
            _GREY,
            "a harmonic family in the band; no chain speed known, so not checked as a link pass: no pitch and no "
            "verdict (give --speed or --escalator)",
        )
    if status.lower() not in ("ok", ""):
        return status.upper(), _GREY, reason or "no verdict"
    pitch_text = pitch_figure(pitch)
    if pitch.verdict is None:
        return f"PITCH {pitch_text}", _GREY, "no nominal pitch given: no elongation verdict (--nominal-pitch)"
    el = elongation_figure(pitch)
    colour = VERDICT_COLOURS.get(str(pitch.verdict).lower(), _GREY)
    # the pitch and the nominal pitch are in the evidence below: each figure once
    under = (
        f"elongation {el} against the limits {' / '.join(f'{v:g}' for v in ctx.limits)} % "
        "(watch / plan / replace)"
    )  # an accepted decision's reason repeats this line: not shown
    return str(pitch.verdict).upper(), colour, under


#: where page 1's column starts and the lowest it may reach (figure fraction: under the page's header, above its
#: bottom edge), and the smallest scale of its type that it shrinks to when its text would run past the bottom
_TOP, _BOTTOM, _MIN_SCALE = 0.965, 0.025, 0.5


class _ScaledColumn(TextColumn):
    """A :class:`TextColumn` whose type sizes and gaps are all ``scale`` times those asked for."""

    def __init__(self, fig, *, scale, **kw):
        super().__init__(fig, **kw)
        self.scale = scale

    def gap(self, dy):
        super().gap(dy * self.scale)

    def text(self, text, size, **kw):
        super().text(text, size * self.scale, **kw)

    def pairs(self, rows, size, **kw):
        super().pairs(rows, size * self.scale, **kw)


def verdict_page(doc, ctx) -> None:
    """Page 1: who, when, what; the verdict; what makes it unreliable; the evidence.

    Drawn at full size, and again smaller where its text would run past the page's bottom (a verdict with its
    warnings, a worn link, the pages left out and the notes can be more than a page): every type size and gap
    shrinks by the share that fits, down to half size, so the page shows all of it and nothing is drawn off it."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=_PAGE)
    scale = 1.0
    for _ in range(6):
        col = _draw_verdict(fig, doc, ctx, scale)
        if col.y >= _BOTTOM or scale <= _MIN_SCALE:
            break
        # the height used scales about as the type (a smaller type wraps to fewer lines): shrink by what fits
        scale = max(_MIN_SCALE, scale * (_TOP - _BOTTOM) / (_TOP - col.y) * 0.97)
        fig.clf()
    doc.emit(fig, "verdict")


def _draw_verdict(fig, doc, ctx, scale):
    """Page 1's column drawn on ``fig`` at ``scale`` times its type sizes; returns the column (its ``y``: how far
    down it reached)."""
    pitch, summary = ctx.pitch, ctx.summary
    col = _ScaledColumn(fig, x=0.07, y=_TOP, width=0.86, scale=scale)
    col.text(f"{ctx.unit_kind.capitalize()} drive-chain diagnostic", 16, weight="bold")
    col.pairs(
        [
            (ctx.unit_kind, ctx.unit_text),
            ("measured", ctx.measurement_date_text),
            ("recording", f"{summary['file']}, channel {ctx.channel} [{ctx.units}]"),
            (
                "report",
                f"{ctx.date.strftime('%Y-%m-%d %H:%M')} UTC" + (" (SOURCE_DATE_EPOCH)" if ctx.date_fixed else ""),
            ),
        ],
        9.5,
        key_width=0.16,
    )
    col.gap(0.012)
    rides = phone_rides_summary(ctx)
    big, colour, under = _headline(ctx)
    if rides and not ctx.found:
        # a phone's walk whose rides carry the link pass: they are the headline; the whole walk's refusal (walking
        # included, no one record of the chain) is said under them, not as the verdict
        col.gap(0.002)
        _rides_block(col, ctx, rides, f"the whole walk, walking included: {big.lower()} (page 'spectrum')")
        rides = []
    else:
        col.text(big, _BIG, weight="bold", color=colour)
        col.text(under, 11, color=colour)
    warnings = list(getattr(pitch, "warnings", []) or []) if pitch is not None else []
    if not ctx.found:
        warnings = []  # the headline says it, with the reason
    elif pitch is not None:  # an inconclusive status and its reason are the headline: not a warning again under it
        status, reason = str(getattr(pitch, "status", "") or ""), str(getattr(pitch, "reason", "") or "")
        warnings = [w for w in warnings if w != f"{status}: {reason}"]
    col.gap(0.008)
    if warnings:
        col.text(f"{len(warnings)} WARNING{'S' if len(warnings) > 1 else ''}", _BIG, weight="bold", color="#b35900")
        col.text("the verdict may be unreliable: check these before acting", 11, color="#b35900")
        for w in warnings[:6]:
            col.text("- " + w, 10, weight="bold", color="#b35900")
        if len(warnings) > 6:
            col.text(f"... and {len(warnings) - 6} more (JSON: vibkit pitch --json)", 10, color="#b35900")
    elif ctx.found:
        col.text("no warning from the estimator", 11, color=_GREY)
    links = getattr(ctx, "links", None)
    if links is not None and links.flagged:  # the elongation is the chain's mean: a worn link is said here too
        n = len(links.flagged)
        col.gap(0.006)
        col.text(f"{n} WORN LINK{'S' if n > 1 else ''} FLAGGED", _BIG, weight="bold", color="#b35900")
        col.text(f"{flagged_links_text(links)} (page 'links')", 11, weight="bold", color="#b35900")
        col.text(
            "+- is the noise's part only; the worn-link signature is the model's, and its shape changes with the "
            f"excess (its relative error here: {_signature_error(links)}), which can move the excess read by up to "
            "that share of it",
            8,
            color="#b35900",
        )
    if rides:  # a phone's walk: the rides are what it says of the chain (the whole walk is no one record of it)
        col.gap(0.006)
        whole = "walk" if ctx.unit_kind == "escalator" else "recording"
        _rides_block(col, ctx, rides, f"the verdict above is the whole {whole}'s, walking included")
    col.gap(0.012)
    col.text("Evidence", 12, weight="bold")
    col.pairs(evidence_rows(ctx), 9, key_width=0.3)
    absent = absent_pages_text(getattr(doc, "absent", []))
    if absent:
        col.gap(0.006)
        col.text("Pages not in this report", 10, weight="bold")
        for line in absent:
            col.text(line, 8, color="0.2")
    notes = list(getattr(pitch, "notes", []) or []) if pitch is not None else []
    notes += [n for n in ctx.notes if not n.startswith("NO LINK-PASS")]
    if notes:
        col.gap(0.006)
        for n in notes[:5]:
            col.text("note: " + n, 8, color="0.3")
    return col


def _rides_block(col, ctx, rides, whole):
    """The rides of a phone's walk on page 1: how many, one line each, and what ``whole`` says of the walk."""
    kind = ctx.unit_kind
    col.text(
        # (a person's walk, of the phone: "recording" where the unit is itself a walk)
        f"{len(rides)} {kind.upper()} RIDE{'S' if len(rides) > 1 else ''} IN THIS "
        f"{'WALK' if kind == 'escalator' else 'RECORDING'}",
        _BIG,
        weight="bold",
    )
    for line in rides:
        col.text(line, 10, weight="bold")
    col.text(f"one page each ('{kind} ride k of n'); {whole}: the rides are the chain's evidence", 8, color=_GREY)


def _signature_error(links):
    """The worn-link signature's relative error of the flags (``0.15``), else ``n/a``."""
    errs = [f["signature_relative_error"] for f in links.flagged if f.get("signature_relative_error") is not None]
    return f"{max(errs):.2f}" if errs else "n/a"


def flagged_links_text(links):
    """``"link 55 or 115: +1.50 +- 0.02 mm; link 8: ..."`` of a :class:`vibkit.diagnose.links.LinksResult`."""
    return "; ".join(flag_label(f) for f in links.flagged)


def evidence_rows(ctx):
    """(what, value) rows of the evidence under the verdict: each figure once, rounded to its sigma."""
    pitch, comp, units = ctx.pitch, ctx.comparison, ctx.units
    rows = []
    if ctx.found:
        sig = pitch.fundamental_sigma_hz if pitch is not None else None
        method = f" ({pitch.method})" if pitch is not None and getattr(pitch, "method", "") else ""
        rows.append(("link-pass frequency", fmt_pm(ctx.f0, sig, "Hz") + method))
    if pitch is not None:
        rows.append(("chain speed", speed_figure(ctx)))
        rows.append(("link pitch = speed / frequency", pitch_figure(pitch)))
        if pitch.nominal_pitch_m is not None:
            rows.append(("nominal pitch", fmt_length(pitch.nominal_pitch_m)))
            status = str(getattr(pitch, "status", "ok") or "ok").lower()
            el = getattr(pitch, "elongation_percent", None)
            sigma_holds = SIGMA_TOO_LARGE in str(getattr(pitch, "reason", ""))  # known, only too large
            if status != "ok" and not sigma_holds and el is not None and math.isfinite(el):
                # a record that gives no verdict gives no sigma to trust either: the value to a tenth of a per
                # cent, said so (a stranger's step sensor read -0.52 +- 0.13 % of a new chain)
                rows.append(("elongation", f"about {el:+z.1f} % ({status}: no verdict, no sigma that holds)"))
            elif pitch.verdict is None or status != "ok":
                rows.append(("elongation", elongation_figure(pitch)))  # else it is under the verdict
        snr = getattr(pitch, "snr_db", None)
        if snr is not None and math.isfinite(snr):
            rows.append((HARMONIC_SNR, f"{snr:.0f} dB ({HARMONIC_SNR_DEFINITION})"))
    scale, shown = (1000.0, "mm") if units == "m" else (1.0, units)
    rows.append(("RMS / peak to peak", f"{ctx.rms * scale:.3g} / {ctx.p2p * scale:.3g} {shown}"))
    rows.append(("spikes", spikes_text(ctx)))
    rows.append(
        (
            "clipping",
            f"{ctx.clip_n} sample(s) held at the extreme values: "
            + (
                "suspected (more than 4)"
                if ctx.clipped
                else "not suspected (a clipped sensor holds its extreme for more than 4 samples in a row)"
            ),
        )
    )
    if ctx.summary.get("n_links") is not None:
        rows.append(("links in the chain", f"{ctx.summary['n_links']} ({ctx.summary['n_links_from']})"))
    links = getattr(ctx, "links", None)
    if links is not None and not links.flagged:  # a flagged link is in large letters above
        rows.append(("worn links", f"none flagged in {links.loops} loops of {links.n_links} links (page 'links')"))
    elif links is None and getattr(ctx, "links_note", ""):
        rows.append(("worn links", ctx.links_note))
    if comp is not None:
        rows.append(("pitch against the scene", scene_pitch_text(comp)))
        rows.append(
            (
                "spectra against the simulation",
                f"agreement score {comp.score:.2f} (1: every harmonic matches in frequency and "
                "amplitude, 0: none does; rule on page 'harmonics')",
            )
        )
    return rows


def spikes_text(ctx) -> str:
    """The spike count with what chance alone gives on as many samples of pure noise."""
    from scipy.stats import poisson

    n, mu = len(ctx.events), ctx.spikes_expected
    if not mu >= 0:  # nothing tested (bursts shorter than the detector's window)
        return f"{n} (Hampel events; page 'time signal')"
    most = int(poisson.ppf(0.99, mu))  # 99 % of noise-only records of this length give at most this many
    judged = (
        "more than chance gives: see page 'time signal'"
        if n > most
        else "no more than chance alone gives: no sign of a knock"
    )
    return (
        f"{n} Hampel events; chance alone gives about {mu:.2g} on these samples (at most {most} in 99 % of "
        f"records of pure noise): {judged}"
    )


def scene_pitch_text(comp) -> str:
    """The recording's pitch against the scene's, worded as a check of the scene: a scene that does not match
    is not a second fault of the chain."""
    ratio = f"{PITCH_RATIO} {fmt_pm(comp.pitch_ratio, comp.pitch_ratio_sigma)} ({PITCH_RATIO_DEFINITION})"
    if comp.pitch_consistent is None:
        return f"{ratio}: not judged, the recording's speed is not known (give --speed)"
    if comp.pitch_consistent:
        return f"{ratio}: the scene's chain has the recording's pitch"
    return (
        f"{ratio}: the scene's chain pitch differs from the recording's; the scene is not this chain as worn "
        "today. This judges the scene, not the chain (the verdict above is the recording's)"
    )


def absent_pages_text(absent) -> list:
    """Page 1's lines on the pages this report does not have, and why."""
    return [f"no {name} page: {why}" for name, why in absent]


def recording_page(doc, ctx) -> None:
    """Page 2: recording, checksum, reader, vibkit version, escalator, scene, sensor, provenance."""
    import matplotlib.pyplot as plt

    rec, sc, ch, summary = ctx.rec, ctx.scene, ctx.channel, ctx.summary
    fig = plt.figure(figsize=_PAGE)
    kind = ctx.unit_kind
    _page_title(fig, f"Recording and {kind}", f"what was measured, by what, and what describes the {kind}")
    col = TextColumn(fig, x=0.07, y=0.9, width=0.86)
    sha = str(rec.attrs.get("sha256", ""))
    col.pairs(
        [
            ("recording", summary["file"]),
            ("sha256", sha),
            ("reader", str(rec.attrs.get("reader", ""))),
            ("measured", ctx.measurement_date_text),
            ("report date (UTC)", ctx.date.strftime("%Y-%m-%d %H:%M")),
            ("vibkit version", __version__),
            (kind, ctx.unit_text),
            ("chain speed", speed_figure(ctx)),
            (
                "scene",
                (f"{sc.name} ({sc.analysis}; pitch {fmt_length(sc.chain.link_pitch)}, Z = {sc.sprocket.teeth})")
                if sc
                else "none",
            ),
            ("sensor channel", f"{ch} [{ctx.units}], {rec[ch].attrs.get('quantity', 'other')}"),
            ("provenance", str(rec.attrs.get("provenance", "not stated"))),
        ],
        9.5,
        key_width=0.22,
    )
    col.gap(0.02)
    col.text(
        textwrap.fill(
            "Generated by vibkit. Frequencies from harmonic least squares with Cramer-Rao standard deviations; "
            "pitch = speed / link-pass frequency; every number is rounded to its uncertainty. The same inputs "
            "give the same file when SOURCE_DATE_EPOCH fixes the report date.",
            100,
        ),
        8,
        color="0.35",
    )
    doc.emit(fig, "recording")
