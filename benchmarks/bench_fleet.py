"""Benchmark of ``vibkit fleet scan``: recordings per second, a plain loop against Dask workers, on both stores.

Run:  python benchmarks/bench_fleet.py [--quick] [--workers 1,2] [--stores sqlite,postgresql]

Synthetic recordings (link-pass harmonics plus white noise, 30 s at 200 Hz, CSV, about 150 kB
each) are scanned into a fresh database (a SQLite file, or a new database on a PostgreSQL server
that this script starts with pgserver) by:

* ``analysis only``: read + estimate_pitch in a loop, nothing stored (what the workers do);
* ``plain loop``: ``FleetDB.scan(parallel=False)``: hashing, analysis and one committed
  transaction per recording, all in this process (the baseline);
* ``dask N``: ``FleetDB.scan`` on a local Dask cluster of N worker processes
  (:func:`vibkit.runtime.cluster.dask_client`), the cluster started and its workers warmed up (vibkit
  imported, kernels loaded) before the clock starts; the start-up is reported on its own.

Each case is the best of ``--repeat`` rounds, the cases taking turns within a round (one process,
the same varying load for all).  Writes (atomically)
``benchmarks/results/fleet.{md,csv}`` (``fleet_quick.*`` with ``--quick``) with the machine, the
date and the load average (the machine may be shared: read the ratios with it).
"""

from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _common import RESULTS, machine, markdown_table, support, write_csv, write_text

SPEED = 0.5  # m/s
NOMINAL = 0.4 / 3  # m
FS = 200.0  # Hz


def synth(path, pitch_m, seed, duration):
    t = np.arange(int(duration * FS)) / FS
    x = support.chain.random_phase_family(t, SPEED / pitch_m, np.random.default_rng(seed))
    np.savetxt(path, np.column_stack([t, x]), delimiter=",", header="time_s,accel_m_s2", comments="", fmt="%.6f")


def make_fleet(folder, n, duration):
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["file,unit,speed_m_s,date,nominal_pitch_m"]
    for i in range(n):
        name = f"u{i % 10:02d}_{i:04d}.csv"
        synth(folder / name, NOMINAL * (1 + 0.0001 * i), i, duration)
        day = dt.date(2022, 1, 1) + dt.timedelta(days=7 * i)
        lines.append(f"{name},U{i % 10:02d},{SPEED},{day.isoformat()},{NOMINAL}")
    cat = folder.parent / "units.csv"
    cat.write_text("\n".join(lines) + "\n")
    return cat


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a smoke run: few recordings, one repeat")
    ap.add_argument("--workers", default="1,2", help="worker counts of the Dask cases (default 1,2)")
    ap.add_argument("--repeat", type=int, help="runs per case (best kept; default 3, quick 1)")
    ap.add_argument(
        "--stores",
        default="sqlite,postgresql",
        help="stores scanned into (default sqlite,postgresql; postgresql needs pgserver and psycopg)",
    )
    a = ap.parse_args(argv)
    n = 4 if a.quick else 96
    duration = 30.0
    repeat = a.repeat or (1 if a.quick else 3)
    workers = [int(w) for w in a.workers.split(",") if w.strip()][: 1 if a.quick else None]
    stores = [x.strip() for x in a.stores.split(",") if x.strip()]

    import vibkit
    from vibkit.fleet import FleetDB
    from vibkit.fleet.measurement import _file_sha256
    from vibkit.fleet.scan import _analyse_job, _Job
    from vibkit.runtime.cluster import dask_client

    load0 = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-fleet-") as tmp:
        tmp = Path(tmp)
        rec = tmp / "visits"
        t0 = time.perf_counter()
        cat = make_fleet(rec, n, duration)
        print(f"{n} recordings of {duration:g} s written in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        files = sorted(rec.iterdir())
        size_kb = files[0].stat().st_size / 1e3
        jobs = [_Job(str(p), "U", SPEED, 0.0, NOMINAL, "2024-01-01", None, _file_sha256(p)) for p in files]
        _analyse_job(jobs[0])  # loads the compiled kernels in this process

        made = [0]

        def fresh_db(store):
            made[0] += 1
            if store == "sqlite":
                return FleetDB(tmp / f"f{made[0]}.sqlite")
            import psycopg

            with psycopg.connect(server.get_uri(), autocommit=True) as con:
                con.execute(f"CREATE DATABASE bench_{made[0]}")
            return FleetDB(server.get_uri(f"bench_{made[0]}"))

        def scan_plain(store):
            with fresh_db(store) as db:
                res = db.scan(rec, cat, parallel=False)
            assert len(res.added) == n, res.failed[:3]

        def scan_dask(store, w, client):
            with fresh_db(store) as db:
                res = db.scan(rec, cat, client=client)
            assert len(res.added) == n, res.failed[:3]

        server = None
        with contextlib.ExitStack() as stack:
            if "postgresql" in stores:
                import warnings

                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    import pgserver

                    server = pgserver.get_server(tempfile.mkdtemp(prefix="vibkit-pg-bench-"), cleanup_mode="delete")
                stack.callback(server.cleanup)
            clients, starts = {}, {}
            for w in workers:
                t0 = time.perf_counter()
                c = stack.enter_context(dask_client(n_workers=w))
                c.wait_for_workers(w)
                c.run(_analyse_job, jobs[0])  # every worker imports vibkit and loads the kernels
                clients[w], starts[w] = c, time.perf_counter() - t0
            cases = [("analysis only", 0, lambda k: [_analyse_job(j) for j in jobs])]
            for st in stores:
                cases += [(f"plain loop, {st}", 0, lambda k, st=st: scan_plain(st))]
                cases += [(f"dask {w}, {st}", w, lambda k, w=w, st=st: scan_dask(st, w, clients[w])) for w in workers]
            times = {c[0]: [] for c in cases}
            loads = {c[0]: [] for c in cases}
            for k in range(repeat):  # round robin: every case sees the same (shared, varying) load
                for name, _, fn in cases:
                    times[name].append(_timed(lambda: fn(k)))
                    loads[name].append(os.getloadavg()[0])
                    print(f"round {k + 1}: {name:>24}: {times[name][-1]:7.2f} s", file=sys.stderr)
        for name, w, _ in cases:
            best = min(times[name])
            rows.append(
                {
                    "case": name,
                    "workers": w,
                    "recordings": n,
                    "wall_s": best,
                    "recordings_per_s": n / best,
                    "cluster_start_s": starts.get(w) if name.startswith("dask") else None,
                    "load_avg_1min_mean": round(float(np.mean(loads[name])), 2),
                }
            )
    load1 = os.getloadavg()
    base = next(r["wall_s"] for r in rows if r["case"].startswith("plain loop"))
    for r in rows:
        r["ratio_vs_plain_loop"] = base / r["wall_s"]
        r["load_avg_1min_start"] = round(load0[0], 2)
        r["load_avg_1min_end"] = round(load1[0], 2)
    suffix = "_quick" if a.quick else ""
    write_csv(RESULTS / f"fleet{suffix}.csv", [{k: ("" if v is None else v) for k, v in r.items()} for r in rows])
    head = [
        "# Fleet scan throughput",
        "",
        f"{n} synthetic recordings ({duration:g} s at {FS:g} Hz, CSV, {size_kb:.0f} kB "
        "each), scanned into a fresh database: a SQLite file (WAL, synchronous=FULL) or a PostgreSQL database "
        "(pgserver on this machine, Unix socket), one transaction per recording; "
        f"best of {repeat} rounds, the cases taking turns within each round; Dask cases with the cluster already "
        "started and warmed up (start-up in its own "
        "column). Ratio: the first store's plain loop wall / case wall (> 1 is faster).",
        "",
        f"Machine: {machine()}; vibkit {vibkit.__version__}; numpy {np.__version__}; {platform.platform()}.",
        f"Date: {dt.datetime.now(dt.timezone.utc).isoformat(timespec='seconds')}. Load average (1/5/15 min) at "
        f"start {load0[0]:.2f}/{load0[1]:.2f}/{load0[2]:.2f}, at end {load1[0]:.2f}/{load1[1]:.2f}/{load1[2]:.2f} "
        f"on {os.cpu_count()} cores (a shared machine: other jobs ran at the same time).",
        "",
    ]
    table = markdown_table(
        [
            {
                "case": r["case"],
                "workers": r["workers"],
                "wall [s]": r["wall_s"],
                "recordings/s": r["recordings_per_s"],
                "ratio vs plain loop": r["ratio_vs_plain_loop"],
                "cluster start [s]": "-" if r["cluster_start_s"] is None else r["cluster_start_s"],
                "load avg (1 min)": r["load_avg_1min_mean"],
            }
            for r in rows
        ]
    )
    write_text(RESULTS / f"fleet{suffix}.md", "\n".join(head) + "\n" + table + "\n")
    print(table)
    return 0


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    sys.exit(main())
