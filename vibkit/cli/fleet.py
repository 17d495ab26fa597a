"""``vibkit fleet``: measurement history of a fleet of escalators (add, scan, status, report, migrate)."""

from __future__ import annotations

import sys
import textwrap

from vibkit.diagnose.rounding import SPEED_SIGMA_NOT_STATED, fmt_length, fmt_pm

from .options import (
    CHANNEL_EVERY,
    TIME_FORMAT,
    _profile_of,
    add_command,
    add_escalator,
    add_force_overwrite,
    add_json,
    add_limits,
    add_links,
    add_marker,
    add_nominal_pitch,
    add_recording,
    add_speed,
    read_recording,
    reader_options,
    segment_of,
    workers,
)
from .output import CLIError, UsageError, check_output, is_stdout, msg, output_path, print_json, shown, table
from .settings import chain_links, run_speed

EPILOG = (
    "examples (on the example fleet that vibkit datasets copy data writes into data/fleet-example/):\n"
    "  vibkit fleet add data/fleet-example/E07/2026-11-23.csv --unit E07 --speed 0.5 \\\n"
    "      --nominal-pitch 0.13333\n"
    "  vibkit fleet scan data/fleet-example --catalogue data/fleet-example/units.csv --workers 0\n"
    "  vibkit fleet status --json\n  vibkit fleet report -o out/fleet.pdf\n"
    "  vibkit fleet migrate --from out/fleet.sqlite --to postgresql://tech@fleet-server/fleet\n"
    "database: --db PATH (or sqlite:///PATH) or postgresql://user@host/dbname,\n"
    "  else $VIBKIT_FLEET_DB, else ./vibkit-fleet.sqlite\n"
    "exit codes: 0 done; 1 error; 2 usage; 3 scan: some files failed (others were stored or\n"
    "  already were); 4 status --alert LIMIT: a unit's latest elongation has reached that limit\n"
    "catalogue columns: file (name or glob), unit, speed_m_s, date (ISO 8601; empty: an ISO date\n"
    "  in the file name, else the recording's start time), nominal_pitch_m (empty: the unit's),\n"
    "  optional speed_sigma_m_s, channel, escalator, n_links (the links are scanned), marker_s\n"
    "  (when a marked link passed the sensor: its numbers follow the same links across visits)"
)


def add_parser(subparsers):
    s = add_command(
        subparsers,
        "fleet",
        "measurement history of a fleet of escalators: add, scan, status, report, migrate, roles",
        EPILOG,
    )
    fsub = s.add_subparsers(dest="fleet_command", metavar="SUBCOMMAND", required=True)

    def fleet_sub(name, help_):
        sp = add_command(fsub, name, help_, EPILOG)
        sp.add_argument(
            "--db",
            help="fleet database: a path, sqlite:///PATH or postgresql://user@host/dbname "
            "(default $VIBKIT_FLEET_DB, else ./vibkit-fleet.sqlite)",
        )
        add_json(sp)
        return sp

    f = fleet_sub("add", "analyse one recording and store its pitch and elongation")
    add_recording(f, channel_default=CHANNEL_EVERY)
    f.add_argument("--unit", help="escalator identifier (default: the --escalator profile's unit; else required)")
    add_speed(f, "the --escalator profile's, else the speed the file states, e.g. chain_speed_m_s; neither: refused")
    f.add_argument(
        "--speed-uncertainty",
        help="speed standard deviation, in m/s or in %% (e.g. 0.1%%; default the --escalator profile's): without it "
        "the visit is stored with a warning, and its unit's trend is flagged (its intervals are too small)",
    )
    f.add_argument("--date", help="measurement date, ISO 8601 (default: the recording's start time)")
    add_nominal_pitch(f, "the --escalator profile's, else the unit's; required for a new unit")
    f.add_argument(
        "--replaced",
        action="store_true",
        help="the unit's chain was replaced since its previous measurement: a new trend segment starts here",
    )
    add_escalator(f)
    add_links(
        f,
        "links in the chain: the links are scanned as fleet scan scans them (default the --escalator "
        "profile's chain.n_links; neither: the scan is stored 'not run')",
    )
    add_marker(
        f,
        f"time from the recording's start ({TIME_FORMAT}) at which a marked link passed the sensor: it is link 1, and "
        "its numbers follow the same links across visits (the catalogue's marker_s)",
    )
    f.set_defaults(func=run_add)

    f = fleet_sub(
        "scan", "add every recording of a folder that a catalogue describes, in parallel (Dask) where that pays"
    )
    f.add_argument("directory", metavar="DIR", help="folder of recordings (searched recursively)")
    f.add_argument("--catalogue", required=True, help="CSV: file, unit, speed_m_s, date, nominal_pitch_m")
    f.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    f.add_argument(
        "--workers",
        type=workers,
        help="worker processes of a local cluster, started where it pays (default: one per core; 0: analyse in "
        "this process)",
    )
    add_recording(
        f, positional=False, channel=False, with_segment=False
    )  # for every file; the catalogue's channel column per file
    f.set_defaults(func=run_scan)

    f = fleet_sub(
        "status",
        "the work list: per unit the latest elongation, the rate per year, the next limit and its date, flags; most urgent first",
    )
    f.add_argument("--unit", action="append", help="only this unit (repeatable)")
    add_limits(f)
    f.add_argument(
        "--format",
        choices=FORMATS,
        help="table (default), json (as --json) or csv (one row per unit, for a spreadsheet or a CMMS)",
    )
    f.add_argument(
        "--alert",
        choices=ALERT_LIMITS,
        help=f"exit with status {STATUS_PAST_LIMIT} when a listed unit's latest elongation has reached this "
        "limit of --limits (for a scheduled job; the output is written as without it)",
    )
    f.set_defaults(func=run_status)

    f = fleet_sub(
        "report", "PDF: the work list (page 1), then elongation against date per unit, then the flagged links"
    )
    f.add_argument("-o", "--output", required=True, help="PDF to write")
    add_force_overwrite(f, "PDF")
    add_limits(f)
    f.set_defaults(func=run_report)

    f = add_command(
        fsub,
        "migrate",
        "copy every measurement of one fleet database into another (e.g. a SQLite "
        "file to PostgreSQL), in one transaction; again: copies only what is missing",
        EPILOG,
    )
    f.add_argument("--from", dest="source", required=True, help="the existing database (path or URL)")
    f.add_argument("--to", dest="target", required=True, help="the receiving database (created if missing)")
    add_json(f)
    f.set_defaults(func=run_migrate)

    f = fleet_sub(
        "roles",
        "print the SQL that gives a PostgreSQL fleet history a technician's role (may add visits) and a "
        "reader's (may only read), for its owner to run once (psql -f)",
    )
    f.add_argument("--database", help="the database's name (default: --db's, else fleet)")
    f.add_argument("--schema", default="public", help="the schema holding the history (default public)")
    f.set_defaults(func=run_roles)
    return s


#: exit code of ``fleet scan`` when some files failed and others were stored (or already were)
SCAN_SOME_FAILED = 3
#: exit code of ``fleet status --alert LIMIT`` when a listed unit's latest elongation has reached LIMIT
STATUS_PAST_LIMIT = 4
#: ``fleet status --format``
FORMATS = ("table", "json", "csv")
#: ``fleet status --alert``: the limits of ``--limits WATCH,PLAN,REPLACE`` by name
ALERT_LIMITS = ("watch", "plan", "replace")


def _fleet_db(a, *, create=True):
    from vibkit.fleet.history import FleetDB

    db = FleetDB(a.db, create=create, readonly=not create)  # status, report: read-only
    for n in db.notes:  # e.g. an older schema read without upgrading it
        msg(f"note: {n}")
    return db


# said under a stored line: the fleet's SNR is not the peak's height over the floor that `vibkit pitch` tabulates
HARMONIC_SNR_NOTE = (
    "note: harmonic SNR: the fitted link-pass harmonics' power over the rest of the recording's (noise and all other "
    "vibration); it reads far lower than a line's height over the spectrum's floor, which `vibkit pitch` tabulates"
)


def _fmt_measurement(m):
    """One line of a stored measurement."""
    if m.speed_sigma_stated:  # rounded to the sigma
        numbers = (
            f"pitch {fmt_length(m.pitch_m, m.pitch_sigma_m)}, "
            f"elongation {fmt_pm(m.elongation_percent, m.elongation_sigma_percent, '%', sign=True)}"
        )
    else:  # the speed's uncertainty not stated: no +-
        numbers = (
            f"pitch {1000 * m.pitch_m:.2f} mm, elongation {m.elongation_percent:+z.2f} % ({SPEED_SIGMA_NOT_STATED})"
        )
    return (
        f"#{m.id} unit {m.unit} {m.date_utc[:10]}: {numbers} "
        f"(harmonic SNR {'n/a' if m.snr_db is None else f'{m.snr_db:.0f} dB'})"
    )


def run_add(a):
    from vibkit.fleet.inputs import check_inputs

    profile = _profile_of(a)
    if a.unit is not None and not a.unit.strip():
        raise CLIError("fleet add: --unit is empty; give the escalator's identifier, e.g. --unit E07")
    if a.unit is None and profile is None:
        raise CLIError("fleet add: give --unit (or --escalator FILE, whose unit is used)")
    if a.speed is None and profile is None:
        # the speed the file states (Leon's chain_speed_m_s, a tachometer's column), as `pitch` takes it
        from vibkit.diagnose.channels import speed_from_recording

        a.speed, source = speed_from_recording(read_recording(a))
        if a.speed is None:
            raise CLIError(
                "fleet add: give --speed, the chain speed measured on the steps (or --escalator FILE); the file "
                "states none"
            )
        msg(f"note: speed {a.speed:g} m/s from the {source.removeprefix('file: ')} of {shown(a.recording)}")
    if a.unit and profile is not None and profile.unit and a.unit.strip() != str(profile.unit).strip():
        # a visit of one unit stored under another's name: a trend that is not the unit's
        raise CLIError(
            f"--unit {a.unit} contradicts the escalator profile {profile.source} (unit {profile.unit}): give one of "
            "them, or the profile of that unit"
        )
    unit = a.unit or profile.unit
    sp = run_speed(a, profile=profile)  # --speed, else the profile's; --speed-uncertainty, else the profile's
    nominal = a.nominal_pitch if a.nominal_pitch is not None else (profile.nominal_pitch if profile else None)
    # without a stated speed uncertainty the speed's sigma is stored as "not stated" (NULL; a stated 0 is kept as 0):
    # no +- is printed for it, and the trend of its unit is flagged (its intervals are too small)
    sigma = sp.sigma
    check_inputs(unit=unit, speed=sp.value, speed_sigma=sigma, nominal_pitch=nominal, date=a.date)
    with _fleet_db(a) as db:
        n_notes = len(db.notes)
        m = db.add(
            a.recording,
            unit=unit,
            speed=sp.value,
            speed_sigma=sigma,
            date=a.date,
            nominal_pitch=nominal,
            channel=a.channel,
            replaced=a.replaced,
            read_options=reader_options(a),
            n_links=chain_links(a, profile),
            marker_s=a.marker,
            escalator=a.escalator,
            segment=segment_of(a),
        )
        scan = db.link_scans(m.unit).get(m.id)
        for n in db.notes[n_notes:]:  # e.g. a profile whose geometry gives no scene for the signature
            msg(f"note: {n}")
        path = db.path
    if a.json:
        print_json(
            "fleet.add",
            {"database": path, "measurement": m.as_reported(), "link_scan": None if scan is None else scan.as_dict()},
        )
    else:
        print(f"stored {_fmt_measurement(m)}")
        msg(HARMONIC_SNR_NOTE)
        if scan is not None:
            from vibkit.diagnose.report.fleet_links import scan_advice

            why = f": {scan.reason}" if scan.reason and not scan.scanned else ""
            advice = scan_advice(scan)
            print(f"links: {_fmt_scan(scan)}{why}" + (f"; {advice}" if advice else ""))
        msg(f"note: database {path}; date from {m.date_source}")
    if m.speed_sigma_stated and not m.speed_sigma_m_s > 0:
        msg(
            f"note: speed uncertainty stated as 0 m/s ({sp.sigma_source}): the elongation's +- is the frequency's "
            "alone (stored as a stated exact speed)"
        )
    elif not m.speed_sigma_stated:
        msg(
            "warning: stored without a speed uncertainty (not stated): its elongation has no +-, and the unit's "
            "rate and forecast intervals are too small; give --speed-uncertainty"
        )
    if m.quality != "ok":
        msg(f"warning: stored flagged {m.quality}, left out of the trend: {m.quality_reason}")
    for w in m.warnings:  # a sensor on a step among them, for the channel measured (as `vibkit pitch` says it)
        msg(f"warning: {w}")
    return 0


def run_scan(a):
    def failed(name, why):
        msg(f"vibkit fleet scan: failed: {why if why.startswith(name) else f'{name}: {why}'}")

    from vibkit.fleet.catalogue import read_catalogue

    read_catalogue(a.catalogue)  # a bad catalogue is refused before the database is opened (or made)
    with _fleet_db(a) as db:
        res = db.scan(
            a.directory,
            a.catalogue,
            scheduler=a.scheduler,
            n_workers=a.workers or None,
            parallel=False if a.workers == 0 else None,  # None: on Dask where that pays
            on_failure=failed,
            progress=sys.stderr.isatty(),
            read_options=reader_options(a),
        )
        path = db.path
    for n in res.notes:
        msg(f"note: {n}")
    if a.json:
        print_json("fleet.scan", {"database": path, **res.as_dict()})
    else:
        print(
            f"added {len(res.added)}, skipped {len(res.skipped)} (already stored), failed {len(res.failed)}"
            f"  [database {path}]"
        )
        for m in res.added:
            scan = res.link_scans.get(m.sha256)
            links = "" if scan is None else f"; links: {_fmt_scan(scan)}"
            print(f"  added {_fmt_measurement(m)}{links}")
        if res.added:
            msg(HARMONIC_SNR_NOTE)
    flagged = sum(1 for m in res.added if m.quality != "ok")
    msg(
        f"vibkit fleet scan: {len(res.added)} added ({flagged} flagged), {len(res.skipped)} already stored, "
        f"{len(res.failed)} failed"
    )
    if not res.added and not res.skipped:
        raise CLIError(
            f"nothing added from {a.directory}: {len(res.failed)} file(s) failed"
            if res.failed
            else f"{a.directory}: no recording found (suffixes .csv, .txt, .nc, .mseed ...)"
        )
    return SCAN_SOME_FAILED if res.failed else 0


def _fmt_scan(scan):
    """A link scan in a few words: its status, what it flagged, what link 1 is."""
    if not scan.scanned:
        return scan.status
    one = "link 1 marked" if scan.marker_s is not None else "link 1 at the start, no marker"
    flagged = ", ".join(f.label for f in scan.flagged)
    # the numbers, as `fleet add` and `fleet scan` alike print them
    return f"{scan.loops} loops, {len(scan.flagged)} flagged ({one})" + (f" (links {flagged})" if flagged else "")


def _print_links(hist, always):
    """The link lines of one unit under the work list: the statement, then a table of its links."""
    if not hist.scanned and not always:
        return
    print()
    print(textwrap.fill(f"{hist.unit} links: {hist.statement}", 100, subsequent_indent="    "))
    if hist.links:
        rows = [[h.label, h.verdict, h.detail] for h in hist.links]
        print(table(rows, ("link", "verdict", "excess pitch [mm] and change")))
    elif hist.scanned:
        print("no link flagged")
    for m, s in hist.visits:
        if s.note:
            msg(f"note: {hist.unit} {m.date_utc[:10]}: {s.note}")


def run_status(a):
    fmt = a.format or ("json" if a.json else "table")
    if a.json and fmt != "json":
        raise UsageError(f"--json and --format {fmt} ask for two outputs; give one of them")
    with _fleet_db(a, create=False) as db:
        trends = db.status(limits_percent=a.limits, units=a.unit or None)
        links = {t.unit: db.links_history(t.unit) for t in trends}
        path = db.path
    if a.unit and not trends:
        raise CLIError(f"{path}: no measurement of unit(s) {', '.join(a.unit)}")
    from vibkit.diagnose.report.common import report_date

    today = report_date()  # now, or SOURCE_DATE_EPOCH
    code = _alert(a, trends)
    if fmt == "csv":
        from vibkit.fleet.export import work_list_records, write_csv

        write_csv(work_list_records(trends, today.timestamp(), links), sys.stdout)
        return code
    if fmt == "json":
        print_json(
            "fleet.status",
            {
                "database": path,
                "limits_percent": list(a.limits),
                "today_utc": today.strftime("%Y-%m-%d"),
                "units": [{**t.as_dict(today.timestamp()), **_links_json(links[t.unit])} for t in trends],
            },
        )
        return code
    if not trends:
        print(f"{path}: no measurement stored yet")
        return code
    from vibkit.diagnose.report.fleet import OVERDUE_MEANING, WORK_LIST_HEADER, work_list_rows

    rows = work_list_rows(trends, today_unix_s=today.timestamp())
    # the flags column takes what is left of 100 columns (the whole list is in --json)
    used = sum(max(len(str(r[j])) for r in rows + [WORK_LIST_HEADER]) + 2 for j in range(len(WORK_LIST_HEADER) - 1))
    width = max(12, 100 - used)
    print(table(work_list_rows(trends, flags_width=width, today_unix_s=today.timestamp()), WORK_LIST_HEADER))
    for tr in trends:  # flags too long for the table, in full under it
        flags = "; ".join(tr.flags)
        if len(flags) > width:
            print(textwrap.fill(f"{tr.unit} flags: {flags}", 100, subsequent_indent="    "))
    msg(
        textwrap.fill(
            "note: most urgent first; latest usable elongation and the rate with 1 sigma; the next "
            "limit and the year-month it is reached, with its 2-sigma interval; flagged measurements and "
            f"outliers are left out of the trends (all of it: --json); today {today:%Y-%m-%d}",
            100,
        )
    )
    if any(t.overdue(today.timestamp()) for t in trends):
        msg(textwrap.fill(f"note: {OVERDUE_MEANING}", 100))
    for t in trends:
        _print_links(links[t.unit], always=bool(a.unit))
    return code


def _alert(a, trends):
    """The exit status of ``fleet status``: :data:`STATUS_PAST_LIMIT` when ``--alert`` names a limit a unit has
    reached (said on stderr), else 0."""
    if not a.alert:
        return 0
    from vibkit.fleet.export import units_past_limit

    limit = a.limits[ALERT_LIMITS.index(a.alert)]
    past = units_past_limit(trends, limit)
    if not past:
        return 0
    msg(
        f"vibkit fleet status: {len(past)} unit(s) at or past the {a.alert} limit ({limit:g} %): {', '.join(past)} "
        f"(exit status {STATUS_PAST_LIMIT})"
    )
    return STATUS_PAST_LIMIT


def _links_json(hist):
    d = hist.as_dict()
    return {
        "links": d["links"],
        "links_comparable": d["comparable"],
        "links_statement": d["statement"],
        "link_scans": d["visits"],
    }


def run_report(a):
    with output_path(a.output, ".pdf") as target:  # '-o -': written to a temporary file, then to stdout
        return _run_report(a, target)


def _run_report(a, target):
    from vibkit.diagnose.report import write_fleet_report

    check_output(a.output, [], a.force, json_flag=a.json)
    with _fleet_db(a, create=False) as db:
        check_output(a.output, [db.path], a.force)
        trends = db.status(limits_percent=a.limits)
        meas = db.measurements()
        links = {t.unit: db.links_history(t.unit) for t in trends}  # what fleet status says of the links
        path = db.path
    if not trends:
        raise CLIError(f"{path}: no measurement stored yet; nothing to report")
    import zlib

    try:
        rep = write_fleet_report(trends, meas, target, limits_percent=a.limits, database=path, links=links)
    except zlib.error as exc:  # the PDF's compressor, closed after a write failed (a full disk): the file named
        raise CLIError(
            f"{a.output}: the PDF could not be written ({exc}); nothing was written: is the disk full? free space "
            "or write elsewhere with -o"
        ) from None
    shown = a.output if is_stdout(a.output) else rep.path
    if a.json:
        print_json(
            "fleet.report",
            {
                "output": shown,
                "database": path,
                "pages": [t for t, _ in rep.pages],
                "units": len(trends),
                "units_drawn": rep.summary["units_drawn"],
            },
        )
    else:
        n_links = sum(1 for t, _ in rep.pages if t == "fleet links")
        msg(
            f"vibkit fleet report: wrote {shown} ({len(rep.pages)} page(s): the work list, then "
            f"{rep.summary['units_drawn']} of {len(trends)} units drawn, then {n_links} of links)"
        )
    return 0


def run_migrate(a):
    from vibkit.fleet.errors import FleetError
    from vibkit.fleet.storage import migrate

    try:
        r = migrate(a.source, a.target)
    except FleetError as exc:  # the store names --db, the flag of the other commands: here it is --from
        raise CLIError(str(exc).replace("; --db or VIBKIT_FLEET_DB names another", "; --from names it")) from None
    if a.json:
        print_json("fleet.migrate", r)
    else:
        print(
            f"copied {r['copied']}, skipped {r['skipped']} (already there); {r['target']} holds "
            f"{r['target_total']} measurement(s)"
        )
    return 0


def run_roles(a):
    import urllib.parse

    from vibkit.fleet.postgres_store import READER_ROLE, TECHNICIAN_ROLE, roles_sql

    database = a.database
    if database is None and a.db and str(a.db).startswith(("postgresql:", "postgres:")):
        database = urllib.parse.urlsplit(str(a.db)).path.lstrip("/") or None
    sql = roles_sql(database or "fleet", a.schema)
    if a.json:
        print_json(
            "fleet.roles",
            {"database": database or "fleet", "technician": TECHNICIAN_ROLE, "reader": READER_ROLE, "sql": sql},
        )
    else:
        sys.stdout.write(sql)
    return 0


_RUN = {
    "add": run_add,
    "scan": run_scan,
    "status": run_status,
    "report": run_report,
    "migrate": run_migrate,
    "roles": run_roles,
}


def run(a):
    """Run the fleet subcommand ``a.fleet_command`` (each subparser also sets its own ``func``)."""
    return _RUN[a.fleet_command](a)
