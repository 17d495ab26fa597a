"""Work-precision of the shipped forward scenes and their contact stiffness x0.1 and x10 variants,
and what the convergence check costs.

Each scene (full length) with k = 1e5, 1e6, 1e7 runs by dopri5 (steps ended on the breakpoints) at
rtol 1e-6 ... 1e-12 and at its default tolerance (``default_rtol``: from the contact stiffness),
with the chain's configuration read from the pitch table (the default), and with the exact closure
at the default tolerance and at 1e-12; every run is compared with the exact 1e-12 run on what a user reads (:func:`vibkit.analyses.convergence.summary`):
contact and back-flank episodes, the last contact, the sprocket speed ripple over the second half;
``right`` says whether the convergence check's criteria find it equal to the 1e-12 run. Then the
default run with ``check = true``: its verdict and its CPU time against the plain run's.
CPU time is the process's (``time.process_time``), wall time the clock's.

Run: ``python benchmarks/work_precision_variants.py [--quick]`` (--quick: 6 s, three tolerances);
writes benchmarks/results/work_precision_variants.{csv,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import vibkit
from vibkit.analyses.convergence import compare, summary
from vibkit.analyses.forward import default_rtol
from vibkit.model.scene import load_scene

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("thesis-forward", "las-palmas", "thesis-passengers")
STIFFNESS = (1e5, 1e6, 1e7)


def variant(name, k, rtol=None, check=False, closure="table"):
    sc = load_scene(ROOT / "sim" / f"{name}.toml")
    eff = dict(sc.effects)
    eff["contact"] = replace(eff["contact"], stiffness=k)
    outs = tuple(dict.fromkeys(tuple(sc.outputs["variables"]) + ("flank_force", "sprocket_speed", "delta")))
    solver = dict(sc.sections["solver"], check=check, closure=closure)
    if rtol is not None:
        solver.update(rtol=rtol, atol=rtol * 1e-2)
    return replace(sc, effects=eff, sections=dict(sc.sections, solver=solver), outputs=dict(sc.outputs, variables=outs))


def timed(scene, duration):
    t0, c0 = time.perf_counter(), time.process_time()
    ds = vibkit.simulate(scene, duration=duration, progress=False)
    return ds, time.perf_counter() - t0, time.process_time() - c0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="6 s runs, rtol 1e-6, 1e-9, 1e-12")
    args = ap.parse_args(argv)
    ladder = (1e-6, 1e-9, 1e-12) if args.quick else (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    load0 = os.getloadavg()[0]
    vibkit.simulate(variant("thesis-forward", 1e6), duration=0.2, progress=False)  # warm-up: the kernels
    rows = []
    for name in SCENES:
        for k in STIFFNESS:
            sc0 = variant(name, k)
            duration = 6.0 if args.quick else sc0.section("run")["duration"]
            dt = sc0.section("run")["output_step"]
            dflt = default_rtol(sc0.effects)
            runs = {}
            # the reference: the exact closure at the tightest tolerance; then the pitch table (the
            # default) down the ladder, and the exact closure at the default tolerance beside it
            top = min(ladder)
            ds, wall, cpu = timed(variant(name, k, top, closure="exact"), duration)
            runs[(top, "exact")] = (summary(ds), wall, cpu)
            for r in sorted(set(ladder) | {dflt}, reverse=True):
                ds, wall, cpu = timed(variant(name, k, r), duration)
                runs[(r, "table")] = (summary(ds), wall, cpu)
            ds, wall, cpu = timed(variant(name, k, dflt, closure="exact"), duration)
            runs[(dflt, "exact")] = (summary(ds), wall, cpu)
            ref = runs[(top, "exact")][0]
            print(f"{name} k={k:g} ...", file=sys.stderr, flush=True)
            for (r, closure), (s, wall, cpu) in runs.items():
                diff = compare(s, ref, r, dt, duration)
                rows.append(
                    {
                        "scene": name,
                        "stiffness": k,
                        "rtol": r,
                        "closure": closure,
                        "default": "yes" if r == dflt else "",
                        "episodes": s["contact_episodes"],
                        "back_flank": s["back_flank_episodes"],
                        "last_contact_s": s["last_contact_s"],
                        "ripple_percent": s["sprocket_ripple_percent"],
                        "right": "reference"
                        if (r, closure) == (top, "exact")
                        else ("yes" if not diff else "no: " + ", ".join(diff)),
                        "wall_s": wall,
                        "cpu_s": cpu,
                        "x_real_time_cpu": duration / cpu,
                    }
                )
            ds, wall, cpu = timed(variant(name, k, check=True), duration)
            v = json.loads(ds.attrs["convergence"])
            rows.append(
                {
                    "scene": name,
                    "stiffness": k,
                    "rtol": dflt,
                    "closure": "table",
                    "default": "yes, with check",
                    "episodes": v["runs"][0]["contact_episodes"],
                    "back_flank": v["runs"][0]["back_flank_episodes"],
                    "last_contact_s": v["runs"][0]["last_contact_s"],
                    "ripple_percent": v["runs"][0]["sprocket_ripple_percent"],
                    "right": ("converged" if v["converged"] else "sensitive" if v["sensitive"] else "not converged")
                    + f" ({len(v['runs'])} runs; check cost {cpu / runs[(dflt, 'table')][2]:.2f}x)",
                    "wall_s": wall,
                    "cpu_s": cpu,
                    "x_real_time_cpu": duration / cpu,
                }
            )
    stem = "work_precision_variants" + ("_quick" if args.quick else "")
    write_csv(RESULTS / f"{stem}.csv", rows)
    md = (
        f"# Work-precision: shipped scenes and their stiffness variants\n\n{machine()}; {today()}; dopri5, steps "
        f"ended on the breakpoints; every run compared with the exact closure's rtol 1e-12 run by the "
        f"convergence check's criteria; closure: the chain's configuration read from the table over one "
        f"pitch (the default) or solved at every evaluation (exact); CPU time of the process; load average {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at "
        f"the end.\n\n" + markdown_table(rows) + "\n"
    )
    write_text(RESULTS / f"{stem}.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
