"""Fleet inputs outside their stated ranges, and SQLite's failures, as one line naming what to do."""

import datetime as dt
import sqlite3

import pytest

from vibkit.fleet import FleetDB, FleetError
from vibkit.fleet.inputs import RANGES, check_date, check_inputs, check_pitch, check_speed, check_speed_sigma

from corpus_fleet import make_db


def test_ranges_are_checked_in_si_at_their_edges():
    lo, hi, _ = RANGES["nominal_pitch"]
    assert check_pitch(lo) == lo and check_pitch(hi) == hi and check_pitch(0.13333) == 0.13333
    for bad in (lo * (1 - 1e-12), hi * (1 + 1e-12), 133.33, 1e-9, float("nan"), float("inf"), "x", True):
        with pytest.raises(FleetError):
            check_pitch(bad)
    with pytest.raises(FleetError, match=r"metres: 0.13333 m, not 133.33"):
        check_pitch(133.33)
    assert check_speed(0.1) == 0.1 and check_speed(2.0) == 2.0
    for bad in (0.0999, 2.01, 1e-9, -0.5):
        with pytest.raises(FleetError, match="0.1-2 m/s"):
            check_speed(bad)
    assert check_speed_sigma(0.1, 0.5) == 0.1 and check_speed_sigma(0.0, 0.5) == 0.0
    for bad in (0.1001, 5.0, -1e-6):
        with pytest.raises(FleetError, match="0-20 %"):
            check_speed_sigma(bad, 0.5)
    utc = dt.timezone.utc
    assert check_date(dt.datetime(1970, 1, 1, tzinfo=utc)).year == 1970
    for bad in (dt.datetime(1969, 12, 31, 23, 59, tzinfo=utc), dt.datetime(2101, 1, 1, tzinfo=utc)):
        with pytest.raises(FleetError, match="1970-2100"):
            check_date(bad)


def test_every_input_is_checked_before_the_recording_is_read(tmp_path):
    missing = tmp_path / "not-there.csv"  # reading it would fail: the inputs must fail first
    for kw, match in (
        ({"date": "9999-12-31T23:59:59-23:59"}, "1970-2100"),
        ({"speed": 1e-9}, "0.1-2 m/s"),
        ({"nominal_pitch": 133.33}, "0.05-0.3 m"),
        ({"speed_sigma": 5.0}, "0-20 %"),
        ({"unit": " "}, "unit"),
    ):
        args = {"unit": "E01", "speed": 0.5, "speed_sigma": 0.0, "nominal_pitch": 0.13333, "date": "2026-01-01"}
        args.update(kw)
        with pytest.raises(FleetError, match=match):
            check_inputs(**args)
        with FleetDB(tmp_path / "f.sqlite") as db, pytest.raises(FleetError, match=match):
            db.add(missing, **args)


def test_damaged_pages_are_one_line_naming_the_file(tmp_path):
    make_db("f.sqlite", corrupt=True)(tmp_path)
    for readonly in (False, True):
        with pytest.raises(FleetError, match=r"f.sqlite: the database file is damaged .*\.recover"):
            with FleetDB(tmp_path / "f.sqlite", create=False, readonly=readonly) as db:
                db.status()


def test_read_only_use_never_writes(tmp_path):
    make_db("f.sqlite")(tmp_path)
    before = (tmp_path / "f.sqlite").read_bytes()
    with FleetDB(tmp_path / "f.sqlite", create=False, readonly=True) as db:
        assert [t.unit for t in db.status()] == ["E01"]
        m = db.measurements()[0]
        with pytest.raises(FleetError, match=r"f.sqlite: cannot write: the file or its folder is read-only"):
            db.insert(m.__class__(**{**m.as_dict(), "id": None, "sha256": "1" * 64, "warnings": ()}))
    assert (tmp_path / "f.sqlite").read_bytes() == before
    wal = tmp_path / "f.sqlite-wal"  # SQLite's read-only reader of a WAL database may make an empty -wal/-shm
    assert not wal.exists() or wal.stat().st_size == 0
    # an empty SQLite database of someone else: refused, left as it was
    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.execute("DROP TABLE t")
    con.commit()
    con.close()
    before = other.read_bytes()
    with pytest.raises(FleetError, match="not a fleet history"):
        FleetDB(other, create=False, readonly=True)
    assert other.read_bytes() == before


def test_a_locked_database_is_one_line(tmp_path, monkeypatch):
    make_db("f.sqlite")(tmp_path)
    monkeypatch.setattr(FleetDB, "TIMEOUT_S", 0.2)
    with FleetDB(tmp_path / "f.sqlite") as db:
        m = db.measurements()[0]
        holder = sqlite3.connect(tmp_path / "f.sqlite", isolation_level=None)
        holder.execute("BEGIN EXCLUSIVE")  # another process writing
        try:
            with pytest.raises(FleetError, match=r"f.sqlite: locked by another process .*try again"):
                db.insert(m.__class__(**{**m.as_dict(), "id": None, "sha256": "1" * 64, "warnings": ()}))
        finally:
            holder.execute("ROLLBACK")
            holder.close()
        assert len(db.measurements()) == 1
