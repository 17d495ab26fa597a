"""``vibkit fleet``: measurement history of a fleet of escalators (add, scan, status, report)."""

from __future__ import annotations

import sys

from .options import (add_command, add_json, add_limits, add_recording, cli_message, positive, reader_options,
                      speed_sigma, workers)
from .output import CLIError, check_output, msg, print_json, table

EPILOG = ("examples (on the shipped example fleet, data/fleet-example/):\n"
          "  vibkit fleet add data/fleet-example/E07/2026-11-23.csv --unit E07 --speed 0.5 \\\n"
          "      --nominal-pitch 0.13333\n"
          "  vibkit fleet scan data/fleet-example --catalogue data/fleet-example/units.csv --workers 0\n"
          "  vibkit fleet status --json\n  vibkit fleet report -o out/fleet.pdf\n"
          "database: --db PATH (or sqlite:///PATH), else $VIBKIT_FLEET_DB, else ./vibkit-fleet.sqlite\n"
          "catalogue columns: file (name or glob), unit, speed_m_s, date (ISO 8601; empty: the recording's\n"
          "  start time), nominal_pitch_m (empty: the unit's), optional speed_sigma_m_s, channel")


def add_parser(subparsers):
    s = add_command(subparsers, "fleet", "measurement history of a fleet of escalators: add, scan, status, report",
                    EPILOG)
    fsub = s.add_subparsers(dest="fleet_command", metavar="SUBCOMMAND", required=True)

    def fleet_sub(name, help_):
        sp = add_command(fsub, name, help_, EPILOG)
        sp.add_argument("--db", help="fleet database: a path or sqlite:///PATH (default $VIBKIT_FLEET_DB, "
                        "else ./vibkit-fleet.sqlite)")
        add_json(sp)
        return sp

    f = fleet_sub("add", "analyse one recording and store its pitch and elongation")
    add_recording(f)
    f.add_argument("--unit", required=True, help="escalator identifier")
    f.add_argument("--speed", type=positive, required=True, help="chain speed measured on the steps [m/s]")
    f.add_argument("--speed-uncertainty", help="speed standard deviation, in m/s or in %% (e.g. 0.1%%)")
    f.add_argument("--date", help="measurement date, ISO 8601 (default: the recording's start time)")
    f.add_argument("--nominal-pitch", type=positive, help="nominal link pitch [m] (required for a new unit)")
    f.set_defaults(func=run_add)

    f = fleet_sub("scan", "add every recording of a folder that a catalogue describes, in parallel (Dask)")
    f.add_argument("directory", metavar="DIR", help="folder of recordings (searched recursively)")
    f.add_argument("--catalogue", required=True, help="CSV: file, unit, speed_m_s, date, nominal_pitch_m")
    f.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    f.add_argument("--workers", type=workers, help="worker processes of the local cluster (default: one per "
                   "core; 0: analyse in this process)")
    add_recording(f, positional=False, channel=False)  # for every file; the catalogue's channel column per file
    f.set_defaults(func=run_scan)

    f = fleet_sub("status", "per unit: latest elongation, trend [%/year] and limit forecasts, most urgent first")
    f.add_argument("--unit", action="append", help="only this unit (repeatable)")
    add_limits(f)
    f.set_defaults(func=run_status)

    f = fleet_sub("report", "one PDF page: elongation against date per unit, with the limits")
    f.add_argument("-o", "--output", required=True, help="PDF to write")
    f.add_argument("--force", action="store_true", help="replace an existing output file")
    add_limits(f, "elongation limits [%%]")
    f.set_defaults(func=run_report)
    return s


def _fleet_db(a, *, create=True):
    from vibkit.fleet.history import FleetDB

    return FleetDB(a.db, create=create)


def _fmt_measurement(m):
    return (f"#{m.id} unit {m.unit} {m.date_utc[:10]}: "
            f"pitch {1000 * m.pitch_m:.3f} +- {1000 * m.pitch_sigma_m:.3f} mm, "
            f"elongation {m.elongation_percent:+.3f} +- {m.elongation_sigma_percent:.3f} % "
            f"(SNR {'n/a' if m.snr_db is None else f'{m.snr_db:.0f} dB'})")


def run_add(a):
    sigma = speed_sigma(a.speed_uncertainty, a.speed) if a.speed_uncertainty else 0.0
    with _fleet_db(a) as db:
        m = db.add(a.recording, unit=a.unit, speed=a.speed, speed_sigma=sigma, date=a.date,
                   nominal_pitch=a.nominal_pitch, channel=a.channel,
                   read_options=reader_options(a))
        path = db.path
    if a.json:
        print_json("fleet.add", {"database": path, "measurement": m.as_dict()})
    else:
        print(f"stored {_fmt_measurement(m)}")
        msg(f"note: database {path}; date from {m.date_source}")
    for w in m.warnings:
        msg(f"warning: {w}")
    return 0


def run_scan(a):
    def failed(name, why):
        why = cli_message(why)
        msg(f"vibkit fleet scan: failed: {why if why.startswith(name) else f'{name}: {why}'}")

    with _fleet_db(a) as db:
        res = db.scan(a.directory, a.catalogue, scheduler=a.scheduler, n_workers=a.workers or None,
                      parallel=a.workers != 0, on_failure=failed, progress=sys.stderr.isatty(),
                      read_options=reader_options(a))
        path = db.path
    for n in res.notes:
        msg(f"note: {n}")
    if a.json:
        print_json("fleet.scan", {"database": path, **res.as_dict()})
    else:
        print(f"added {len(res.added)}, skipped {len(res.skipped)} (already stored), failed {len(res.failed)}"
              f"  [database {path}]")
        for m in res.added:
            print(f"  added {_fmt_measurement(m)}")
    if not res.added and not res.skipped:
        raise CLIError(f"nothing added from {a.directory}: {len(res.failed)} file(s) failed"
                       if res.failed else f"{a.directory}: no recording found (suffixes .csv, .txt, .nc, .mseed ...)")
    return 0


def _fmt_forecast(f):
    if f.status == "reached":
        return "reached"
    if f.status == "forecast":
        if f.date_utc is None:
            return "after 9999"
        lo, hi = (f.earliest_utc or "?")[:7], (f.latest_utc or "after 9999")[:7]
        return f"{f.date_utc[:7]} ({lo}..{hi})"
    if f.status == "not before":
        return f"not before {f.earliest_utc[:7]}" if f.earliest_utc else "-"
    return "-"


def run_status(a):
    with _fleet_db(a, create=False) as db:
        trends = db.status(limits_percent=a.limits, units=a.unit or None)
        path = db.path
    if a.unit and not trends:
        raise CLIError(f"{path}: no measurement of unit(s) {', '.join(a.unit)}")
    if a.json:
        print_json("fleet.status", {"database": path, "limits_percent": list(a.limits),
                                    "units": [t.as_dict() for t in trends]})
        return 0
    if not trends:
        print(f"{path}: no measurement stored yet")
        return 0
    rows = []
    for t in trends:
        slope = "-" if t.slope_percent_per_year is None else \
            f"{t.slope_percent_per_year:+.3f} +- {t.slope_sigma_percent_per_year:.3f}"
        rows.append([t.rank, t.unit, t.n_measurements, t.latest_date_utc[:10],
                     f"{t.latest_elongation_percent:+.3f} +- {t.latest_elongation_sigma_percent:.3f}", t.latest_verdict,
                     slope] + [_fmt_forecast(f) for f in t.forecasts])
    print(table(rows, ["rank", "unit", "n", "latest", "elongation [%]", "verdict", "trend [%/year]"]
                + [f"{f.limit_percent:g} % on" for f in trends[0].forecasts]))
    msg("note: forecast dates with their 2-sigma interval (year-month); 'not before' where the trend is not "
        "significantly positive")
    return 0


def run_report(a):
    from vibkit.diagnose.report import write_fleet_report

    check_output(a.output, [], a.force)
    with _fleet_db(a, create=False) as db:
        check_output(a.output, [db.path], a.force)
        trends = db.status(limits_percent=a.limits)
        meas = db.measurements()
        path = db.path
    if not trends:
        raise CLIError(f"{path}: no measurement stored yet; nothing to report")
    rep = write_fleet_report(trends, meas, a.output, limits_percent=a.limits, database=path)
    if a.json:
        print_json("fleet.report", {"output": rep.path, "database": path, "pages": [t for t, _ in rep.pages],
                                    "units": len(trends), "units_drawn": rep.summary["units_drawn"]})
    else:
        print(f"wrote {rep.path} (1 page, {rep.summary['units_drawn']} of {len(trends)} units drawn)")
    return 0


_RUN = {"add": run_add, "scan": run_scan, "status": run_status, "report": run_report}


def run(a):
    """Run the fleet subcommand ``a.fleet_command`` (each subparser also sets its own ``func``)."""
    return _RUN[a.fleet_command](a)
