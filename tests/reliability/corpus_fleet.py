"""Reliability cases of ``vibkit fleet``: inputs outside their stated ranges refused before any
analysis, damaged / foreign databases in one line, read-only uses that never write."""

import datetime as dt
import sqlite3
from pathlib import Path

from corpus import REC, Case

ADD = ["fleet", "add", "{w}/rec.csv", "--db", "{w}/main.sqlite", "--unit", "E01"]


def make_db(name="main.sqlite", *, corrupt=False):
    """A fleet database with one stored measurement (no analysis: a row written directly)."""

    def setup(w: Path):
        from vibkit.fleet import FleetDB, Measurement

        with FleetDB(w / name) as db:
            db.insert(
                Measurement(
                    id=None,
                    unit="E01",
                    date_utc="2026-01-01T00:00:00Z",
                    date_unix_s=1767225600.0,
                    date_source="given",
                    speed_m_s=0.5,
                    speed_sigma_m_s=0.0,
                    nominal_pitch_m=0.13333,
                    channel="a",
                    fundamental_hz=3.75,
                    fundamental_sigma_hz=1e-4,
                    pitch_m=0.13340,
                    pitch_sigma_m=1e-5,
                    elongation_percent=0.05,
                    elongation_sigma_percent=0.01,
                    snr_db=30.0,
                    warnings=(),
                    sha256="0" * 64,
                    path="/x.csv",
                    size_bytes=1,
                    vibkit_version="0",
                    analysed_utc="2026-01-01T00:00:00Z",
                )
            )
        if corrupt:  # header intact, the pages after the first flipped
            with open(w / name, "r+b") as fh:
                fh.seek(4096)
                page = fh.read(4096)
                fh.seek(4096)
                fh.write(bytes(b ^ 0xFF for b in page))

    return setup


def foreign_empty(name):
    """A SQLite database with no table (another program's, just created)."""

    def setup(w: Path):
        con = sqlite3.connect(w / name)
        con.execute("CREATE TABLE t (x)")
        con.execute("DROP TABLE t")
        con.commit()
        con.close()

    return setup


#: the ``measurement`` table as vibkit wrote it before schema 2 (no quality flag, no ``replaced``)
SCHEMA_1_DDL = """
CREATE TABLE measurement (
    id INTEGER PRIMARY KEY, unit TEXT NOT NULL CHECK (length(unit) > 0), date_utc TEXT NOT NULL,
    date_unix_s REAL NOT NULL, date_source TEXT NOT NULL, speed_m_s REAL NOT NULL CHECK (speed_m_s > 0),
    speed_sigma_m_s REAL NOT NULL CHECK (speed_sigma_m_s >= 0), nominal_pitch_m REAL NOT NULL CHECK (nominal_pitch_m > 0),
    channel TEXT NOT NULL, fundamental_hz REAL NOT NULL, fundamental_sigma_hz REAL NOT NULL, pitch_m REAL NOT NULL,
    pitch_sigma_m REAL NOT NULL, elongation_percent REAL NOT NULL, elongation_sigma_percent REAL NOT NULL, snr_db REAL,
    warnings TEXT NOT NULL, sha256 TEXT NOT NULL UNIQUE CHECK (length(sha256) = 64), path TEXT NOT NULL,
    size_bytes INTEGER NOT NULL, vibkit_version TEXT NOT NULL, analysed_utc TEXT NOT NULL);
CREATE INDEX measurement_unit_date ON measurement (unit, date_unix_s);
PRAGMA application_id = 1447185222;
PRAGMA user_version = 1;
"""

#: rows of a schema-1 history: (unit, years after 2023-01-15, elongation [%], its sigma [%]); E22's last two are
#: outside the physical window, E23's second is too wide (sigma 0.9 %), E24 grows by exactly 0.4 %/year
SCHEMA_1_ROWS = [
    ("E22", 0.0, 3.8, 0.1),
    ("E22", 0.5, -5.8, 0.3),
    ("E22", 1.0, 52.0, 0.4),
    ("E23", 0.0, 0.5, 0.05),
    ("E23", 1.0, 0.9, 0.9),
    ("E23", 2.0, 1.2, 0.05),
    ("E24", 0.0, 0.3, 0.05),
    ("E24", 0.5, 0.5, 0.05),
    ("E24", 1.0, 0.7, 0.05),
    ("E24", 1.5, 0.9, 0.05),
]


def schema1_db(name="main.sqlite", rows=SCHEMA_1_ROWS, *, journal="wal"):
    """A fleet history as an older vibkit (schema 1) left it: WAL journal, closed cleanly (no -wal file)."""

    def setup(w: Path):
        nominal, t0 = 0.13333, 1673740800.0  # 2023-01-15T00:00:00Z
        con = sqlite3.connect(w / name)
        con.execute(f"PRAGMA journal_mode={journal}")
        con.executescript(SCHEMA_1_DDL)
        for i, (unit, years, e, s) in enumerate(rows):
            t = t0 + years * 365.25 * 86400
            date = dt.datetime.fromtimestamp(t, dt.timezone.utc)
            con.execute(
                "INSERT INTO measurement (unit, date_utc, date_unix_s, date_source, speed_m_s, speed_sigma_m_s, "
                "nominal_pitch_m, channel, fundamental_hz, fundamental_sigma_hz, pitch_m, pitch_sigma_m, "
                "elongation_percent, elongation_sigma_percent, snr_db, warnings, sha256, path, size_bytes, "
                "vibkit_version, analysed_utc) VALUES (?, ?, ?, 'given', 0.5, 0.001, ?, 'accel', 3.75, 1e-3, ?, ?, "
                "?, ?, ?, ?, ?, ?, ?, '0.0.9', '2025-11-01T10:00:00Z')",
                (
                    unit,
                    date.isoformat(timespec="seconds").replace("+00:00", "Z"),
                    t,
                    nominal,
                    nominal * (1 + e / 100),
                    nominal * s / 100,
                    e,
                    s,
                    None if i % 4 == 0 else 20.0 + i,
                    '["clipped"]' if i % 3 == 0 else "[]",
                    f"{i + 1:064x}",
                    f"/visits/r{i}.csv",
                    1000 + i,
                ),
            )
        con.commit()
        con.close()

    return setup


CORRUPT = ("main.sqlite", "damaged", "recover")

CASES = [
    # ------------------------------------------------------------------ ranges, before any analysis
    Case(
        "fleet add --date 9999-12-31T23:59:59-23:59",
        "fleet",
        ADD + ["--speed", "0.5", "--nominal-pitch", "0.13333", "--date", "9999-12-31T23:59:59-23:59"],
        files=REC,
        expect_in=("9999-12-31", "1970-2100"),
        absent=("{w}/main.sqlite",),
    ),
    Case(
        "fleet add --date 1850-01-01",
        "fleet",
        ADD + ["--speed", "0.5", "--nominal-pitch", "0.13333", "--date", "1850-01-01"],
        files=REC,
        expect_in=("1970-2100",),
    ),
    Case(
        "fleet add bad date, unreadable recording",
        "fleet",
        [
            "fleet",
            "add",
            "{w}/junk.csv",
            "--db",
            "{w}/main.sqlite",
            "--unit",
            "E01",
            "--speed",
            "0.5",
            "--nominal-pitch",
            "0.13333",
            "--date",
            "2026-13-45",
        ],
        files={"junk.csv": b"\x00\x01garbage"},
        expect_in=("--date", "2026-13-45"),
        note="the date is checked before the recording is read",
    ),
    # a bare number far from any chain is a usage error of the option itself (exit 2), with the likely unit
    Case(
        "fleet add --nominal-pitch 133.33",
        "fleet",
        ADD + ["--speed", "0.5", "--nominal-pitch", "133.33"],
        files=REC,
        expect="usage",
        expect_in=("133.33", "did you mean 133.33mm", "0.13333 m"),
    ),
    Case(
        "fleet add --nominal-pitch 1e-9",
        "fleet",
        ADD + ["--speed", "0.5", "--nominal-pitch", "1e-9"],
        files=REC,
        expect="usage",
        expect_in=("1e-09 m", "not a step-chain pitch"),
    ),
    Case(
        "fleet add --speed 1e-9",
        "fleet",
        ADD + ["--speed", "1e-9", "--nominal-pitch", "0.13333"],
        files=REC,
        expect="usage",
        expect_in=("--speed", "not an escalator or moving-walk speed"),
    ),
    Case(
        "fleet add --speed 50",
        "fleet",
        ADD + ["--speed", "50", "--nominal-pitch", "0.13333"],
        files=REC,
        expect="usage",
        expect_in=("did you mean 50cm/s",),
    ),
    # a number the option takes but the fleet's stated ranges refuse: exit 1, the range named
    Case(
        "fleet add --nominal-pitch 30mm",
        "fleet",
        ADD + ["--speed", "0.5", "--nominal-pitch", "30mm"],
        files=REC,
        expect_in=("0.05-0.3 m",),
    ),
    Case(
        "fleet add --speed 0.07",
        "fleet",
        ADD + ["--speed", "0.07", "--nominal-pitch", "0.13333"],
        files=REC,
        expect_in=("--speed", "0.1-2 m/s"),
    ),
    Case(
        "fleet add --speed-uncertainty 1000%",
        "fleet",
        ADD + ["--speed", "0.5", "--speed-uncertainty", "1000%", "--nominal-pitch", "0.13333"],
        files=REC,
        expect_in=("--speed-uncertainty", "0-20 %"),
    ),
    Case(
        "fleet scan, catalogue nominal 1e-6 m",
        "fleet",
        ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/main.sqlite", "--workers", "0"],
        files={"units.csv": "file,unit,speed_m_s,date,nominal_pitch_m\nrec.csv,E01,0.5,2026-01-01,1e-6\n"},
        setup=lambda w: ((w / "visits").mkdir(), (w / "visits" / "rec.csv").write_text(REC["rec.csv"])),
        expect_in=("units.csv, line 2", "nominal_pitch_m", "0.05-0.3 m"),
        absent=("{w}/main.sqlite",),
    ),
    # ------------------------------------------------------------------ damaged, foreign and read-only databases
    Case(
        "fleet status, damaged pages",
        "fleet",
        ["fleet", "status", "--db", "{w}/main.sqlite"],
        setup=make_db(corrupt=True),
        expect_in=CORRUPT,
    ),
    Case(
        "fleet status --json, damaged pages",
        "fleet",
        ["fleet", "status", "--json", "--db", "{w}/main.sqlite"],
        setup=make_db(corrupt=True),
        expect_in=CORRUPT,
    ),
    Case(
        "fleet add, damaged pages",
        "fleet",
        ADD + ["--speed", "0.49", "--nominal-pitch", "0.13333", "--date", "2026-11-01"],
        files=REC,
        setup=make_db(corrupt=True),
        expect_in=CORRUPT,
    ),
    Case(
        "fleet report, damaged pages",
        "fleet",
        ["fleet", "report", "--db", "{w}/main.sqlite", "-o", "{w}/f.pdf"],
        setup=make_db(corrupt=True),
        expect_in=CORRUPT,
        absent=("{w}/f.pdf",),
    ),
    Case(
        "fleet status of an empty foreign SQLite file",
        "fleet",
        ["fleet", "status", "--db", "{w}/other.sqlite"],
        setup=foreign_empty("other.sqlite"),
        expect_in=("other.sqlite", "not a fleet history"),
        protect=("{w}/other.sqlite",),
        note="read-only: vibkit's schema is not written into it",
    ),
    Case(
        "fleet report of an empty foreign SQLite file",
        "fleet",
        ["fleet", "report", "--db", "{w}/other.sqlite", "-o", "{w}/f.pdf"],
        setup=foreign_empty("other.sqlite"),
        expect_in=("not a fleet history",),
        protect=("{w}/other.sqlite",),
        absent=("{w}/f.pdf",),
    ),
    Case(
        "fleet status, sound database",
        "fleet",
        ["fleet", "status", "--db", "{w}/main.sqlite"],
        setup=make_db(),
        expect="ok",
        protect=("{w}/main.sqlite",),
        note="read-only open: the file is left byte for byte",
    ),
    Case(
        "fleet status --json of a schema-1 history",
        "fleet",
        ["fleet", "status", "--json", "--db", "{w}/main.sqlite"],
        setup=schema1_db(),
        expect="ok",
        protect=("{w}/main.sqlite",),
        note="an older vibkit's history is read without upgrading it; the file is left byte for byte",
    ),
]
