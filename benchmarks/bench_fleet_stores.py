"""Benchmark of the fleet's two stores: SQLite file against a PostgreSQL server (started with pgserver).

Run:  python benchmarks/bench_fleet_stores.py [--quick]

* ``cost per insert``: one process stores already analysed measurements one by one (one
  transaction each: duplicate check, the unit's nominal pitch, INSERT, commit): ms per measurement;
* ``recordings/s vs writers``: N processes (technicians) each ``FleetDB.add`` their share of the
  synthetic recordings (10 s at 200 Hz, CSV: read, hash, analyse, store) into one fresh database
  at once; total recordings per second.

Writes ``benchmarks/results/fleet_stores.{md,csv}`` (``_quick`` with ``--quick``) with the machine, the date and
the load average.  Needs ``pgserver`` and ``psycopg`` (``pip install -e '.[test]'``).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import multiprocessing
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

from _common import RESULTS, machine, markdown_table, write_csv, write_text
from bench_fleet import NOMINAL, SPEED, synth


def _adder(db, files, start, q):
    from vibkit.fleet import FleetDB

    with FleetDB(db) as fdb:
        start.wait()
        for i, f in files:
            fdb.add(
                f,
                unit=f"U{i % 10:02d}",
                speed=SPEED,
                nominal_pitch=NOMINAL,
                date=(dt.date(2022, 1, 1) + dt.timedelta(days=7 * i)).isoformat(),
            )
    q.put(len(files))


def _writers(db, files, n):
    ctx = multiprocessing.get_context("fork")
    start, q = ctx.Barrier(n + 1), ctx.Queue()
    ps = [ctx.Process(target=_adder, args=(db, files[k::n], start, q)) for k in range(n)]
    for p in ps:
        p.start()
    start.wait()
    t0 = time.perf_counter()
    done = sum(q.get(timeout=600) for _ in ps)
    wall = time.perf_counter() - t0
    for p in ps:
        p.join()
    assert done == len(files)
    return wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    n_rec = 16 if a.quick else 48
    n_ins = 100 if a.quick else 400
    writers = [1, 2, 4] if a.quick else [1, 2, 4, 8]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import pgserver
    import psycopg

    import vibkit
    from vibkit.fleet import FleetDB
    from vibkit.fleet.measurement import analyse_recording

    load0 = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-fleet-stores-") as tmp:
        tmp = Path(tmp)
        pgdata = tempfile.mkdtemp(prefix="vibkit-pg-bench-")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            srv = pgserver.get_server(pgdata, cleanup_mode="delete")
        try:
            k = [0]

            def fresh(kind):
                k[0] += 1
                if kind == "sqlite":
                    return str(tmp / f"f{k[0]}.sqlite")
                with psycopg.connect(srv.get_uri(), autocommit=True) as con:
                    con.execute(f"CREATE DATABASE b{k[0]}")
                return srv.get_uri(f"b{k[0]}")

            with psycopg.connect(srv.get_uri(), autocommit=True) as con:
                pgver = con.execute("SHOW server_version").fetchone()[0]
            rec = tmp / "visits"
            rec.mkdir()
            files = []
            for i in range(n_rec):
                p = rec / f"r{i:03d}.csv"
                synth(p, NOMINAL * (1 + 0.0001 * i), i, 10.0)
                files.append((i, str(p)))
            m0 = analyse_recording(files[0][1], unit="U", speed=SPEED, nominal_pitch=NOMINAL, date="2024-01-01")
            for kind in ("sqlite", "postgresql"):
                db = fresh(kind)
                ms = [dataclasses.replace(m0, sha256=f"{j:064x}", unit=f"U{j % 10}") for j in range(n_ins)]
                with FleetDB(db) as fdb:
                    t0 = time.perf_counter()
                    for m in ms:
                        fdb.insert(m)
                    wall = time.perf_counter() - t0
                rows.append(
                    {
                        "store": kind,
                        "case": "cost per insert (1 process)",
                        "writers": 1,
                        "items": n_ins,
                        "wall_s": wall,
                        "per_item_ms": 1e3 * wall / n_ins,
                        "items_per_s": n_ins / wall,
                    }
                )
                print(rows[-1], file=sys.stderr)
                for w in writers:
                    wall = _writers(fresh(kind), files, w)
                    rows.append(
                        {
                            "store": kind,
                            "case": "fleet add of recordings",
                            "writers": w,
                            "items": n_rec,
                            "wall_s": wall,
                            "per_item_ms": 1e3 * wall / n_rec,
                            "items_per_s": n_rec / wall,
                        }
                    )
                    print(rows[-1], file=sys.stderr)
        finally:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                srv.cleanup()
    load1 = os.getloadavg()
    suffix = "_quick" if a.quick else ""
    write_csv(RESULTS / f"fleet_stores{suffix}.csv", rows)
    head = [
        "# Fleet stores: SQLite file against PostgreSQL (pgserver, Unix socket, same machine)",
        "",
        f"cost per insert: {n_ins} analysed measurements stored one transaction each by one process; fleet add: "
        f"{n_rec} synthetic recordings (10 s at 200 Hz, CSV) added by N processes at once (read, hash, analyse, "
        "store). PostgreSQL runs on the same machine and competes for its cores.",
        "",
        f"Machine: {machine()}; vibkit {vibkit.__version__}; PostgreSQL {pgver} (pgserver).",
        f"Date: {dt.datetime.now(dt.timezone.utc).isoformat(timespec='seconds')}. Load average (1/5/15 min) at "
        f"start {load0[0]:.2f}/{load0[1]:.2f}/{load0[2]:.2f}, at end {load1[0]:.2f}/{load1[1]:.2f}/{load1[2]:.2f} "
        f"on {os.cpu_count()} cores (a shared machine).",
        "",
    ]
    table = markdown_table(
        [
            {
                "store": r["store"],
                "case": r["case"],
                "writers": r["writers"],
                "wall [s]": r["wall_s"],
                "ms per item": r["per_item_ms"],
                "items/s": r["items_per_s"],
            }
            for r in rows
        ]
    )
    write_text(RESULTS / f"fleet_stores{suffix}.md", "\n".join(head) + "\n" + table + "\n")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
