"""A fleet history written by an older vibkit (schema 1), read by the read-only commands without writing anything.

An archived history (the file and its folder read-only) gives ``fleet status`` and ``fleet report`` the same rows
and answers as the same history upgraded in place; its bytes and mtime are left as they were.  A write command
(``fleet add``) still upgrades it in place, as before.  The history: tests/reliability/corpus_fleet.py."""

import json
import os
import shutil
import sqlite3
import stat
from pathlib import Path

import pytest

from vibkit.cli import main
from vibkit.fleet import FleetDB, FleetError
from vibkit.fleet.storage import migrate

from corpus_fleet import SCHEMA_1_ROWS, schema1_db

ROOT = Path(__file__).resolve().parents[2]

NOTE = "read a schema-1 history without upgrading it"


def _user_version(p):
    con = sqlite3.connect(f"file:{p}?mode=ro", uri=True)
    try:
        return con.execute("PRAGMA user_version").fetchone()[0]
    finally:
        con.close()


def _fingerprint(p):
    """Bytes and mtime of the file, and what lies in its folder (SQLite's read-only reader of a WAL file in a folder
    it may write, as root can, makes an empty -wal and a -shm there: those are left out, an empty -wal checked)."""
    st = p.stat()
    wal = p.with_name(p.name + "-wal")
    assert not wal.exists() or wal.stat().st_size == 0
    names = sorted(n for n in os.listdir(p.parent) if not n.endswith(("-wal", "-shm")))
    return p.read_bytes(), st.st_mtime_ns, st.st_size, names


@pytest.fixture(params=["wal", "delete"])
def archive(request, tmp_path):
    """A schema-1 history in a read-only folder (file 0444, folder 0555) and an upgraded copy of it."""
    ro, up = tmp_path / "archive", tmp_path / "upgraded"
    ro.mkdir()
    up.mkdir()
    schema1_db("fleet.sqlite", journal=request.param)(ro)
    shutil.copy(ro / "fleet.sqlite", up / "fleet.sqlite")
    os.chmod(ro / "fleet.sqlite", 0o444)
    os.chmod(ro, 0o555)
    yield ro / "fleet.sqlite", up / "fleet.sqlite"
    os.chmod(ro, 0o755)  # let pytest clean up as a normal user


def test_library_reads_schema_1_read_only_as_upgraded(archive):
    ro, up = archive
    assert _user_version(ro) == 1
    before = _fingerprint(ro)
    with FleetDB(ro, create=False, readonly=True) as db:
        assert len(db.notes) == 1 and NOTE in db.notes[0] and "with write access" in db.notes[0]
        ms_ro, st_ro = db.measurements(), db.status()
        assert db.units() == ["E22", "E23", "E24"] and db.nominal_pitch("E24") == 0.13333
        assert db.find(f"{3:064x}").quality == "implausible"
        assert db.integrity_check() == "ok"
        m = ms_ro[0]
        with pytest.raises(FleetError, match=r"fleet.sqlite: cannot write: .*read-only"):
            db.insert(m.__class__(**{**m.as_dict(), "id": None, "sha256": "f" * 64, "warnings": ()}))
    assert _fingerprint(ro) == before and _user_version(ro) == 1

    with FleetDB(up) as db:  # the same history upgraded in place, as a write command does
        assert any("upgraded in place from schema 1 to schema 5" in n for n in db.notes)
        ms_up, st_up = db.measurements(), db.status()
    assert _user_version(up) == 5
    assert ms_ro == ms_up and len(ms_ro) == len(SCHEMA_1_ROWS)
    assert [t.as_dict() for t in st_ro] == [t.as_dict() for t in st_up]
    # the flags by today's rules: E22's two impossible points, E23's 0.9 % sigma; nothing 'replaced'
    assert [(m.unit, m.quality) for m in ms_ro if m.quality != "ok"] == [
        ("E22", "implausible"),
        ("E22", "implausible"),
        ("E23", "inconclusive"),
    ]
    assert all(m.quality_reason for m in ms_ro if m.quality != "ok")
    assert all(m.quality_reason == "" and not m.replaced for m in ms_ro if m.quality == "ok")
    assert ms_ro[0].warnings == ("clipped",) and ms_ro[0].snr_db is None
    e24 = next(t for t in st_ro if t.unit == "E24")
    assert e24.slope_percent_per_year == pytest.approx(0.4, rel=1e-9)  # 0.3, 0.5, 0.7, 0.9 % half a year apart
    assert e24.latest_elongation_percent == 0.9


def test_cli_status_and_report_on_a_read_only_schema_1_file(archive, tmp_path, capsys):
    ro, up = archive
    before = _fingerprint(ro)
    FleetDB(up).close()  # upgraded in place, as a write command does
    assert _user_version(up) == 5
    out = tmp_path / "out"
    out.mkdir()
    answers = {}
    for name, db in (("ro", ro), ("up", up)):
        capsys.readouterr()
        assert main(["fleet", "status", "--json", "--db", str(db)]) == 0
        cap = capsys.readouterr()
        status = json.loads(cap.out)  # the note is on stderr: stdout stays one JSON document
        if name == "ro":
            assert NOTE in cap.err and "with write access to upgrade it" in cap.err
        else:
            assert NOTE not in cap.err
        assert main(["fleet", "report", "--json", "--db", str(db), "-o", str(out / f"{name}.pdf")]) == 0
        cap = capsys.readouterr()
        report = json.loads(cap.out)
        assert (NOTE in cap.err) == (name == "ro")
        assert (out / f"{name}.pdf").read_bytes()[:5] == b"%PDF-"
        answers[name] = (
            {k: v for k, v in status.items() if k != "database"},
            {k: v for k, v in report.items() if k not in ("database", "output")},
        )
    assert answers["ro"] == answers["up"]
    assert sorted(u["unit"] for u in answers["ro"][0]["units"]) == ["E22", "E23", "E24"]
    assert answers["ro"][1]["units"] == 3
    assert _fingerprint(ro) == before and _user_version(ro) == 1
    assert stat.S_IMODE(ro.stat().st_mode) == 0o444


def test_write_command_upgrades_schema_1_in_place(tmp_path, capsys):
    schema1_db("fleet.sqlite")(tmp_path)
    db = tmp_path / "fleet.sqlite"
    with FleetDB(db, create=False, readonly=True) as fdb:
        seen = fdb.measurements()
    rec = ROOT / "data" / "fleet-example" / "E07" / "2026-11-23.csv"
    assert (
        main(
            [
                "fleet",
                "add",
                str(rec),
                "--db",
                str(db),
                "--unit",
                "E07",
                "--speed",
                "0.5",
                "--nominal-pitch",
                "0.13333",
                "--json",
            ]
        )
        == 0
    )
    cap = capsys.readouterr()
    assert json.loads(cap.out)["measurement"]["unit"] == "E07"
    assert "upgraded in place from schema 1 to schema 5" in cap.err
    assert _user_version(db) == 5
    with FleetDB(db, create=False, readonly=True) as fdb:
        assert fdb.notes == []  # schema 5 now: nothing to say
        ms = fdb.measurements()
    assert [m for m in ms if m.unit != "E07"] == seen and [m.unit for m in ms].count("E07") == 1


def test_migrate_reads_a_schema_1_source_without_upgrading_it(archive, tmp_path):
    ro, _ = archive
    before = _fingerprint(ro)
    r = migrate(ro, tmp_path / "new.sqlite")
    assert r["copied"] == len(SCHEMA_1_ROWS) and r["skipped"] == 0
    with FleetDB(ro, readonly=True) as a, FleetDB(tmp_path / "new.sqlite") as b:
        strip = [{**m.as_dict(), "id": None} for m in a.measurements()]
        assert strip == [{**m.as_dict(), "id": None} for m in b.measurements()]
    assert _fingerprint(ro) == before and _user_version(ro) == 1
