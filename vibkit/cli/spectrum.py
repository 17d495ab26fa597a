"""``vibkit spectrum``: link-pass fundamental and harmonic peak table of a recording."""

from __future__ import annotations

import textwrap

from vibkit.diagnose.rounding import fmt_band, fmt_pm

from .options import (
    CHANNEL_EVERY,
    LINKS_WANDER_HELP,
    add_command,
    add_escalator,
    add_json,
    add_limits,
    add_links,
    add_recording,
    add_speed_uncertainty,
    band,
    escalator_profile,
    harmonics,
    read_recording,
)
from .output import in_file, msg, print_json, shown, table
from .pitch import (
    add_speed_options,
    print_channels,
    print_pitch,
    refused,
    speed_source,
    speed_text,
)
from .settings import profile_note, run_settings

EPILOG = (
    "example:\n  vibkit spectrum data/field/leon-tensioner.csv --band 2.5:6 --json\n"
    "with a speed (--speed, --escalator's or the file's) the same decision as `vibkit pitch`:\n"
    "the same pitch, elongation and verdict (exit 0, 1 or 3);\n"
    "without one the frequency only (search band 2.5-6 Hz)"
)


def add_parser(subparsers):
    s = add_command(subparsers, "spectrum", "link-pass fundamental and harmonic peak table of a recording", EPILOG)
    add_recording(s, channel_default=CHANNEL_EVERY)
    add_json(s)
    s.add_argument(
        "--band",
        type=band,
        help="search band of the link-pass LOW:HIGH [Hz] (default speed / 80-200 mm, or 2.5:6 without a speed)",
    )
    s.add_argument("--harmonics", type=harmonics, default=5, help="harmonics listed (default 5)")
    add_speed_options(s, "chain speed (optional; gives the pitch as `vibkit pitch` does)")
    add_speed_uncertainty(s)
    add_limits(s)
    add_escalator(s)
    add_links(s, LINKS_WANDER_HELP)
    s.set_defaults(func=run)
    return s


def _common_line(a, res, line, rec):
    """A phone's one steady line, found on its axes together, a second clear of each end (stepping on and off): the
    frequency only (no speed was given); the channels' own harmonic families listed beside it."""
    from vibkit.diagnose.rides import common_line_names

    names = common_line_names(rec)
    best = names[line.strongest_channel]
    reason = (
        f"one steady line common to the axes {', '.join(names)} at {fmt_pm(line.frequency_hz, line.sigma_hz)} Hz, "
        f"{line.level_db:.1f} dB over the floor (p <= {line.p_value:.1g}), a second clear of each end: a ride's link "
        "pass (`vibkit rides`), or a tone"
    )
    if a.json:
        print_json(
            "spectrum",
            {
                "status": "ok",
                "reason": reason,
                "exit_code": 0,
                "file": shown(a.recording),
                "channel": best,
                "band_hz": list(line.band),
                "speed_m_s": None,
                "method": "steady line common to the axes",
                "fundamental_hz": line.frequency_hz,
                "fundamental_sigma_hz": line.sigma_hz,
                "common_line": {
                    "level_db": line.level_db,
                    "p_value": line.p_value,
                    "channels": dict(zip(names, line.channel_levels_db)),
                    "parts_hz": list(line.parts_hz),
                },
                "channels": res.per_channel(),
            },
        )
    else:
        print(f"{shown(a.recording)}: axes {', '.join(names)} together")
        print(
            f"link-pass fundamental {fmt_pm(line.frequency_hz, line.sigma_hz, 'Hz')} (search band {fmt_band(line.band)})"
        )
        print_channels(res)
        msg(textwrap.fill(f"note: {reason}", 100, subsequent_indent="  "))
    return 0


def _a_walk(a, rec):
    """A phone export's walk (its walking band up over a fifth of it): refused, no number; a line over a walk is the
    gait's or another machine's, and a ride in it is found by `vibkit rides` and analysed with --segment.  Other
    three-axis files (a wrist's logger, a machine's accelerometer) go on to the channels' own verdicts; a line common
    to their axes is given only where `find_rides` confirms it (:func:`~vibkit.diagnose.rides.unconfirmed_line`)."""
    from vibkit.diagnose.rides import WALK_FRACTION, walking_fraction

    w = walking_fraction(rec)
    if w is None or w < WALK_FRACTION:
        return None
    reason = (
        f"a walk, not a ride: the phone walks over {100 * w:.0f} % of it (a ride's span: under {100 * WALK_FRACTION:.0f} "
        "%), and a line over a walk is its gait's or another machine's; `vibkit rides` finds the rides in it, then "
        "give one as --segment START:END"
    )
    if a.json:
        print_json(
            "spectrum",
            {
                "status": "no link-pass found",
                "reason": reason,
                "exit_code": 1,
                "file": shown(a.recording),
                "walking_fraction": w,
            },
        )
    msg(f"vibkit spectrum: {shown(a.recording)}: no link-pass found: {reason}")
    return 1


def run(a):
    from vibkit.diagnose.channels import estimate_channels
    from vibkit.diagnose.rides import common_line, is_phone_recording, unconfirmed_line

    rec = read_recording(a)
    if a.channel is None and is_phone_recording(rec):  # every channel of a phone's export: a walk is no ride
        walk = _a_walk(a, rec)
        if walk is not None:
            return walk
    profile = escalator_profile(a)
    # with a speed the same settings as `vibkit pitch` (its speed and sigma, nominal pitch, band, teeth); without
    # one the band of a step chain's link pass
    settings = run_settings(a, rec, profile, frequency_only_band=True)  # a contradiction: the one line said
    sp = settings.speed
    speed, source = sp.value, (speed_source(sp) if sp.value is not None else None)
    if speed:
        profile_note(settings, profile)
    try:
        res = estimate_channels(
            rec,
            channel=a.channel,
            speed=speed or 1.0,
            speed_sigma=sp.sigma if speed else None,
            band=settings.band,
            n_harmonics=a.harmonics,
            nominal_pitch=settings.nominal_pitch if speed else None,
            limits_percent=settings.limits,
            teeth=settings.teeth,
            n_links=settings.n_links,
            links_per_step=settings.links_per_step,
            sensors=settings.sensors_by_channel,
            speed_source=source or "none",
            frequency_only=speed is None,
        )
    except ValueError as exc:  # the analysis's words about the signal, with the file named
        raise in_file(a.recording, exc) from None
    # a phone's axes together (a phone export, or three axes none of which shows a family alone): the ride's one
    # line, clear of stepping on and off, as `vibkit rides` reads it; never over channels that disagree
    not_a_ride = None
    if not speed and (is_phone_recording(rec) or (res.best is None and res.status == "no link-pass found")):
        try:
            line = common_line(rec, tuple(res.estimates[0].band_hz))
        except ValueError as exc:  # the signal's words, with the file named
            raise in_file(a.recording, exc) from None
        if line is not None and line.detected:
            why = unconfirmed_line(rec, line.frequency_hz, line.band)  # a phone, or any three axes of acceleration
            if why is None:
                return _common_line(a, res, line, rec)
            not_a_ride = f"a steady line at {fmt_pm(line.frequency_hz, line.sigma_hz)} Hz on the axes together: {why}"
    if res.best is None:
        e0 = res.estimates[0]
        extra = {"file": shown(a.recording), "units": e0.extra.get("units", "1"), "band_hz": list(e0.band_hz)}
        if not_a_ride:
            extra["not_a_ride"] = not_a_ride
            msg(textwrap.fill(f"note: {not_a_ride}", 100, subsequent_indent="  "))
        return refused("spectrum", a, res, extra, speed_known=bool(speed))
    est = res.best
    ch, units = est.channel, est.extra.get("units", "1")
    peaks = [
        {
            "order": h["order"],
            "frequency_hz": h["frequency_hz"],
            "amplitude": h["amplitude"],
            "units": units,
            "detected": h["detected"],
        }
        for h in est.harmonics
    ]
    payload = {
        "status": res.status,
        "reason": res.reason,
        "exit_code": res.exit_code,
        "file": shown(a.recording),
        "channel": ch,
        "units": units,
        "band_hz": list(est.band_hz),
        "speed_m_s": speed,
        "speed_source": source,
        "method": est.method,
        "method_reason": est.method_reason,
        "detection": est.detection,
        "invalid_samples": est.invalid_samples,
        "fundamental_hz": est.fundamental_hz,
        "fundamental_sigma_hz": est.fundamental_sigma_hz,
        "snr_db": est.snr_db,
        "peaks": peaks,
        "channels": res.per_channel(),
        "warnings": est.warnings,
        **est.pitch_fields(),  # with a speed: the pitch, elongation and verdict, as `vibkit pitch` names them
    }
    if a.json:
        print_json("spectrum", payload)
    else:
        print(f"{shown(a.recording)}: channel {ch} [{units}]" + (f", speed {speed_text(est)}" if speed else ""))
        print(
            f"link-pass fundamental {fmt_pm(est.fundamental_hz, est.fundamental_sigma_hz, 'Hz')} "
            f"(search band {fmt_band(est.band_hz)})"
        )
        if speed:
            print_pitch(est)
            print()
        print_channels(res)
        print(
            table(
                [
                    [p["order"], f"{p['frequency_hz']:.4f}", f"{p['amplitude']:.4g}", "yes" if p["detected"] else "no"]
                    for p in peaks
                ],
                ("order", "frequency [Hz]", f"amplitude [{units}]", "detected"),
            )
        )
        for w in (w for w in est.warnings if not w.startswith(f"{res.status}: ")):  # said last, once
            msg(textwrap.fill(f"warning: {w}", 100, subsequent_indent="  "))
        for n in est.notes if speed else []:  # a frequency-only estimate's notes are about its placeholder speed
            msg(textwrap.fill(f"note: {n}", 100, subsequent_indent="  "))
        if res.status != "ok":
            msg(textwrap.fill(f"vibkit spectrum: {res.status}: {res.reason}", 100, subsequent_indent="  "))
    return res.exit_code
