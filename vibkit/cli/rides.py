"""``vibkit rides``: the escalator rides in a phone recording of a walk, and what each says of its chain."""

from __future__ import annotations

from vibkit.diagnose.rounding import fmt_pm

from .options import (
    add_command,
    add_escalator,
    add_json,
    add_nominal_pitch,
    add_recording,
    add_speed,
    band,
    escalator_profile,
    read_recording,
)
from .output import UsageError, msg, print_json, shown, table

EPILOG = (
    "examples:\n"
    "  vibkit rides advio-01/iphone                      # a folder of phone sensor files (or a zip)\n"
    "  vibkit rides accelerometer.csv --nominal-pitch 133.33mm --speed 0.5 --json\n"
    "a ride is a still span (walking stopped) that holds a steady line in the link-pass band; the line's\n"
    "frequency with its sigma, and with a nominal pitch the chain's actual speed (no elongation verdict:\n"
    "a phone gives no speed to judge the pitch against). A line where the barometer shows a lift's climb\n"
    "(faster than any escalator's) is refused, with the reason. Exit 0 with rides or without."
)


def add_parser(subparsers):
    s = add_command(
        subparsers, "rides", "the escalator rides in a phone recording of a walk: link pass, speed, direction", EPILOG
    )
    add_recording(s, channel=False)
    add_json(s)
    add_nominal_pitch(s, "the --escalator profile's; none: no speed", use="")
    add_speed(s, "the --escalator profile's rated speed", what="rated step speed (for the deviation, EN 115-1 +-5 %%)")
    s.add_argument(
        "--band",
        type=band,
        help="where the link pass may be LOW:HIGH [Hz] (default: rated speed / pitch +-10 %%, else 2.9:9)",
    )
    s.add_argument(
        "--false-alarm",
        type=float,
        default=1e-3,
        metavar="P",
        help="bound on the false-alarm probability of each still span's test (default 0.001)",
    )
    add_escalator(s)
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.diagnose.rides import find_rides

    if not 0 < a.false_alarm < 1:
        raise UsageError(f"--false-alarm {a.false_alarm:g}: expected a probability between 0 and 1")
    rec = read_recording(a)
    profile = escalator_profile(a)
    pitch = a.nominal_pitch if a.nominal_pitch is not None else (profile.nominal_pitch if profile else None)
    rated = a.speed if a.speed is not None else (profile.speed if profile else None)
    found = find_rides(rec, nominal_pitch=pitch, rated_speed=rated, band=a.band, p_fa=a.false_alarm)
    rides = [r.to_dict() for r in found.rides]
    src = shown(a.recording)
    if a.json:
        print_json(
            "rides",
            {
                "recording": a.recording,
                "band_hz": list(found.band_hz),
                "false_alarm": found.p_fa,
                "channels": list(found.channels),
                "nominal_pitch_m": pitch,
                "rated_speed_m_s": rated,
                "rides": rides,
                "still_spans": [{"start_s": t0, "end_s": t1, "verdict": v} for t0, t1, v in found.still_spans],
                "refused": [dict(x) for x in found.refused],
                "notes": list(found.notes),
            },
        )
        return 0
    rows = []
    for r in found.rides:
        rows.append(
            [
                f"{r.start_s:.1f}-{r.end_s:.1f}",
                r.direction,
                fmt_pm(r.link_pass_hz, r.link_pass_sigma_hz)
                if r.link_pass_hz is not None
                else "not told: " + " or ".join(f"{f:.2f}" for f in r.lines_hz),
                f"{r.level_db:.1f}",
                "-" if r.speed_m_s is None else fmt_pm(r.speed_m_s, r.speed_sigma_m_s),
                "-"
                if r.speed_deviation_percent is None
                else fmt_pm(r.speed_deviation_percent, r.speed_deviation_sigma_percent),
                "-" if r.vertical_speed_m_s is None else fmt_pm(r.vertical_speed_m_s, r.vertical_speed_sigma_m_s),
                "-" if r.incline_deg is None else fmt_pm(r.incline_deg, r.incline_sigma_deg),
                r.channel,
            ]
        )
    header = [
        "ride [s]",
        "direction",
        "link pass [Hz]",
        "line [dB]",
        "speed [m/s]",
        "vs rated [%]",
        "vertical [m/s]",
        "incline [deg]",
        "channel",
    ]
    if rows:
        print(table(rows, header))
    msg(
        f"{src}: {len(found.rides)} ride(s) in {len(found.still_spans)} still span(s) of >= 6 s; link pass searched in "
        f"{found.band_hz[0]:.3g}-{found.band_hz[1]:.3g} Hz, false-alarm probability <= {found.p_fa:g} per span"
        + ("" if pitch is not None else "; no nominal pitch: no speed (give --nominal-pitch or --escalator)")
    )
    for t0, t1, verdict in found.still_spans:
        if verdict != "ride":
            msg(f"  still {t0:.1f}-{t1:.1f} s: {verdict}")
    for r in found.rides:
        if r.flag:
            msg(f"  ride {r.start_s:.1f}-{r.end_s:.1f} s: {r.flag}")
    for note in found.notes:
        msg(f"  {note}")
    return 0
