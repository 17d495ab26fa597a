"""The fleet's two stores alike: a SQLite file and a real PostgreSQL server that this suite starts with
pgserver (session-scoped, in a private temporary folder).  8 processes adding at once store every
measurement exactly once; a killed scan leaves complete rows only; a migration round-trips."""

import dataclasses
import datetime as dt
import multiprocessing
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.fleet import DuplicateRecordingError, FleetDB, FleetError, Measurement
from vibkit.fleet.storage import migrate

from support.fleet import NOMINAL, T0, fake

ROOT = Path(__file__).resolve().parents[2]


# pg_server: the session's PostgreSQL server (tests/fleet/conftest.py)
_N_DB = [0]


def _fresh_pg_url(srv):
    import psycopg

    _N_DB[0] += 1
    name = f"fleet_{os.getpid()}_{_N_DB[0]}"
    with psycopg.connect(srv.get_uri(), autocommit=True) as con:
        con.execute(f"CREATE DATABASE {name}")
    return srv.get_uri(name)


@pytest.fixture(params=["sqlite", "postgresql"])
def store(request, tmp_path):
    """A fresh, empty fleet database of each kind: its path or URL."""
    if request.param == "sqlite":
        return str(tmp_path / "fleet.sqlite")
    return _fresh_pg_url(request.getfixturevalue("pg_server"))


def _fleet(n=24):
    return [
        fake(
            i,
            f"U{i % 4}",
            0.25 * (i // 4),
            0.3 + 0.1 * (i // 4),
            quality="inconclusive" if i == 7 else "ok",
            replaced=(i == 21),
        )
        for i in range(n)
    ]


def _adder(db, order, start, queue):
    """One technician: wait for the others, then store every measurement in its own order."""
    ms = _fleet()
    added, dup, other = [], 0, []
    try:
        with FleetDB(db) as fdb:
            start.wait(timeout=60)
            for k in order:
                try:
                    added.append(fdb.insert(ms[k]).sha256)
                except DuplicateRecordingError:
                    dup += 1
                except Exception as exc:  # noqa: BLE001 - reported to the test
                    other.append(f"{type(exc).__name__}: {exc}")
    except Exception as exc:  # noqa: BLE001
        other.append(f"open: {type(exc).__name__}: {exc}")
    queue.put((added, dup, other))


def test_eight_processes_add_at_once(store):
    n, procs = 24, 8
    ctx = multiprocessing.get_context("fork")
    start, queue = ctx.Barrier(procs), ctx.Queue()
    orders = [random.Random(p).sample(range(n), n) for p in range(procs)]
    ps = [ctx.Process(target=_adder, args=(store, o, start, queue)) for o in orders]
    for p in ps:
        p.start()
    results = [queue.get(timeout=240) for _ in ps]
    for p in ps:
        p.join(timeout=60)
    assert all(p.exitcode == 0 for p in ps)
    assert [r[2] for r in results] == [[]] * procs  # no error other than "already stored"
    added = [sha for r in results for sha in r[0]]
    assert sorted(added) == sorted(m.sha256 for m in _fleet())  # each stored by exactly one process
    assert all(len(r[0]) + r[1] == n for r in results)
    with FleetDB(store, create=False) as db:
        rows = db.measurements()
        assert db.integrity_check() == "ok"
    assert len(rows) == n == len({m.sha256 for m in rows}) == len({m.id for m in rows})
    want = {m.sha256: m for m in _fleet()}
    for m in rows:  # complete and true to what was stored
        assert dataclasses.replace(m, id=None) == want[m.sha256]


def test_same_store_semantics(store):
    with FleetDB(store) as db:
        a = db.insert(fake(1, "E1", 0.0, 0.5))
        with pytest.raises(DuplicateRecordingError, match="already stored .* #%d of unit 'E1'" % a.id):
            db.insert(fake(1, "E2", 0.5, 0.6))
        with pytest.raises(FleetError, match="one unit has one nominal pitch"):
            db.insert(fake(2, "E1", 0.5, 0.6, nominal=0.1016))
        b = db.insert(fake(3, "E1", 1.0, 0.7, quality="implausible", replaced=True))
        assert db.find(b.sha256) == b and b.replaced is True and b.quality == "implausible"
        assert db.nominal_pitch("E1") == NOMINAL and db.units() == ["E1"] and db.nominal_pitch("E9") is None
        assert [m.id for m in db.measurements("E1")] == [a.id, b.id]
        (tr,) = db.status()
        assert tr.n_measurements == 2 and tr.n_used == 1 and tr.flagged[0]["quality"] == "implausible"


def test_migration_round_trips(tmp_path, pg_server, capsys):
    src = tmp_path / "old.sqlite"
    with FleetDB(src) as db:
        for m in _fleet(12):
            db.insert(m)
        before = [dataclasses.replace(m, id=None) for m in db.measurements()]
    url = _fresh_pg_url(pg_server)
    assert main(["fleet", "migrate", "--from", str(src), "--to", url, "--json"]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert (d["copied"], d["skipped"], d["target_total"]) == (12, 0, 12)
    back = tmp_path / "back.sqlite"
    r = migrate(url, back)
    assert (r["copied"], r["target_total"]) == (12, 12)
    with FleetDB(back, create=False) as db:
        after = [dataclasses.replace(m, id=None) for m in db.measurements()]
    assert after == before  # every field, flags and provenance included
    # again: nothing copied twice
    assert migrate(src, url)["copied"] == 0 and migrate(src, url)["skipped"] == 12
    # a unit with another nominal pitch in the target: refused, nothing copied
    other = tmp_path / "other.sqlite"
    with FleetDB(other) as db:
        db.insert(fake(100, "U0", 3.0, 1.0, nominal=0.1016))
        db.insert(fake(101, "U9", 3.0, 1.0))
    with pytest.raises(FleetError, match="one unit has one nominal pitch"):
        migrate(other, url)
    with FleetDB(url, create=False) as db:
        assert len(db.measurements()) == 12 and db.units() == ["U0", "U1", "U2", "U3"]
    with pytest.raises(FleetError, match="same database"):
        migrate(src, src)


def test_postgres_refusals(pg_server):
    import psycopg

    url = _fresh_pg_url(pg_server)
    with pytest.raises(FleetError, match="no fleet database here"):
        FleetDB(url, create=False)
    with psycopg.connect(url, autocommit=True) as con:
        con.execute("CREATE TABLE measurement (n INTEGER)")
    with pytest.raises(FleetError, match="not a vibkit fleet's"):
        FleetDB(url)
    bad = url.replace("?host=", "?connect_timeout=2&host=").replace(url.split("?host=")[1], "/nonexistent")
    with pytest.raises(FleetError, match="cannot connect to the PostgreSQL server.*PGPASSWORD"):
        FleetDB(bad)
    assert main(["fleet", "status", "--db", bad]) == 1
    # the connection lost mid-session (server restarted, network): one clear error, nothing half-stored
    url2 = _fresh_pg_url(pg_server)
    with FleetDB(url2) as db:
        with psycopg.connect(url2, autocommit=True) as con:
            con.execute(
                "SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE application_name = "
                "'vibkit fleet' AND datname = current_database()"
            )
        with pytest.raises(FleetError, match="connection was lost|query failed"):
            db.insert(fake(9, "E9", 0.0, 0.4))
    with FleetDB(url2) as db:
        assert db.measurements() == []


def _synth(path, pitch_m, seed, fs=200.0, duration=10.0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs)) / fs
    f = 0.5 / pitch_m
    x = rng.standard_normal(t.size)
    for k, a in enumerate((1.0, 0.5, 0.3), 1):
        x += a * np.cos(2 * np.pi * k * f * t + rng.uniform(0, 2 * np.pi))
    path.write_text("time_s,accel_m_s2\n" + "".join(f"{ti:.3f},{xi:.6f}\n" for ti, xi in zip(t, x)))


@pytest.mark.slow
def test_killed_scan_on_postgres_leaves_complete_rows(tmp_path, pg_server):
    import psycopg

    url = _fresh_pg_url(pg_server)
    d = tmp_path / "visits"
    d.mkdir()
    n = 80  # the scan stores its first batch after a second of analyses: many more are left then
    rows = ["file,unit,speed_m_s,date,nominal_pitch_m"]
    for i in range(n):
        _synth(d / f"r{i:02d}.csv", NOMINAL * (1 + 0.0002 * i), 2000 + i)
        rows.append(f"r{i:02d}.csv,U{i % 3},0.5,{(T0 + dt.timedelta(days=15 * i)).date()},{NOMINAL}")  # all past
    cat = tmp_path / "units.csv"
    cat.write_text("\n".join(rows) + "\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "vibkit",
            "fleet",
            "scan",
            str(d),
            "--catalogue",
            str(cat),
            "--db",
            url,
            "--workers",
            "0",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )
    stored = 0
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with psycopg.connect(url, autocommit=True) as con:
                    stored = con.execute("SELECT count(*) FROM measurement").fetchone()[0]
            except psycopg.Error:
                stored = 0
            if stored >= 3:
                break
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL, "the scan ended before it could be killed"
    import hashlib

    with FleetDB(url) as db:
        assert db.integrity_check() == "ok"
        ms = db.measurements()
        assert 3 <= len(ms) < n
        for m in ms:
            # every column written (the catalogue states no speed uncertainty: stored as not stated, None)
            assert all(
                getattr(m, c) is not None for c in m.__dataclass_fields__ if c not in ("snr_db", "speed_sigma_m_s")
            )
            assert m.speed_sigma_m_s is None
            assert hashlib.sha256(Path(m.path).read_bytes()).hexdigest() == m.sha256 and m.quality == "ok"
        res = db.scan(d, cat, parallel=False)
        assert len(res.skipped) == len(ms) and len(res.added) == n - len(ms) and not res.failed
        assert len(db.measurements()) == n


def _v1_schema():
    """The schema-1 DDL, written once in tests/reliability/corpus_fleet.py."""
    from corpus_fleet import SCHEMA_1_DDL

    return SCHEMA_1_DDL


def test_version_1_sqlite_file_is_upgraded_and_flagged(tmp_path):
    import sqlite3

    p = tmp_path / "v1.sqlite"
    con = sqlite3.connect(p)
    con.executescript(_v1_schema())
    cols = [f for f in Measurement.__dataclass_fields__ if f not in ("id", "quality", "quality_reason", "replaced")]
    for m in (fake(1, "E22", 0.0, 3.8, s=0.1), fake(2, "E22", 0.5, -5.8, s=0.3), fake(3, "E22", 1.0, 52.0, s=0.4)):
        vals = [("[]" if c == "warnings" else getattr(m, c)) for c in cols]
        con.execute(f"INSERT INTO measurement ({', '.join(cols)}) VALUES ({', '.join('?' * len(cols))})", vals)
    con.commit()
    con.close()
    with FleetDB(p) as db:
        ms = db.measurements("E22")
        (tr,) = db.status()
    assert [m.quality for m in ms] == ["ok", "implausible", "implausible"]
    assert "physical window" in ms[2].quality_reason and not any(m.replaced for m in ms)
    # a unit with two impossible points: no -112 %/year trend, both flagged
    assert tr.slope_percent_per_year is None and tr.latest_elongation_percent == 3.8 and len(tr.flagged) == 2
    con = sqlite3.connect(p)
    assert con.execute("PRAGMA user_version").fetchone()[0] == 5
    con.close()


def test_environment_variable_names_the_server(pg_server, monkeypatch, tmp_path, capsys):
    url = _fresh_pg_url(pg_server).replace("postgresql://postgres:@", "postgresql://postgres:secret@")
    monkeypatch.setenv("VIBKIT_FLEET_DB", url)
    with FleetDB() as db:
        assert db.kind == "postgresql" and db.local_files == ()
        assert "secret" not in db.path and "postgres:***@" in db.path  # the password is never printed
        db.insert(fake(5, "E5", 0.0, 0.4))
        db.insert(fake(6, "E5", 1.0, 0.6))
    assert main(["fleet", "status"]) == 0
    assert main(["fleet", "report", "-o", str(tmp_path / "f.pdf")]) == 0
    out = capsys.readouterr().out
    assert "E5" in out and "secret" not in out and (tmp_path / "f.pdf").read_bytes()[:5] == b"%PDF-"
