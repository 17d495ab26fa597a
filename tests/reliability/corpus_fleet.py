"""Reliability cases of ``vibkit fleet`` (issue 23): inputs outside their stated ranges refused before any
analysis, damaged / foreign databases in one line, read-only uses that never write."""

import sqlite3
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from corpus import REC, Case  # noqa: E402

ADD = ["fleet", "add", "{w}/rec.csv", "--db", "{w}/main.sqlite", "--unit", "E01"]


def make_db(name="main.sqlite", *, corrupt=False):
    """A fleet database with one stored measurement (no analysis: a row written directly)."""

    def setup(w: Path):
        from vibkit.fleet import FleetDB, Measurement

        with FleetDB(w / name) as db:
            db.insert(Measurement(
                id=None, unit="E01", date_utc="2026-01-01T00:00:00Z", date_unix_s=1767225600.0, date_source="given",
                speed_m_s=0.5, speed_sigma_m_s=0.0, nominal_pitch_m=0.13333, channel="a", fundamental_hz=3.75,
                fundamental_sigma_hz=1e-4, pitch_m=0.13340, pitch_sigma_m=1e-5, elongation_percent=0.05,
                elongation_sigma_percent=0.01, snr_db=30.0, warnings=(), sha256="0" * 64, path="/x.csv",
                size_bytes=1, vibkit_version="0", analysed_utc="2026-01-01T00:00:00Z"))
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


CORRUPT = ("main.sqlite", "damaged", "recover")

CASES = [
    # ------------------------------------------------------------------ ranges, before any analysis
    Case("fleet add --date 9999-12-31T23:59:59-23:59", "fleet", ADD + ["--speed", "0.5", "--nominal-pitch", "0.13333",
                                                                     "--date", "9999-12-31T23:59:59-23:59"],
         files=REC, expect_in=("9999-12-31", "1970-2100"), absent=("{w}/main.sqlite",)),
    Case("fleet add --date 1850-01-01", "fleet", ADD + ["--speed", "0.5", "--nominal-pitch", "0.13333",
                                                      "--date", "1850-01-01"], files=REC, expect_in=("1970-2100",)),
    Case("fleet add bad date, unreadable recording", "fleet",
         ["fleet", "add", "{w}/junk.csv", "--db", "{w}/main.sqlite", "--unit", "E01", "--speed", "0.5",
          "--nominal-pitch", "0.13333", "--date", "2026-13-45"], files={"junk.csv": b"\x00\x01garbage"},
         expect_in=("--date", "2026-13-45"), note="the date is checked before the recording is read"),
    # a bare number far from any chain is a usage error of the option itself (exit 2), with the likely unit
    Case("fleet add --nominal-pitch 133.33", "fleet", ADD + ["--speed", "0.5", "--nominal-pitch", "133.33"], files=REC,
         expect="usage", expect_in=("133.33", "did you mean 133.33mm", "0.13333 m")),
    Case("fleet add --nominal-pitch 1e-9", "fleet", ADD + ["--speed", "0.5", "--nominal-pitch", "1e-9"], files=REC,
         expect="usage", expect_in=("1e-09 m", "not a step-chain pitch")),
    Case("fleet add --speed 1e-9", "fleet", ADD + ["--speed", "1e-9", "--nominal-pitch", "0.13333"], files=REC,
         expect="usage", expect_in=("--speed", "not an escalator or moving-walk speed")),
    Case("fleet add --speed 50", "fleet", ADD + ["--speed", "50", "--nominal-pitch", "0.13333"], files=REC,
         expect="usage", expect_in=("did you mean 50cm/s",)),
    # a number the option takes but the fleet's stated ranges refuse: exit 1, the range named
    Case("fleet add --nominal-pitch 30mm", "fleet", ADD + ["--speed", "0.5", "--nominal-pitch", "30mm"], files=REC,
         expect_in=("0.05-0.3 m",)),
    Case("fleet add --speed 0.07", "fleet", ADD + ["--speed", "0.07", "--nominal-pitch", "0.13333"], files=REC,
         expect_in=("--speed", "0.1-2 m/s")),
    Case("fleet add --speed-uncertainty 1000%", "fleet",
         ADD + ["--speed", "0.5", "--speed-uncertainty", "1000%", "--nominal-pitch", "0.13333"], files=REC,
         expect_in=("--speed-uncertainty", "0-20 %")),
    Case("fleet scan, catalogue nominal 1e-6 m", "fleet",
         ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/main.sqlite", "--workers", "0"],
         files={"units.csv": "file,unit,speed_m_s,date,nominal_pitch_m\nrec.csv,E01,0.5,2026-01-01,1e-6\n"},
         setup=lambda w: ((w / "visits").mkdir(), (w / "visits" / "rec.csv").write_text(REC["rec.csv"])),
         expect_in=("units.csv, line 2", "nominal_pitch_m", "0.05-0.3 m"), absent=("{w}/main.sqlite",)),
    # ------------------------------------------------------------------ damaged, foreign and read-only databases
    Case("fleet status, damaged pages", "fleet", ["fleet", "status", "--db", "{w}/main.sqlite"],
         setup=make_db(corrupt=True), expect_in=CORRUPT),
    Case("fleet status --json, damaged pages", "fleet", ["fleet", "status", "--json", "--db", "{w}/main.sqlite"],
         setup=make_db(corrupt=True), expect_in=CORRUPT),
    Case("fleet add, damaged pages", "fleet", ADD + ["--speed", "0.49", "--nominal-pitch", "0.13333", "--date",
                                                   "2026-11-01"], files=REC, setup=make_db(corrupt=True),
         expect_in=CORRUPT),
    Case("fleet report, damaged pages", "fleet", ["fleet", "report", "--db", "{w}/main.sqlite", "-o", "{w}/f.pdf"],
         setup=make_db(corrupt=True), expect_in=CORRUPT, absent=("{w}/f.pdf",)),
    Case("fleet status of an empty foreign SQLite file", "fleet", ["fleet", "status", "--db", "{w}/other.sqlite"],
         setup=foreign_empty("other.sqlite"), expect_in=("other.sqlite", "not a fleet history"),
         protect=("{w}/other.sqlite",), note="read-only: vibkit's schema is not written into it"),
    Case("fleet report of an empty foreign SQLite file", "fleet",
         ["fleet", "report", "--db", "{w}/other.sqlite", "-o", "{w}/f.pdf"], setup=foreign_empty("other.sqlite"),
         expect_in=("not a fleet history",), protect=("{w}/other.sqlite",), absent=("{w}/f.pdf",)),
    Case("fleet status, sound database", "fleet", ["fleet", "status", "--db", "{w}/main.sqlite"], setup=make_db(),
         expect="ok", protect=("{w}/main.sqlite",), note="read-only open: the file is left byte for byte"),
]
