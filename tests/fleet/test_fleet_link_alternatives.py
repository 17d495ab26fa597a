"""A flagged link the recording cannot place uniquely ("55 or 10"): its alternatives stored and read back on SQLite
and PostgreSQL (a real server), schema-3 histories read as they are and upgraded in place with every row and flag
kept, migrated with their measurements, and the comparison across visits that takes an earlier "10 or 55" for the
link now flagged as 55."""

import json
import sqlite3

import pytest
from fleet.test_fleet_links import COLS_2, PG_2, SCHEMA_2_INDEX, SCHEMA_2_TABLE, SQLITE_2, _rows, _user_version

from vibkit.cli import main
from vibkit.diagnose.report import write_fleet_report
from vibkit.fleet import FleetDB
from vibkit.fleet.links import FlaggedLink, LinkScan
from vibkit.fleet.schema import measurement_values
from vibkit.fleet.storage import migrate

from support.fleet import fake

MM = 1e-3

#: the link tables as schema 3 wrote them (frozen here: the upgrade is tested against what old histories hold)
SCHEMA_3_LINKS = [
    """CREATE TABLE link_scan (
    measurement_id {MID} PRIMARY KEY REFERENCES measurement (id) ON DELETE CASCADE,
    status TEXT NOT NULL CHECK (status IN ('ok', 'inconclusive', 'too few loops', 'failed', 'not run')),
    reason TEXT NOT NULL DEFAULT '',
    n_links INTEGER CHECK (n_links IS NULL OR n_links >= 2),
    loops INTEGER,
    marker_s {REAL} CHECK (marker_s IS NULL OR marker_s >= 0),
    method TEXT NOT NULL DEFAULT '',
    false_alarm {REAL}
)""",
    """CREATE TABLE flagged_link (
    measurement_id {MID} NOT NULL REFERENCES link_scan (measurement_id) ON DELETE CASCADE,
    link INTEGER NOT NULL CHECK (link >= 1),
    excess_pitch_m {REAL},
    sigma_m {REAL} CHECK (sigma_m IS NULL OR sigma_m >= 0),
    statistic {REAL},
    feature TEXT NOT NULL DEFAULT '',
    loops TEXT NOT NULL DEFAULT '[]',
    PRIMARY KEY (measurement_id, link)
)""",
]
#: what the schema-3 rows hold: measurement 1 a scan flagging links 12 and 40, the others "not run"
SCAN_3 = "INSERT INTO link_scan VALUES (1, 'ok', '', 159, 3, 12.5, 'worn-link signature', 0.01)"
NOT_RUN_3 = (
    "INSERT INTO link_scan (measurement_id, status, reason) VALUES ({0}, 'not run', 'old'), ({1}, 'not run', 'old')"
)
FLAGS_3 = [
    "INSERT INTO flagged_link VALUES (1, 12, 0.0004, 0.00005, 8.0, 'signature', '[1, 2, 3]')",
    "INSERT INTO flagged_link VALUES (1, 40, NULL, NULL, 6.5, 'level', '[2]')",
]


def _scan(flags, marker=12.5):
    """A stored-like link scan: flags (link, excess [mm], sigma [mm], alternatives)."""
    return LinkScan(
        "ok",
        n_links=90,
        loops=3,
        marker_s=marker,
        method="worn-link signature of the scene",
        false_alarm=0.01,
        flagged=tuple(FlaggedLink(n, x * MM, s * MM, (1, 2), 8.0, "signature", tuple(a)) for n, x, s, a in flags),
    )


@pytest.fixture(params=["sqlite", "postgresql"])
def store(request, tmp_path):
    if request.param == "sqlite":
        return str(tmp_path / "fleet.sqlite")
    return request.getfixturevalue("new_pg_url")()


def _flags_of_12_and_40(scans):
    (s,) = [s for s in scans.values() if s.status == "ok"]
    return [(f.link, f.alternatives, f.excess_pitch_m, f.loops, f.feature) for f in s.flagged]


OLD_FLAGS = [(12, (), 0.0004, (1, 2, 3), "signature"), (40, (), None, (2,), "level")]


# ------------------------------------------------------------------------------------------ storage
def test_alternatives_round_trip(store):
    scan = _scan([(55, 1.0, 0.1, (10,)), (30, 0.5, 0.1, ())])
    with FleetDB(store) as db:
        a = db.insert(fake(1, "E07", 0.0, 1.0), scan)
    with FleetDB(store, readonly=True) as db:
        got = db.link_scans()[a.id]
    assert got.flagged == tuple(sorted(scan.flagged, key=lambda f: f.link))  # read back by link
    assert [(f.link, f.alternatives, f.label) for f in got.flagged] == [(30, (), "30"), (55, (10,), "55 or 10")]


def test_migration_keeps_the_alternatives(tmp_path, new_pg_url):
    src = tmp_path / "src.sqlite"
    scan = _scan([(55, 1.0, 0.1, (10,))])
    with FleetDB(src) as db:
        db.insert(fake(1, "E07", 0.0, 1.0), scan)
    url = new_pg_url()
    assert migrate(src, url)["copied"] == 1
    with FleetDB(url, readonly=True) as db:
        (s,) = db.link_scans().values()
    assert s.flagged == scan.flagged and s.flagged[0].label == "55 or 10"


def test_schema_3_sqlite_read_only_then_upgraded_with_its_rows_and_flags(tmp_path):
    p = tmp_path / "v3.sqlite"
    con = sqlite3.connect(p)
    con.execute(SCHEMA_2_TABLE.format(**SQLITE_2))
    con.execute(SCHEMA_2_INDEX)
    for m in _rows():
        con.execute(
            f"INSERT INTO measurement ({', '.join(COLS_2)}) VALUES ({', '.join('?' * len(COLS_2))})",
            measurement_values(m),
        )
    for stmt in [t.format(MID="INTEGER", REAL="REAL") for t in SCHEMA_3_LINKS] + [SCAN_3, NOT_RUN_3.format(2, 3)]:
        con.execute(stmt)
    for stmt in FLAGS_3:
        con.execute(stmt)
    con.execute("PRAGMA application_id = 1447185222")
    con.execute("PRAGMA user_version = 3")
    con.commit()
    con.close()
    before = p.read_bytes()
    with FleetDB(p, create=False, readonly=True) as db:
        assert [n for n in db.notes if "read a schema-3 history without upgrading it" in n]
        old = db.measurements()
        assert _flags_of_12_and_40(db.link_scans()) == OLD_FLAGS
    assert p.read_bytes() == before and _user_version(p) == 3

    with FleetDB(p) as db:
        assert any("upgraded in place from schema 3 to schema 5" in n for n in db.notes)
        assert [m.as_dict() for m in db.measurements()] == [m.as_dict() for m in old]
        scans = db.link_scans()
        assert _flags_of_12_and_40(scans) == OLD_FLAGS
        assert sorted(s.status for s in scans.values()) == ["not run", "not run", "ok"]
        new = db.insert(fake(9, "E07", 3.0, 1.5), _scan([(55, 1.0, 0.1, (10,))]))
    assert _user_version(p) == 5
    with FleetDB(p, readonly=True) as db:
        assert db.notes == [] and db.link_scans()[new.id].flagged[0].alternatives == (10,)


def test_schema_3_postgresql_read_only_then_upgraded_with_its_rows_and_flags(new_pg_url):
    import psycopg

    url = new_pg_url()
    with psycopg.connect(url, autocommit=True) as con:
        con.execute(SCHEMA_2_TABLE.format(**PG_2))
        con.execute("CREATE TABLE vibkit_fleet_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
        con.execute("INSERT INTO vibkit_fleet_meta VALUES ('application', 'vibkit-fleet'), ('schema_version', '3')")
        for m in _rows():
            con.execute(
                f"INSERT INTO measurement ({', '.join(COLS_2)}) VALUES ({', '.join(['%s'] * len(COLS_2))})",
                measurement_values(m),
            )
        ids = [r[0] for r in con.execute("SELECT id FROM measurement ORDER BY id").fetchall()]
        assert ids == [1, 2, 3]
        for stmt in [t.format(MID="BIGINT", REAL="DOUBLE PRECISION") for t in SCHEMA_3_LINKS] + [
            SCAN_3,
            NOT_RUN_3.format(2, 3),
            *FLAGS_3,
        ]:
            con.execute(stmt)
    with FleetDB(url, readonly=True) as db:
        assert any("read a schema-3 history without upgrading it (no alternative link numbers)" in n for n in db.notes)
        old = db.measurements()
        assert _flags_of_12_and_40(db.link_scans()) == OLD_FLAGS
    with psycopg.connect(url) as con:
        cols = con.execute("SELECT column_name FROM information_schema.columns WHERE table_name = 'flagged_link'")
        assert "alternatives" not in {r[0] for r in cols.fetchall()}  # nothing written
    with FleetDB(url) as db:
        assert any("upgraded in place from schema 3 to schema 5" in n for n in db.notes)
        assert [m.as_dict() for m in db.measurements()] == [m.as_dict() for m in old]
        assert _flags_of_12_and_40(db.link_scans()) == OLD_FLAGS
        new = db.insert(fake(9, "E07", 3.0, 1.5), _scan([(55, 1.0, 0.1, (10,))]))
    with FleetDB(url, readonly=True) as db:
        assert db.notes == [] and db.link_scans()[new.id].flagged[0].alternatives == (10,)
    with psycopg.connect(url) as con:
        assert con.execute("SELECT value FROM vibkit_fleet_meta WHERE key = 'schema_version'").fetchone()[0] == "5"


# ------------------------------------------------------------------------------------------ history
def _visits(path, *scans):
    with FleetDB(path) as db:
        for i, flags in enumerate(scans):
            db.insert(fake(i + 1, "E07", float(i), 1.0 + 0.1 * i), _scan(flags))
    with FleetDB(path, readonly=True) as db:
        return db.links_history("E07")


def test_a_link_flagged_before_as_an_alternative_is_not_new_and_is_compared(tmp_path):
    """The earlier visit said "10 or 55" (10 stored as best); the link is 55, now 1.0 mm against 0.5 mm then."""
    h = _visits(tmp_path / "f.sqlite", [(10, 0.5, 0.1, (55,))], [(55, 1.0, 0.1, ())])
    (x,) = h.links
    assert (x.label, x.verdict) == ("55", "worse")  # 0.5 mm against 2 x 0.14 mm: not "new"
    assert x.detail == "+0.50 mm on 2023-01-15 as 10 or 55 -> +1.00 mm: +0.50 +- 0.14 mm"
    assert [(v.link, v.alternatives) for v in x.visits] == [(10, (55,)), (55, ())]
    # within 2 sigma of the earlier flag: unchanged, still compared with the earlier "10 or 55"
    (y,) = _visits(tmp_path / "g.sqlite", [(10, 0.5, 0.1, (55,))], [(55, 0.6, 0.1, ())]).links
    assert y.verdict == "unchanged" and "as 10 or 55" in y.detail


def test_an_ambiguous_flag_says_so_and_a_link_sharing_no_number_is_new(tmp_path):
    h = _visits(tmp_path / "f.sqlite", [(55, 0.5, 0.1, ())], [(55, 1.0, 0.1, (10,)), (30, 0.4, 0.1, (75,))])
    by = {x.link: x for x in h.links}
    assert [x.label for x in h.links] == ["55 or 10", "30 or 75"]  # worse first, then new
    assert by[55].verdict == "worse" and by[55].detail.endswith(
        "; ambiguous: link 55 or 10, the recording cannot tell which (look at both)"
    )
    assert by[30].verdict == "new" and by[30].detail.startswith("flagged now (+0.40 mm), none of them on 2023-01-15")
    # an ambiguous link not flagged now is named by what the earlier visit said
    (z,) = _visits(tmp_path / "g.sqlite", [(10, 0.5, 0.1, (55,))], []).links
    assert (z.verdict, z.detail) == ("not flagged now", "flagged on 2023-01-15 as 10 or 55 (+0.50 mm), not now")


def test_status_json_text_and_report_give_both_numbers(tmp_path, capsys):
    p = tmp_path / "f.sqlite"
    _visits(p, [(10, 0.5, 0.1, (55,))], [(55, 1.0, 0.1, (10,))])
    assert main(["fleet", "status", "--db", str(p), "--json"]) == 0
    (u,) = json.loads(capsys.readouterr().out)["units"]
    (link,) = u["links"]
    assert (link["link"], link["alternatives"], link["verdict"]) == (55, [10], "worse")
    assert [(v["link"], v["alternatives"]) for v in link["visits"]] == [(10, [55]), (55, [10])]
    assert [s["flagged"][0]["alternatives"] for s in u["link_scans"]] == [[55], [10]]
    assert main(["fleet", "status", "--db", str(p)]) == 0
    out = capsys.readouterr().out
    row = next(r for r in out.splitlines() if r.startswith("55 or 10"))
    assert row.split()[3] == "worse" and "as 10 or 55" in row, out
    with FleetDB(p, readonly=True) as db:
        trends, meas = db.status(), db.measurements()
        links = {t.unit: db.links_history(t.unit) for t in trends}
    rep = write_fleet_report(trends, meas, tmp_path / "fleet.pdf", links=links)
    (texts,) = [t for title, t in rep.pages if title == "fleet links"]
    assert texts[texts.index("55 or 10") + 1] == "worse"


def test_an_earlier_ambiguous_flag_is_the_link_of_its_best_number_when_both_are_flagged_now(tmp_path):
    """The earlier "55 or 10"; now 10 and 55 each flagged alone: 55 (its best number) is compared, 10 is new."""
    h = _visits(tmp_path / "f.sqlite", [(55, 0.5, 0.1, (10,))], [(10, 0.4, 0.1, ()), (55, 1.0, 0.1, ())])
    assert [(x.link, x.verdict) for x in h.links] == [(55, "worse"), (10, "new")]
    assert "as 55 or 10" in h.links[0].detail
