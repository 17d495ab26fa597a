"""One page per escalator ride that :func:`vibkit.diagnose.rides.find_rides` finds in a phone's walk: the line
that makes it a ride, where in the still span it stands, and what the ride says of the chain."""

from __future__ import annotations

import textwrap

from ..rides import find_rides, ride_evidence
from ..rounding import fmt_pm
from .common import _PAGE, _page_title

__all__ = ["phone_ride_pages", "phone_rides_absent", "phone_rides_summary"]

#: the last search, by the report it was made for: page 1 asks why pages are absent before they are drawn
_LAST = {}


def _search(ctx):
    """(RideSearch or None, why there is none): the rides in the report's recording, searched once per report."""
    key = id(ctx)
    if key not in _LAST:
        _LAST.clear()
        rec = getattr(ctx, "rec", None)
        if rec is None or str(rec.attrs.get("reader", "")).startswith("vibkit.simulate"):
            found = (None, "not a phone recording of a walk (a simulation)")
        else:
            try:
                pitch = getattr(ctx, "nominal_pitch", None)
                profile = getattr(ctx, "profile", None)
                rated = getattr(profile, "speed", None) if profile is not None else None
                found = (find_rides(rec, nominal_pitch=pitch, rated_speed=rated), "")
            except ValueError as exc:
                found = (None, f"not a phone recording of a walk ({' '.join(str(exc).split())})")
        _LAST[key] = (ctx, found)
    return _LAST[key][1]


def phone_rides_absent(ctx) -> str:
    """Why the report has no ride page ("" when it has one)."""
    search, why = _search(ctx)
    if search is None:
        return why
    if search.rides:
        return ""
    spans = len(search.still_spans)
    return (
        f"no {ctx.unit_kind} ride in the recording: {spans} still span(s) of 6 s or more, none with a steady line in "
        f"{search.band_hz[0]:.3g}-{search.band_hz[1]:.3g} Hz"
        if spans
        else f"no {ctx.unit_kind} ride in the recording: the person never stood still for 6 s"
    )


def phone_rides_summary(ctx) -> list:
    """Page 1's lines on the rides found in a phone's walk (none when the recording is no walk with rides)."""
    search, _ = _search(ctx)
    if search is None or not search.rides:
        return []
    out = []
    for k, r in enumerate(search.rides, 1):
        speed = "" if r.speed_m_s is None else f", chain speed {fmt_pm(r.speed_m_s, r.speed_sigma_m_s)} m/s"
        told = (
            f"link pass {fmt_pm(r.link_pass_hz, r.link_pass_sigma_hz)} Hz"
            if r.link_pass_hz is not None
            else "two steady lines (" + " and ".join(f"{f:.3f}" for f in r.lines_hz) + " Hz): the link pass not told"
        )
        out.append(f"ride {k}: {r.start_s:.1f}-{r.end_s:.1f} s, {r.direction}: {told}{speed}")
    return out


def phone_ride_pages(doc, ctx) -> list:
    """One page per ride found (see the module's notes); the rides drawn."""
    import matplotlib.pyplot as plt

    search, _ = _search(ctx)
    if search is None or not search.rides:
        return []
    n = len(search.rides)
    for k, ride in enumerate(search.rides, 1):
        ev = ride_evidence(ctx.rec, ride, search)
        fig = plt.figure(figsize=_PAGE)
        heading = f"{ctx.unit_kind.capitalize()} ride {k} of {n}"
        _page_title(
            fig,
            heading,
            f"{ride.start_s:.1f}-{ride.end_s:.1f} s of the recording (stepping on to stepping off: still, or the line "
            "where the person stood at the landing first); "
            f"analysed {ride.line_start_s:.1f}-{ride.line_end_s:.1f} s, where the link-pass line stands clear of "
            "stepping on and off",
        )
        ax = fig.add_axes([0.1, 0.56, 0.84, 0.26])
        f, lv = ev["f"], ev["level_db"]
        sel = (f >= 0.5) & (f <= min(12.0, f[-1]))
        ax.plot(f[sel], lv[sel], lw=0.7, color="0.2")
        ax.axvspan(*search.band_hz, color="tab:blue", alpha=0.07, label="band searched")
        if ride.link_pass_hz is not None:
            ax.axvline(
                ride.link_pass_hz, color="tab:red", lw=0.8, ls="--", label=f"link pass {ride.link_pass_hz:.3f} Hz"
            )
        for f_line, style in zip(ride.lines_hz, ("--", ":")):
            ax.axvline(f_line, color="tab:orange", lw=0.8, ls=style, label=f"steady line {f_line:.3f} Hz")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("level over the floor [dB]\n(all axes together)")
        ax.set_title("Spectrum of the ride: the axes' mean periodogram over its running-median floor", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        ax2 = fig.add_axes([0.1, 0.3, 0.84, 0.17])
        ax2.plot(ev["track_s"], ev["track_db"], marker=".", lw=0.8, color="tab:red")
        ax2.axvspan(ride.line_start_s, ride.line_end_s, color="tab:green", alpha=0.1, label="analysed")
        ax2.axhline(3.0, color="0.5", lw=0.6, ls=":", label="3 dB: the line there")
        ax2.set_xlabel("time [s, the recording's own]")
        ax2.set_ylabel("line level [dB]")
        ax2.set_title("The line's level in 4 s windows across the still span", fontsize=9)
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7, loc="lower center")
        told = (
            f"Link pass {fmt_pm(ride.link_pass_hz, ride.link_pass_sigma_hz)} Hz, {ride.level_db:.1f} dB over the floor "
            if ride.link_pass_hz is not None
            else "Two steady lines, "
            + " and ".join(f"{f:.3f} Hz ({d:.1f} dB)" for f, d in zip(ride.lines_hz, ride.lines_db))
            + ", neither a harmonic of the other: which is the chain's link pass the record cannot tell, so none is "
            "given "
        )
        lines = [
            told
            + f"(false-alarm bound {search.p_fa:g}: p <= {ride.p_value:.1g}); the most evidence on {ride.channel}.",
            f"Direction: {ride.direction}"
            + (
                f" (vertical speed {fmt_pm(ride.vertical_speed_m_s, ride.vertical_speed_sigma_m_s)} m/s, "
                f"{ride.rise_source})."
                if ride.vertical_speed_m_s is not None
                else " (no barometer: up or down cannot be told)."
            ),
        ]
        if ride.flag:
            lines.append(f"Not ruled out: {ride.flag}.")
        if ride.speed_m_s is not None:
            lines.append(
                f"Chain speed from the link pass and the nominal pitch: {fmt_pm(ride.speed_m_s, ride.speed_sigma_m_s)} m/s"
                + (
                    f", {fmt_pm(ride.speed_deviation_percent, ride.speed_deviation_sigma_percent, sign=True)} % from "
                    "the rated speed (EN 115-1 allows +-5 %)"
                    if ride.speed_deviation_percent is not None
                    else ""
                )
                + (
                    f"; incline {fmt_pm(ride.incline_deg, ride.incline_sigma_deg)} deg."
                    if ride.incline_deg is not None
                    else "."
                )
            )
        else:
            lines.append("No nominal pitch: no speed (the profile's or --nominal-pitch gives one).")
        lines.append(
            "No elongation verdict from a phone: the pitch needs the speed measured better than the elongation "
            "sought (a tachometer on a step, or the tensioner sensor); a rated speed is known to +-5 % only."
        )
        fig.text(
            0.06,
            0.2,
            "\n".join(textwrap.fill(x, 115) for x in lines),
            fontsize=7.5,
            va="top",
        )
        doc.emit(fig, heading)
    return list(search.rides)
