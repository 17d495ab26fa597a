"""The report's closing pages: data quality (what the reader found and decided) and the parameters
(everything needed to repeat the report)."""

from __future__ import annotations

import os
import textwrap

import numpy as np

from ..rounding import fmt_band
from .common import (
    _PAGE,
    TextColumn,
    _fmt,
    _page_title,
    _table,
    fmt_length,
    speed_sigma_source,
    speed_source,
    speed_value,
)

__all__ = ["data_quality_page", "parameters_page", "glossary_page", "GLOSSARY"]

#: the words of the report a field engineer may not know, each said once (the glossary page)
GLOSSARY = (
    (
        "link pass",
        "one chain link passing a fixed point (the sensor, a sprocket tooth). Its frequency is chain speed / link "
        "pitch: at 0.5 m/s and 133.33 mm, 3.75 times a second. Every chain-made vibration repeats at it or at its "
        "multiples (harmonics: 2x, 3x ...).",
    ),
    (
        "link pitch, elongation",
        "the distance between two link pins. A worn chain's pins and bushes wear, so its pitch grows: the "
        "elongation is the measured pitch over the nominal (new) pitch, less one, in per cent.",
    ),
    (
        "step pass",
        "one step passing the sensor: the link pass divided by the links per step (1/3 of it on a 3-link step).",
    ),
    (
        "delta",
        "the tensioner carriage's displacement towards the upper head [m]: the lower head slides so that the "
        "chain closes round its loop; it moves once per link pass as each link wraps onto the sprocket's polygon. "
        "A tensioner displacement sensor records it.",
    ),
    (
        "harmonic SNR",
        "power of the fitted link-pass harmonics over the power of what is left, per sample of the recording. It "
        "compares the whole family with all the broadband noise, so it reads far lower than a peak's height over "
        "the spectrum's floor (a line 60 dB over the floor can have a harmonic SNR of 5 dB).",
    ),
    (
        "+- (sigma)",
        "one standard deviation of a figure: about two times in three the truth lies within it. Every figure is "
        "rounded to its sigma.",
    ),
    (
        "Cramer-Rao",
        "the smallest sigma any unbiased estimator can reach on the given noise; vibkit's frequency sigma starts "
        "from it and is widened when the recording's parts disagree more than it allows.",
    ),
    (
        "Birge ratio",
        "how much the parts of a recording (its time slices) scatter compared with their own sigmas: about 1 "
        "when they agree; well over 1 means the frequency wanders (the speed changed), and the sigma is widened "
        "by it.",
    ),
    (
        "Hampel events (spikes)",
        "samples far outside the local median (a robust local scatter, judged in a sliding window) once the "
        "link-pass family is taken out: a knock, a blow, a loose part. On pure noise a few still pass by chance: "
        "page 1 gives how many chance alone gives at the detector's false-alarm rate.",
    ),
    (
        "order spectrum",
        "the spectrum after the signal is resampled at constant link-pass phase: order 1 is the link pass, "
        "order 2 its second harmonic, 1/3 the step pass of a 3-link step. A wandering speed no longer smears the "
        "lines.",
    ),
    (
        "not detected (< X)",
        "a harmonic whose peak does not stand out of the noise: its level is under X, and no interval is given.",
    ),
    (
        "scene",
        "vibkit's model of an escalator (chain, sprocket, tensioner, guide, sensor) that it simulates; a profile's "
        "scene is built from the unit's drawings (vibkit scene PROFILE).",
    ),
)


def data_quality_page(doc, ctx) -> None:
    """Samples, sample rate, bursts and gaps, time jitter, resampling, clipping, non-finite samples, and
    the reader's history."""
    import matplotlib.pyplot as plt

    rec, bursts = ctx.rec, ctx.bursts
    fig = plt.figure(figsize=_PAGE)
    _page_title(fig, "Data quality", "what the reader found and decided")
    ax = fig.add_axes((0.06, 0.55, 0.88, 0.36))
    gaps = [bursts[i + 1].t0 - (bursts[i].t0 + bursts[i].x.size / bursts[i].fs) for i in range(len(bursts) - 1)]
    rows = [
        ["samples", f"{rec.sizes['time']}"],
        ["nominal sample rate", f"{rec.attrs.get('sample_rate_hz', 0):.6g} Hz"],
        ["bursts", f"{len(bursts)}"],
        ["gaps", (f"{len(gaps)}, {min(gaps):.4g} to {max(gaps):.4g} s" if gaps else "none")],
        ["time jitter (rms)", _jitter(float(rec.attrs.get("time_jitter_rms_percent", 0.0)))],
        ["resampled to a uniform grid", "yes" if any(b.resampled for b in bursts) else "no"],
        ["clipping", f"{ctx.clip_n} samples held at the extremes" + (" (suspected)" if ctx.clipped else "")],
        ["non-finite samples", f"{int(np.sum(~np.isfinite(rec[ctx.channel].values)))}"],
    ]
    _table(ax, rows, (0.4, 0.6), 9)
    hist = str(rec.attrs.get("history", "")).split("\n")
    fig.text(0.06, 0.5, "Reader's decisions:", fontsize=10, fontweight="bold")
    fig.text(0.06, 0.48, "\n".join(textwrap.fill("- " + h, 100) for h in hist[:20]), fontsize=8, va="top")
    doc.emit(fig, "data quality")


def parameters_page(doc, ctx) -> None:
    """The options as resolved (speed, pitch, limits, band, spike detector, duration) and the scene's text."""
    import matplotlib.pyplot as plt

    pitch, sc, duration = ctx.pitch, ctx.scene, ctx.duration
    fig = plt.figure(figsize=_PAGE)
    _page_title(fig, "Parameters", "everything needed to repeat this report")
    sigma_from = speed_sigma_source(ctx)  # a row of its own: beside the speed's source it overflowed the cell
    rows = [
        ["channel", ctx.channel],
        ["chain speed", speed_value(ctx)],
        ["speed from", _fit(_short_paths(speed_source(ctx), ctx))],
        *([["speed sigma from", _fit(_short_paths(sigma_from, ctx))]] if sigma_from else []),
        ["nominal pitch", fmt_length(ctx.nominal_pitch) if ctx.nominal_pitch else "not given"],
        ["limits", " / ".join(f"{v:g} %" for v in ctx.limits)],
        ["search band", _band(pitch.band_hz if pitch else ctx.band)],
        ["Hampel half window", f"{ctx.hampel_half_window_s:g} s"],
        ["Hampel false-alarm rate", f"{ctx.hampel_false_alarm_rate:g} per sample"],
        ["simulated duration", "no simulation" if sc is None else _fmt(duration, "s") if duration else "the scene's"],
    ]
    links = getattr(ctx, "links", None)
    if links is not None:  # how the link numbers count: from a marked link, or from the one at the start
        rows.append(
            [
                "link numbers",
                f"from the link marked at {links.marker_s:g} s (--marker)"
                if links.marker_s is not None
                else "from the link at the sensor at the start",
            ]
        )
    res = getattr(ctx, "result", None)
    if res is not None and "solver_method" in res.attrs:
        # the simulation's numerics: its solver, and the convergence verdict ([solver] check = true)
        steps = res.attrs.get("solver_steps")
        rows.append(["solver", f"{res.attrs['solver_method']}" + (f", {steps} steps" if steps is not None else "")])
        if "solver_closure" in res.attrs:
            rows.append(
                [
                    "chain closure",
                    _fit(
                        "read from the table over one pitch"
                        if res.attrs["solver_closure"] == "table"
                        else f"solved at every step: {str(res.attrs['solver_closure']).split(' (')[0]}"
                    ),
                ]
            )
        if "convergence" in res.attrs:
            import json

            conv = json.loads(res.attrs["convergence"])
            rows.append(["converged", _fit(conv["message"])])
        else:
            rows.append(["converged", "not checked (set [solver] check = true)"])
    ax = fig.add_axes((0.06, 0.62, 0.88, 0.3))
    _table(ax, rows, (0.4, 0.6), 9)
    if sc is None:
        doc.emit(fig, "parameters")
        return
    # every line of the scene, long ones wrapped (a cut line cannot repeat the report), on as many pages as it takes
    lines = []
    for ln in sc.text.splitlines():
        if ln.strip() and not ln.lstrip().startswith("#"):
            lines += textwrap.wrap(ln, _WIDTH, subsequent_indent="      ", break_long_words=True) or [ln]
    name = os.path.basename(sc.source)
    built = " (scene built from the profile)"
    if name.endswith(built):  # the profile's scene, in memory: the command that writes it to a file
        name = name[: -len(built)]
        heading = f"Scene built from the {ctx.unit_kind} profile {name} (vibkit scene PROFILE -o FILE writes it):"
    else:
        heading = f"Scene {name}:"
    fig.text(0.06, 0.58, heading, fontsize=10, fontweight="bold")
    fig.text(0.06, 0.565, "\n".join(lines[:_LINES]), fontsize=6.5, family="monospace", va="top")
    doc.emit(fig, "parameters")
    rest = lines[_LINES:]
    while rest:
        fig = plt.figure(figsize=_PAGE)
        _page_title(fig, "Parameters (continued)", heading.rstrip(":"))
        fig.text(0.06, 0.9, "\n".join(rest[:_MORE_LINES]), fontsize=6.5, family="monospace", va="top")
        doc.emit(fig, "parameters (continued)")
        rest = rest[_MORE_LINES:]


#: the scene's lines the parameters page lists, their width in characters (a longer line goes on, indented, on the
#: next), and the lines a continuation page lists
_LINES, _WIDTH, _MORE_LINES = 48, 100, 85


#: characters a value cell of the parameters table holds at its font (9 pt, 0.6 of the table's width)
_CELL_CHARS = 58


def _fit(text):
    """A value cell's text, shortened at a word to what the cell holds (the whole text is in the JSON)."""
    return textwrap.shorten(text, _CELL_CHARS, placeholder=" [...]")


def _short_paths(text, ctx):
    """``text`` with the profile's and the scene's file paths given by their file names (the recording page
    names them in full)."""
    for obj in (getattr(ctx, "profile", None), getattr(ctx, "scene", None)):
        src = str(getattr(obj, "source", "") or "")
        if os.sep in src:
            text = text.replace(src, os.path.basename(src))
    return text


def _band(band):
    """A search band as the page shows it: "LOW - HIGH Hz", or the default it stands for."""
    if band is None:
        return "default: speed / 200 mm to speed / 80 mm"
    return fmt_band(band, " - ")


def _jitter(percent):
    """The time stamps' rms jitter in per cent of the sampling period, to two digits; under 0.001 % (a clock's
    rounding, 1e-10 % from stamps stored as floats) it is no jitter that matters."""
    if not percent > 1e-3:
        return "under 0.001 % of the period"
    return f"{percent:.2g} % of the period"


def glossary_page(doc, ctx) -> None:
    """The words of the report explained (:data:`GLOSSARY`)."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=_PAGE)
    _page_title(fig, "Glossary", "the words of this report, as a field engineer needs them")
    col = TextColumn(fig, x=0.07, y=0.9, width=0.86)
    for word, meaning in GLOSSARY:
        col.text(word, 10, weight="bold")
        col.text(meaning, 9)
        col.gap(0.008)
    doc.emit(fig, "glossary")
