"""``vibkit pitch``: link pitch (and elongation) from a recording's link-pass frequency and the chain speed."""

from __future__ import annotations

import math
import textwrap

from vibkit.diagnose.rounding import SPEED_SIGMA_NOT_STATED, fmt_band, fmt_length, fmt_pm

from .options import (
    CHANNEL_EVERY,
    LINKS_WANDER_HELP,
    add_command,
    add_escalator,
    add_json,
    add_limits,
    add_links,
    add_nominal_pitch,
    add_recording,
    add_speed,
    add_speed_uncertainty,
    band,
    escalator_profile,
    read_recording,
    teeth,
)
from .output import CLIError, in_file, msg, print_json, shown, table
from .settings import profile_note, run_settings

EPILOG = (
    "examples:\n  vibkit pitch data/field/leon-tensioner.csv --speed-uncertainty 0.1% \\\n"
    "      --nominal-pitch 133.33mm\n"
    "  vibkit pitch logger.txt --sample-rate 2050 --speed 52cm/s --json\n"
    "exit status: 0 verdict (or pitch), 1 no link-pass found / implausible / bad input,\n"
    "  2 usage error, 3 inconclusive (frequency and sigma given, no verdict)"
)


def add_parser(subparsers):
    s = add_command(
        subparsers, "pitch", "link pitch from a recording's link-pass frequency and the chain speed", EPILOG
    )
    add_recording(s, channel_default=CHANNEL_EVERY)
    add_json(s)
    add_speed_options(s)
    add_speed_uncertainty(s)
    add_limits(s)
    s.add_argument(
        "--band",
        type=band,
        help="search band LOW:HIGH [Hz] (default speed / 80-200 mm; with --escalator around its link pass)",
    )
    s.add_argument(
        "--teeth", type=teeth, help="sprocket teeth, for the shaft hypothesis (default the profile's, else 28)"
    )
    add_escalator(s)
    add_links(s, LINKS_WANDER_HELP)
    s.set_defaults(func=run)
    return s


def add_speed_options(s, what="chain speed measured on the steps"):
    """--speed and --nominal-pitch of ``pitch`` and ``spectrum`` (resolved with the rest of the run's settings,
    :func:`vibkit.cli.settings.run_settings`)."""
    add_speed(s, "the --escalator profile's, else the speed the file states, e.g. chain_speed_m_s", what)
    add_nominal_pitch(s, "the --escalator profile's", ": gives elongation and verdict")


def require_speed(a, settings):
    """The run's speed (``settings.speed``), else a CLIError: ``pitch`` needs one."""
    if settings.speed.value is not None:
        return settings.speed
    raise CLIError(
        f"{shown(a.recording)}: the file states no chain speed; give --speed (e.g. --speed 0.5 or --speed 50cm/s)"
    )


def speed_source(sp):
    """Where the speed came from, as the result names it: ``--speed`` for the flag."""
    return "--speed" if sp.source == "given" else sp.source


def run(a):
    from vibkit.diagnose.channels import estimate_channels

    rec = read_recording(a)
    profile = escalator_profile(a)
    settings = run_settings(a, rec, profile)  # a --links the profile contradicts: the one line said
    sp = require_speed(a, settings)
    profile_note(settings, profile)
    try:
        res = estimate_channels(
            rec,
            channel=a.channel,
            speed=sp.value,
            speed_sigma=sp.sigma,
            band=settings.band,
            nominal_pitch=settings.nominal_pitch,
            limits_percent=settings.limits,
            teeth=settings.teeth,
            n_links=settings.n_links,
            links_per_step=settings.links_per_step,
            sensors=settings.sensors_by_channel,
            speed_source=speed_source(sp),
        )
    except ValueError as exc:  # the analysis's words about the signal, with the file named
        raise in_file(a.recording, exc) from None
    if res.best is None:
        return refused("pitch", a, res, {"file": shown(a.recording)}, speed_known=sp.value is not None)
    est = res.best
    if a.json:
        d = est.as_dict()
        d.update(
            file=shown(a.recording),
            status=res.status,
            reason=res.reason,
            exit_code=res.exit_code,
            channels=res.per_channel(),
        )
        print_json("pitch", d)
        return res.exit_code
    print(f"{shown(a.recording)}: channel {est.channel}, speed {speed_text(est)}")
    print(
        f"link-pass frequency  {fmt_pm(est.fundamental_hz, est.fundamental_sigma_hz, 'Hz')} "
        f"({len(est.per_burst)} burst(s))"
    )
    print(f"method               {est.method}")
    print_pitch(est)
    print()
    print_channels(res)
    print(
        table(
            [
                [
                    h.name,
                    f"{h.frequency_hz:.4f}",
                    "n/a" if math.isnan(h.snr_db) else f"{h.snr_db:z.0f}",
                    f"{1000 * h.implied_pitch_m:.2f}",
                    f"{1000 * h.nearest_catalogue_m:.2f} ({h.deviation_percent:+.1f} %)",
                    "<-" if h.chosen else "",
                ]
                for h in est.hypotheses
            ],
            ("hypothesis", "link pass [Hz]", "peak/floor [dB]", "pitch [mm]", "catalogue [mm]", ""),
        )
    )
    msg("note: peak/floor: the spectrum's power at the frequency over its median floor (not the harmonic SNR)")
    for h in est.hypotheses:  # the reasons under the table: it stays within 100 columns
        print(textwrap.fill(f"{h.name}: {h.reason}", 100, subsequent_indent="    "))
    print()
    print(
        table(
            [
                [h["order"], f"{h['frequency_hz']:.4f}", f"{h['amplitude']:.4g}", "yes" if h["detected"] else "no"]
                for h in est.harmonics
            ],
            ("order", "frequency [Hz]", f"amplitude [{est.extra['units']}]", "detected"),
        )
    )
    for w in (w for w in est.warnings if not w.startswith(f"{res.status}: ")):  # said last, once
        msg(textwrap.fill(f"warning: {w}", 100, subsequent_indent="  "))
    for n in est.notes + [f"method {est.method}: {est.method_reason}"]:
        msg(textwrap.fill(f"note: {n}", 100, subsequent_indent="  "))
    if res.status != "ok":
        msg(textwrap.fill(f"vibkit pitch: {res.status}: {res.reason}", 100, subsequent_indent="  "))
    return res.exit_code


def speed_text(est):
    """``0.500 +- 0.014 m/s (escalator profile E12, rated)``, or without a stated sigma
    ``0.5 m/s (--speed; speed uncertainty not stated: --speed-uncertainty)``."""
    if est.speed_sigma_stated:
        return f"{fmt_pm(est.speed_m_s, est.speed_sigma_m_s, 'm/s')} ({est.speed_source})"
    return f"{est.speed_m_s:g} m/s ({est.speed_source}; {SPEED_SIGMA_NOT_STATED}: --speed-uncertainty)"


def print_pitch(est):
    """The link pitch and (with a nominal pitch) the elongation, its verdict and the limits: ``pitch`` and
    ``spectrum`` with a speed; without a stated speed uncertainty no +- (the frequency's part is a lower bound)."""
    stated = est.speed_sigma_stated
    if stated:
        print(f"link pitch           {fmt_length(est.pitch_m, est.pitch_sigma_m)}")
    else:  # the frequency's part is a lower bound: the value to its digits, no +-
        print(f"link pitch           {1000 * est.pitch_m:.2f} mm ({SPEED_SIGMA_NOT_STATED})")
    if est.nominal_pitch_m is not None:
        el = (
            fmt_pm(est.elongation_percent, est.elongation_sigma_percent, "%", sign=True)
            if stated
            else f"{est.elongation_percent:+z.2f} % ({SPEED_SIGMA_NOT_STATED})"
        )
        print(
            f"elongation           {el} of {1000 * est.nominal_pitch_m:.2f} mm -> {est.verdict}\n"
            f"                     (limits {' / '.join(f'{v:g}' for v in est.limits_percent)} %)"
        )


def print_channels(res):
    """The per-channel table (only when more than one channel was analysed)."""
    rows = res.per_channel()
    if len(rows) < 2:
        return
    print(
        table(
            [
                [
                    r["channel"],
                    r["status"],
                    fmt_pm(r["fundamental_hz"], r["fundamental_sigma_hz"]) if "fundamental_hz" in r else "-",
                    f"{1000 * r['pitch_m']:.2f}" if "pitch_m" in r else "-",
                    r.get("verdict") or "-",
                ]
                for r in rows
            ],
            ("channel", "status", "link pass [Hz]", "pitch [mm]", "verdict"),
        )
    )
    print()


def refused(cmd, a, res, extra, speed_known=False):
    """No usable link pass on any channel: say so (JSON with the status and reason, no number), exit 1."""
    ests = res.estimates
    if a.json:
        d = (
            ests[0].as_dict()
            if len(ests) == 1 and not res.errors
            else {
                "speed_m_s": ests[0].speed_m_s,
                "speed_source": ests[0].speed_source,
                "band_hz": list(ests[0].band_hz),
            }
        )
        d.update(extra)
        d.update(status=res.status, reason=res.reason, exit_code=res.exit_code, channels=res.per_channel())
        print_json(cmd, d)
    else:
        names = ", ".join(e.channel for e in ests)
        print(f"{shown(a.recording)}: channel{'s' if len(ests) > 1 else ''} {names}: {res.status}")
        print_channels(res)
    band = ests[0].band_hz
    hint = ""
    if not (speed_known or getattr(a, "speed", None) or getattr(a, "escalator", None) or getattr(a, "band", None)):
        hint = (
            " (the band searched without a speed: it misses a 101.6 mm chain above 0.6 m/s; give --speed, "
            "--escalator or --band)"
        )
    msg(f"vibkit {cmd}: {res.status} in {fmt_band(band)}{hint}: {res.reason}")
    return res.exit_code
