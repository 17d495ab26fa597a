"""Racing processes on one new fleet database: a failing ``fleet add`` never removes a database another
process created and filled meanwhile, and two processes creating the same new store at the same moment
both store their rows.  Real processes (``vibkit fleet add``), ordered by files they wait for; every wait
is bounded."""

import hashlib
import os
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
VISITS = [ROOT / "data" / "fleet-example" / "E07" / f"{d}.csv" for d in ("2024-11-20", "2025-11-19")]
ADD = ["fleet", "add", "--unit", "E07", "--speed", "0.5", "--speed-uncertainty", "0.1%", "--nominal-pitch", "0.13333"]
LIMIT_S = 240

CHILD = """
import json, sys, time, os
{prelude}
from vibkit.cli import main
sys.exit(main(json.loads(sys.argv[1])))
"""

# the failing add: once it has opened the database (which did not exist), it waits until another process has
# stored a row in it, then fails as a bad recording would
FAIL_AFTER_OTHER_STORED = """
import sqlite3
import vibkit.fleet.storage as _st
from vibkit.fleet.errors import FleetError
def _fail(*a, **k):
    print("READY", flush=True)
    db, t0 = os.environ["RACE_DB"], time.monotonic()
    while time.monotonic() - t0 < 200:
        try:
            con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=1)
            n = con.execute("SELECT count(*) FROM measurement").fetchone()[0]
            con.close()
            if n:
                break
        except sqlite3.Error:
            pass
        time.sleep(0.05)
    raise FleetError("a recording that cannot be analysed (planted failure)")
_st.measure_with_links = _fail  # where fleet add calls it (imported at the top of storage)
"""

# a good add held at its first write (the database not yet made) until the parent says go
HOLD_FIRST_WRITE = """
import vibkit.fleet.sqlite_store as _ss
_orig = _ss.SQLiteStore._materialise
def _held(self):
    print("READY", flush=True)
    t0 = time.monotonic()
    while not os.path.exists(os.environ["RACE_GO"]) and time.monotonic() - t0 < 200:
        time.sleep(0.01)
    return _orig(self)
_ss.SQLiteStore._materialise = _held
"""


def _start(argv, prelude, env):
    return subprocess.Popen(
        [sys.executable, "-c", CHILD.format(prelude=prelude), __import__("json").dumps(argv)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _ready(proc):
    t0 = time.monotonic()
    while time.monotonic() - t0 < LIMIT_S:
        line = proc.stdout.readline()
        if not line or line.strip() == "READY":
            return line.strip() == "READY"
    return False


def _finish(proc):
    try:
        out, err = proc.communicate(timeout=LIMIT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"a racing process did not end within {LIMIT_S} s: {err[-500:]}")
    return proc.returncode, out, err


def _rows(db):
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        return sorted(r[0] for r in con.execute("SELECT sha256 FROM measurement"))
    finally:
        con.close()


def _env(tmp_path, **kw):
    env = dict(os.environ, PYTHONPATH=str(ROOT), VIBKIT_PROGRESS_INTERVAL="1e9", **kw)
    env.pop("VIBKIT_FLEET_DB", None)
    return env


@pytest.mark.slow
def test_a_failing_add_never_removes_a_database_another_process_filled(tmp_path):
    db = tmp_path / "new.sqlite"
    env = _env(tmp_path, RACE_DB=str(db))
    failing = _start(ADD + [str(VISITS[1]), "--db", str(db)], FAIL_AFTER_OTHER_STORED, env)
    try:
        assert _ready(failing), "the failing add never reached its analysis"
        assert not db.exists()  # it opened a database that did not exist, and made none
        good = _start(ADD + [str(VISITS[0]), "--db", str(db)], "", env)
        rc_good, out_good, err_good = _finish(good)
    finally:
        rc_fail, _, err_fail = _finish(failing)
    assert rc_good == 0 and out_good.startswith("stored #1"), err_good
    assert rc_fail == 1 and "planted failure" in err_fail and "Traceback" not in err_fail
    assert db.exists(), "the database the good add stored into was removed"
    assert _rows(db) == [hashlib.sha256(VISITS[0].read_bytes()).hexdigest()]


@pytest.mark.slow
def test_two_processes_creating_one_new_store_both_store(tmp_path):
    db, go = tmp_path / "new.sqlite", tmp_path / "go"
    env = _env(tmp_path, RACE_GO=str(go))
    procs = [_start(ADD + [str(v), "--db", str(db)], HOLD_FIRST_WRITE, env) for v in VISITS]
    try:
        for p in procs:
            assert _ready(p), "a racing add never reached its first write"
        assert not db.exists()  # neither has made the file yet: both make it now, at once
        go.write_text("go")
    finally:
        results = [_finish(p) for p in procs]
    for rc, out, err in results:
        assert rc == 0 and out.startswith("stored #"), err
    assert _rows(db) == sorted(hashlib.sha256(v.read_bytes()).hexdigest() for v in VISITS)
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    con.close()
