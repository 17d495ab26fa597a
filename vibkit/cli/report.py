"""``vibkit report``: the multi-page PDF diagnostic report of a recording."""

from __future__ import annotations

from .options import (
    add_command,
    add_force_overwrite,
    add_json,
    add_limits,
    add_recording,
    band,
    chain_speed,
    pitch_length,
    positive,
    reader_options,
    speed_sigma,
    speed_uncertainty,
)
from .output import check_output, print_json, table

EPILOG = (
    "example:\n  vibkit report data/field/leon-tensioner.csv --scene sim/leon.toml --date 2020-02-14 \\\n"
    "      -o out/leon.pdf"
)


def add_parser(subparsers):
    s = add_command(subparsers, "report", "write the multi-page PDF diagnostic report of a recording", EPILOG)
    add_recording(s)
    add_json(s)
    s.add_argument("--scene", help="scene describing the escalator and sensor (simulated and compared)")
    s.add_argument("-o", "--output", required=True, help="PDF to write; a new path unless --force")
    add_force_overwrite(s, "PDF")
    s.add_argument("--speed", type=chain_speed, help="chain speed [m/s] (default: recording's or scene's)")
    s.add_argument("--speed-uncertainty", type=speed_uncertainty, help="speed standard deviation, in m/s or in %%")
    s.add_argument("--nominal-pitch", type=pitch_length, help="nominal link pitch [m] (default: the scene's)")
    add_limits(s, "elongation limits [%%]")
    s.add_argument("--band", type=band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--duration", type=positive, help="simulated time [s] (default: the scene's)")
    s.add_argument("--date", help="when the recording was made, ISO 8601 (default: the file's start time)")
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.diagnose.report import write_report

    check_output(a.output, [a.recording, a.scene], a.force)
    if a.date is not None:  # before the recording is read: the date validator every command shares
        from vibkit.runtime.dates import parse_iso_date

        parse_iso_date(a.date, "--date")
    sigma = speed_sigma(a.speed_uncertainty, a.speed) if (a.speed_uncertainty and a.speed) else 0.0
    rep = write_report(
        a.recording,
        a.output,
        scene=a.scene,
        speed=a.speed,
        speed_sigma=sigma,
        channel=a.channel,
        nominal_pitch=a.nominal_pitch,
        limits_percent=a.limits,
        duration=a.duration,
        band=a.band,
        progress=True,
        overwrite=a.force,
        read_options=reader_options(a),
        date=a.date,
    )
    if a.json:
        print_json("report", {"output": rep.path, "pages": [t for t, _ in rep.pages], "summary": rep.summary})
    else:
        print(f"wrote {rep.path} ({len(rep.pages)} pages)")
        print(table([[k, f"{v:.6g}" if isinstance(v, float) else v] for k, v in rep.summary.items()]))
    return 0
