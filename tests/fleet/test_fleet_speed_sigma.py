"""A speed uncertainty stated as 0 (an exact speed) and one not stated are two things in the fleet history (schema 5:
0 and NULL), on SQLite and on a real PostgreSQL server; histories of schema 4, whose 0 meant "not stated", are read
as such without being touched, and upgraded in place with their 0s as NULL and their link scans kept."""

import dataclasses
import sqlite3

import pytest
from fleet.test_fleet_links import COLS_2, PG_2, SCHEMA_2_INDEX, SCHEMA_2_TABLE, SQLITE_2

from vibkit.fleet import FleetDB
from vibkit.fleet.schema import link_ddl, measurement_values
from vibkit.fleet.trends import unit_trend

from support.fleet import fake

SCHEMA_4 = 4


def _three():
    """Unit E07: a stated sigma, one stated as 0 (exact), one not stated."""
    return [
        fake(1, "E07", 0.0, 1.0),
        dataclasses.replace(fake(2, "E07", 1.0, 1.3), speed_sigma_m_s=0.0),
        dataclasses.replace(fake(3, "E07", 2.0, 1.6), speed_sigma_m_s=None),
    ]


@pytest.fixture(params=["sqlite", "postgresql"])
def store(request, tmp_path):
    if request.param == "sqlite":
        return str(tmp_path / "fleet.sqlite")
    return request.getfixturevalue("new_pg_url")()


def test_stated_zero_and_not_stated_are_kept_apart(store):
    with FleetDB(store) as db:
        for m in _three():
            db.insert(m)
    with FleetDB(store, readonly=True) as db:
        got = {m.sha256: m for m in db.measurements()}
    sig = [got[m.sha256].speed_sigma_m_s for m in _three()]
    assert sig == [0.001, 0.0, None]
    assert [got[m.sha256].speed_sigma_stated for m in _three()] == [True, True, False]
    rep = got[_three()[1].sha256].as_reported()  # a stated 0 keeps its sigmas (the frequency's part)
    assert rep["speed_sigma_m_s"] == 0.0 and rep["elongation_sigma_percent"] == 0.05 and "uncertainty" not in rep
    rep = got[_three()[2].sha256].as_reported()
    assert rep["speed_sigma_m_s"] is None and rep["elongation_sigma_percent"] is None
    # the trend counts the one not stated, not the stated 0
    t = unit_trend("E07", list(got.values()))
    assert [f for f in t.flags if "not stated in 1 measurement(s)" in f]
    assert not t.speed_sigma_stated  # the latest is the one not stated
    t2 = unit_trend("E07", [got[m.sha256] for m in _three()[:2]])
    assert not [f for f in t2.flags if "not stated" in f] and t2.speed_sigma_stated


def _schema4_rows():
    """Schema 4's rows: its 0 meant "not stated" (the only way it could say it)."""
    return [fake(1, "E07", 0.0, 1.0), dataclasses.replace(fake(2, "E07", 1.0, 1.3), speed_sigma_m_s=0.0)]


def _schema4_sqlite(p):
    con = sqlite3.connect(p)
    con.execute(SCHEMA_2_TABLE.format(**SQLITE_2))  # measurement has not changed from schema 2 to 4
    con.execute(SCHEMA_2_INDEX)
    for m in _schema4_rows():
        con.execute(
            f"INSERT INTO measurement ({', '.join(COLS_2)}) VALUES ({', '.join('?' * len(COLS_2))})",
            measurement_values(m),
        )
    for stmt in link_ddl("sqlite"):
        con.execute(stmt)
    con.execute("INSERT INTO link_scan (measurement_id, status, n_links, loops) VALUES (1, 'ok', 159, 3)")
    con.execute("INSERT INTO link_scan (measurement_id, status, reason) VALUES (2, 'not run', 'x')")
    con.execute("INSERT INTO flagged_link (measurement_id, link, excess_pitch_m, feature) VALUES (1, 40, 4e-4, 't')")
    con.execute("PRAGMA application_id = 1447185222")
    con.execute(f"PRAGMA user_version = {SCHEMA_4}")
    con.commit()
    con.close()


def _notnull_sigma(p):
    con = sqlite3.connect(f"file:{p}?mode=ro", uri=True)
    try:
        info = {r[1]: r[3] for r in con.execute("PRAGMA table_info(measurement)")}
        return info["speed_sigma_m_s"], con.execute("PRAGMA user_version").fetchone()[0]
    finally:
        con.close()


def test_schema_4_sqlite_zero_read_as_not_stated_then_upgraded(tmp_path):
    p = tmp_path / "v4.sqlite"
    _schema4_sqlite(p)
    before = p.read_bytes()
    with FleetDB(p, create=False, readonly=True) as db:
        assert [n for n in db.notes if "read a schema-4 history without upgrading it" in n]
        old = sorted(db.measurements(), key=lambda m: m.id)
    assert p.read_bytes() == before and _notnull_sigma(p) == (1, 4)
    assert [m.speed_sigma_m_s for m in old] == [0.001, None]  # its 0 meant "not stated"

    with FleetDB(p) as db:
        assert any("upgraded in place from schema 4 to schema 5" in n for n in db.notes)
        new = sorted(db.measurements(), key=lambda m: m.id)
        scans = db.link_scans()
        db.insert(dataclasses.replace(fake(5, "E07", 2.0, 1.6), speed_sigma_m_s=0.0))  # a stated 0 now fits
    assert _notnull_sigma(p) == (0, 5)
    assert [m.as_dict() for m in new] == [m.as_dict() for m in old]  # the rows as read before, ids kept
    assert scans[1].status == "ok" and [f.link for f in scans[1].flagged] == [40] and scans[2].status == "not run"
    with FleetDB(p) as db:
        assert db.notes == []
        assert [m.speed_sigma_m_s for m in sorted(db.measurements(), key=lambda m: m.id)] == [0.001, None, 0.0]
        con = db._store._con
        assert con.execute("PRAGMA foreign_keys").fetchone()[0] == 1
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        idx = [r[1] for r in con.execute("PRAGMA index_list(measurement)")]
        assert "measurement_unit_date" in idx
    with FleetDB(p) as db:  # the link scans still cascade with their measurement (foreign keys on the new table)
        db._store.execute("DELETE FROM measurement WHERE id = 1")
        assert 1 not in db.link_scans()


def test_schema_4_postgresql_zero_read_as_not_stated_then_upgraded(new_pg_url):
    import psycopg

    url = new_pg_url()
    with psycopg.connect(url, autocommit=True) as con:
        con.execute(SCHEMA_2_TABLE.format(**PG_2))
        con.execute(SCHEMA_2_INDEX)
        for stmt in link_ddl("postgresql"):
            con.execute(stmt)
        con.execute("CREATE TABLE vibkit_fleet_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
        con.execute(
            "INSERT INTO vibkit_fleet_meta VALUES ('application', 'vibkit-fleet'), ('schema_version', %s)",
            (str(SCHEMA_4),),
        )
        for m in _schema4_rows():
            con.execute(
                f"INSERT INTO measurement ({', '.join(COLS_2)}) VALUES ({', '.join(['%s'] * len(COLS_2))})",
                measurement_values(m),
            )
        con.execute("INSERT INTO link_scan (measurement_id, status, reason) SELECT id, 'not run', 'x' FROM measurement")
    with FleetDB(url, readonly=True) as db:
        assert any("read a schema-4 history without upgrading it" in n for n in db.notes)
        old = sorted(db.measurements(), key=lambda m: m.id)
    assert [m.speed_sigma_m_s for m in old] == [0.001, None]
    with psycopg.connect(url) as con:  # nothing written
        assert con.execute("SELECT count(*) FROM measurement WHERE speed_sigma_m_s = 0").fetchone()[0] == 1
    with FleetDB(url) as db:
        assert any("upgraded in place from schema 4 to schema 5" in n for n in db.notes)
        assert [m.as_dict() for m in sorted(db.measurements(), key=lambda m: m.id)] == [m.as_dict() for m in old]
        db.insert(dataclasses.replace(fake(5, "E07", 2.0, 1.6), speed_sigma_m_s=0.0))
        assert len(db.link_scans()) == 3
    with psycopg.connect(url) as con:
        assert con.execute("SELECT value FROM vibkit_fleet_meta WHERE key = 'schema_version'").fetchone()[0] == "5"
        got = con.execute("SELECT speed_sigma_m_s FROM measurement ORDER BY id").fetchall()
    assert [r[0] for r in got] == [0.001, None, 0.0]
