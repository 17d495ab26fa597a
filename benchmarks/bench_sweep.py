"""Sweep throughput: runs per second of ``vibkit.sweep.run`` on 1 and 2 local worker processes, against a
plain Python loop of ``vibkit.simulate`` over the same varied scenes in this process.

The runs are short on purpose (the no-load forward scene, a few seconds simulated, delta only), so
that what Dask and the Zarr store add per run shows. Three numbers per worker count:

* end to end: the whole ``vibkit.sweep.run`` call with a fresh local cluster (start-up, workers loading
  the compiled kernels, every run streamed to a Zarr store, consolidation);
* warm: the same sweep submitted to a cluster that is already up and warmed (one run per worker
  before the clock starts), still writing the store: the steady throughput;
* the same on the warm cluster without a store (results kept in memory): what the store costs;
* the plain loop (after one warm-up run), the baseline, run side by side in the same process.

The machine is shared with other jobs: the load average is recorded before and after.

Run: ``python benchmarks/bench_sweep.py [--quick]``; writes benchmarks/results/sweep.{csv,md}
(``--quick``: sweep_quick.*).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "sim" / "thesis-forward.toml"


def _scene_text(duration):
    import tomllib

    from vibkit.sweep.plan import to_toml

    data = tomllib.loads(SCENE.read_text())
    data["run"]["duration"] = duration
    data["run"]["initial_speed"] = 0.5
    data["outputs"] = {"variables": ["delta"]}
    return to_toml(data)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="8 runs of 1 s instead of 24 runs of 4 s")
    args = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    import vibkit
    from vibkit.model.scene import parse_scene
    from vibkit.sweep.plan import plan_sweep, varied_text

    n_runs, duration = (2, 0.5) if args.quick else (24, 4.0)
    tmp = Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    scene_path = tmp / "scene.toml"
    scene_path.write_text(_scene_text(duration))
    vary = {"effects.contact.stiffness": f"5e5:2e6:{n_runs}"}
    load_before = os.getloadavg()
    rows = []
    try:
        # the baseline: a plain loop in this process, over the very same varied scenes
        plan = plan_sweep(scene_path, vary)
        scenes = [parse_scene(varied_text(plan.text, p)) for p in plan.points]
        vibkit.simulate(scenes[0], progress=False)  # warm-up: load the compiled kernels
        t0 = time.perf_counter()
        for sc in scenes:
            vibkit.simulate(sc, progress=False)
        loop = time.perf_counter() - t0
        rows.append(
            {
                "how": "plain loop of vibkit.simulate (baseline)",
                "workers": 1,
                "runs": n_runs,
                "wall_s": loop,
                "runs_per_s": n_runs / loop,
                "vs_loop": 1.0,
                "per_run_overhead_ms": 0.0,
                "in_worker_s": loop,
            }
        )
        for workers in (1,) if args.quick else (1, 2):
            out = tmp / f"e2e{workers}.zarr"
            t0 = time.perf_counter()
            ds = vibkit.sweep(scene_path, vary, output=out, n_workers=workers, parallel=True, progress=False)
            wall = time.perf_counter() - t0
            assert int(ds.attrs["runs_ok"]) == n_runs, ds.attrs
            rows.append(
                {
                    "how": "vibkit.sweep end to end (fresh local cluster, Zarr store)",
                    "workers": workers,
                    "runs": n_runs,
                    "wall_s": wall,
                    "runs_per_s": n_runs / wall,
                    "vs_loop": loop / wall,
                    "per_run_overhead_ms": 1e3 * (wall * workers - loop) / n_runs,
                    "in_worker_s": float(ds["wall_time"].sum()),
                }
            )
            with (
                LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=40
                ) as cluster,
                Client(cluster) as client,
            ):
                warm = vibkit.sweep(
                    scene_path, {"effects.contact.stiffness": f"1e6:2e6:{workers}"}, client=client, progress=False
                )  # one run per worker: kernels loaded
                assert int(warm.attrs["runs_ok"]) == workers
                out = tmp / f"warm{workers}.zarr"
                t0 = time.perf_counter()
                ds = vibkit.sweep(scene_path, vary, output=out, client=client, progress=False)
                wall = time.perf_counter() - t0
                assert int(ds.attrs["runs_ok"]) == n_runs, ds.attrs
                in_worker = float(ds["wall_time"].sum())
                t0 = time.perf_counter()
                ds = vibkit.sweep(scene_path, vary, client=client, progress=False)
                wall_mem = time.perf_counter() - t0
                assert int(ds.attrs["runs_ok"]) == n_runs, ds.attrs
                in_worker_mem = float(ds["wall_time"].sum())
            rows.append(
                {
                    "how": "vibkit.sweep on a warm cluster (Zarr store)",
                    "workers": workers,
                    "runs": n_runs,
                    "wall_s": wall,
                    "runs_per_s": n_runs / wall,
                    "vs_loop": loop / wall,
                    "per_run_overhead_ms": 1e3 * (wall * workers - loop) / n_runs,
                    "in_worker_s": in_worker,
                }
            )
            rows.append(
                {
                    "how": "vibkit.sweep on a warm cluster (in memory, no store)",
                    "workers": workers,
                    "runs": n_runs,
                    "wall_s": wall_mem,
                    "runs_per_s": n_runs / wall_mem,
                    "vs_loop": loop / wall_mem,
                    "per_run_overhead_ms": 1e3 * (wall_mem * workers - loop) / n_runs,
                    "in_worker_s": in_worker_mem,
                }
            )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    load_after = os.getloadavg()
    stem = "sweep_quick" if args.quick else "sweep"
    write_csv(RESULTS / f"{stem}.csv", rows)
    md = (
        f"# Sweep throughput\n\n{machine()}; {today()}; {n_runs} runs of the no-load forward scene "
        f"({duration:g} s simulated from 0.5 m/s, dopri5 rtol 1e-5, delta only), contact stiffness varied.\n"
        f"Load average (1, 5, 15 min) before: {', '.join(f'{v:.2f}' for v in load_before)}; after: "
        f"{', '.join(f'{v:.2f}' for v in load_after)} (the machine is shared with other jobs).\n\n"
        f"`vs_loop` is the plain loop's wall time over this row's (above 1: faster than the loop); "
        f"`per_run_overhead_ms` is (wall x workers - loop) / runs, the cost per run of Dask, the store and "
        f"the workers beyond the simulation itself; `in_worker_s` is the sum of the runs' own wall "
        f"times measured in the workers (parse, simulate, summarise): what is left of `wall_s x workers` is "
        f"Dask's and the driver's.\n\n" + markdown_table(rows) + "\n"
    )
    write_text(RESULTS / f"{stem}.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
