"""Forward-dynamics speed: real-time factor of the 44 s no-load scene, peak memory, and what each
effect costs.

Each case runs in a fresh subprocess (so that the peak resident memory is its own), after one
warm-up call that loads the compiled kernels from numba's cache; the time reported is the whole
``vibkit.simulate`` call (integration and outputs), in wall time and in CPU time of the process
(``time.process_time``: what a loaded machine does not inflate), best of five calls (this machine's
timings vary by 10-30 % from one minute to the next).

Run: ``python benchmarks/bench_forward.py [--quick]``; writes benchmarks/results/forward.{csv,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]

NO_LOAD = {
    "gravity": {"g": 9.81},
    "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
    "motor": {"kp": 600.0, "speed": 0.5, "ki": 0.0},
}
NO_LOAD_OUT = ["delta", "sprocket_speed", "contact_force"]

# name: solver settings over the scene's (the default tolerance follows the contact stiffness: 1e-7 here)
SOLVER = {
    "contact, no load, stepping over breakpoints": {"events": False},
    "contact, no load, rtol 1e-6": {"rtol": 1e-6},
    "contact, no load, rtol 1e-9": {"rtol": 1e-9},
    "contact, no load, with check": {"check": True},
    "contact, no load, exact closure": {"closure": "exact"},
    "contact, no load, exact closure, rtol 1e-9": {"closure": "exact", "rtol": 1e-9},
    "contact, no load, default outputs, exact closure": {"closure": "exact"},
}

# name: chain settings over the scene's (links 40, 70 and 100 one mm longer; every link 3 % longer)
WORN = [[40, 0.4 / 3 + 1e-3], [70, 0.4 / 3 + 1e-3], [100, 0.4 / 3 + 1e-3]]
CHAIN = {
    "contact, no load, three worn links": {"worn_links": WORN},
    "contact, no load, three worn links, with check": {"worn_links": WORN},
    "contact, no load, three worn links, exact closure": {"worn_links": WORN},
    "contact, no load, 3 % elongated chain": {"elongation_percent": 3.0},
    "contact, no load, rollers of their own mass and radius": {
        "roller_mass_by_roller": [[3, 9.5], [50, 12.0], [120, 6.0]],
        "roller_radius_by_roller": [[12, 0.033], [90, 0.034]],
    },
    "contact, no load, rollers of their own mass and radius, exact closure": {
        "roller_mass_by_roller": [[3, 9.5], [50, 12.0], [120, 6.0]],
        "roller_radius_by_roller": [[12, 0.033], [90, 0.034]],
    },
}
SOLVER["contact, no load, rollers of their own mass and radius, exact closure"] = {"closure": "exact"}
SOLVER["contact, no load, three worn links, with check"] = {"check": True}
SOLVER["contact, no load, three worn links, exact closure"] = {"closure": "exact"}
SOLVER["contact, no load, run-by-run closure"] = {"closure": "runs"}

CASES = {
    # name: (effects, outputs, description)
    "kinematics only": ({}, ["delta"], "no force at all: the chain coasts (closure walk + reduced dynamics)"),
    "gravity": ({"gravity": {"g": 9.81}}, ["delta"], "gravity on every roller"),
    "contact, no load": (
        {
            "gravity": {"g": 9.81},
            "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
            "motor": {"kp": 600.0, "speed": 0.5, "ki": 0.0},
        },
        ["delta", "sprocket_speed", "contact_force"],
        "the study's no-load scene: delta, sprocket speed, contact forces",
    ),
    "contact, no load, stepping over breakpoints": (
        {
            "gravity": {"g": 9.81},
            "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
            "motor": {"kp": 600.0, "speed": 0.5, "ki": 0.0},
        },
        ["delta", "sprocket_speed", "contact_force"],
        "the same, steps not ended on the guide's breakpoints (wrong contact history: docs/explanation/numerics.md)",
    ),
    "contact, no load, rtol 1e-6": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the same at rtol 1e-6 (the tolerance shipped before the pitch table)",
    ),
    "contact, no load, rtol 1e-9": (NO_LOAD, NO_LOAD_OUT, "the same at rtol 1e-9"),
    "contact, no load, with check": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the same with the convergence check (a second run 100 times tighter, compared)",
    ),
    "contact, no load, exact closure": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the same, the closure solved at every evaluation instead of read from the pitch table (as before the pitch table)",
    ),
    "contact, no load, exact closure, rtol 1e-9": (NO_LOAD, NO_LOAD_OUT, "the same at rtol 1e-9"),
    "contact, no load, default outputs": (None, None, "sim/thesis-forward.toml as shipped (link tensions etc.)"),
    "contact, no load, default outputs, exact closure": (None, None, "the same, exact closure"),
    "contact + passengers": (
        {
            "gravity": {"g": 9.81},
            "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
            "motor": {"kp": 6000.0, "speed": 0.5, "ki": 0.0},
            "passengers": {
                "mass": [70.0, 90.0],
                "step": [3, 53],
                "board": ["lower_landing"] * 2,
                "alight": ["upper_landing"] * 2,
            },
        },
        ["delta", "sprocket_speed"],
        "two passengers (the study's chapter 7.4)",
    ),
    "contact, no load, three worn links": (
        NO_LOAD,
        NO_LOAD_OUT,
        "links 40, 70 and 100 one mm longer: the chain repeats after a loop, not a pitch (closed run by run)",
    ),
    "contact, no load, three worn links, with check": (NO_LOAD, NO_LOAD_OUT, "the same with the convergence check"),
    "contact, no load, three worn links, exact closure": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the same, the closure walked link by link (as before the run-by-run closure)",
    ),
    "contact, no load, run-by-run closure": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the healthy chain closed run by run instead of read from the pitch table (what exactness costs)",
    ),
    "contact, no load, 3 % elongated chain": (
        NO_LOAD,
        NO_LOAD_OUT,
        "every link 3 % longer on the original sprocket (delta -0.229 m: the table's nodes 1 mm apart)",
    ),
    "contact, no load, rollers of their own mass and radius": (
        NO_LOAD,
        NO_LOAD_OUT,
        "three rollers of 6-12 kg, two of 33-34 mm radius: the table, summed roller by roller",
    ),
    "contact, no load, rollers of their own mass and radius, exact closure": (
        NO_LOAD,
        NO_LOAD_OUT,
        "the same, exact closure",
    ),
}

CHILD = r"""
import json, resource, sys, time
from dataclasses import replace
import vibkit
from vibkit.model.scene import load_scene
effects, outputs, duration, solver_over, chain_over = json.loads(sys.argv[1])
scene = load_scene(sys.argv[2])
if chain_over:
    text = scene.text.replace("n_rollers = 159", "n_rollers = 159\n" + "\n".join(f"{k} = {json.dumps(v)}" for k, v in chain_over.items()))
    from vibkit.model.scene import parse_scene
    scene = parse_scene(text, scene.source)
if effects is not None:
    scene = replace(scene, effects=effects)
if outputs is not None:
    scene = replace(scene, outputs=dict(scene.outputs, variables=tuple(outputs)))
run = dict(scene.sections["run"], initial_speed=0.5 if effects is not None and "motor" not in effects else 0.0)
solver = dict(scene.sections["solver"], **solver_over)
scene = replace(scene, sections=dict(scene.sections, run=run, solver=solver))
vibkit.simulate(scene, duration=0.5, progress=False)  # warm-up: compiled kernels from the cache
wall = cpu = float("inf")
for _ in range(5):
    t0, c0 = time.perf_counter(), time.process_time()
    ds = vibkit.simulate(scene, duration=duration, progress=False)
    wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
from vibkit.analyses.forward import default_rtol
print(json.dumps({"wall": wall, "cpu": cpu, "rtol": solver.get("rtol") or default_rtol(scene.effects), "integration": ds.attrs["solver_wall_time_s"], "steps": ds.attrs["solver_steps"],
                  "closure_mode": ds.attrs["solver_closure"],
                  "converged": {1: "yes", 0: "no"}.get(ds.attrs.get("converged"), ""),
                  "evaluations": ds.attrs["solver_evaluations"],
                  "maxrss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "closure": float(ds.closure_residual.max()) if "closure_residual" in ds else float("nan"),
                  "nbytes_mb": ds.nbytes / 2**20}))
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="8 s instead of 44 s")
    args = ap.parse_args(argv)
    duration = 2.0 if args.quick else 44.0
    scene = str(ROOT / "sim" / "thesis-forward.toml")
    rows = []
    load0 = os.getloadavg()[0]
    for name, (effects, outputs, what) in list(CASES.items())[: 2 if args.quick else None]:
        print(f"{name} ...", file=sys.stderr, flush=True)
        out = subprocess.run(
            [
                sys.executable,
                "-c",
                CHILD,
                json.dumps([effects, outputs, duration, SOLVER.get(name, {}), CHAIN.get(name)]),
                scene,
            ],
            capture_output=True,
            text=True,
            check=True,
        )
        res = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(
            {
                "case": name,
                "rtol": res["rtol"],
                "closure": res["closure_mode"],
                "simulated_s": duration,
                "cpu_s": res["cpu"],
                "realtime_factor_cpu": duration / res["cpu"],
                "wall_s": res["wall"],
                "realtime_factor_wall": duration / res["wall"],
                "integration_s": res["integration"],
                "steps": res["steps"],
                "evaluations": res["evaluations"],
                "converged": res["converged"],
                "peak_memory_MB": res["maxrss_mb"],
                "result_MB": res["nbytes_mb"],
                "what": what,
            }
        )
        print(rows[-1], file=sys.stderr, flush=True)
    write_csv(RESULTS / ("forward_quick.csv" if args.quick else "forward.csv"), rows)
    md = (
        f"# Forward dynamics speed\n\n{machine()}; {today()}; {duration:g} s simulated, dopri5 at the "
        f"default tolerance (from the contact stiffness: 1e-7 at k = 1e6) unless the case says, one core, each "
        f"case in a fresh process after a warm-up, best of five calls; converged: the convergence check's "
        f"verdict where the case runs it; CPU time is the process's "
        f"(time.process_time); load average {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end.\n\n"
        + markdown_table(rows)
        + "\n"
    )
    write_text(RESULTS / ("forward_quick.md" if args.quick else "forward.md"), md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
