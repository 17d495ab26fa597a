"""What accuracy costs in time: work-precision of every integrator and formulation, and of the
kinematic sweep.

Forward dynamics: the no-load scene (``sim/thesis-forward.toml``; 44 s, or 4 s with --quick) run by
every method over a ladder of tolerances, with the chain's configuration read from the pitch table
(the default) and, for dopri5, solved at every evaluation (exact closure); errors against a reference
computed by vibkit's dopri5 at rtol 1e-11 with the exact closure: delta, chain speed, link tension (max abs over time and links), link-pass frequency
(relative, from roller 1's mean advance over the steady part) and the closure residual; wall time
of the whole call. Then what users see of the physics: the contact history (episodes of
tooth contact, sampled at 200 Hz, and the time of the last one: converged, 23 and 7.87 s), the
sprocket speed ripple after 8 s (converged 2e-4 %), and the energy error of the conservative scene
(no motor, no damping, started at 0.5 m/s; 44 s) run at the same settings. dopri5 runs with its
steps ended on the guide's breakpoints (the default) and, for comparison, stepping over them. The
study's formulation (all coordinates, Baumgarte, BDF) runs at its own settings.

Kinematics: delta against the closure tolerance and against the sweep step.

Run: ``python benchmarks/work_precision.py [--quick]``; writes benchmarks/results/work_precision.csv,
work_precision.md, work_precision.png and kinematic_precision.csv.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import vibkit
from vibkit.analyses.integrate import IntegrationError
from vibkit.model.chain import Chain
from vibkit.model.guide import Guide
from vibkit.model.params import reference_chain, reference_guide
from vibkit.model.scene import load_scene

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ("delta", "chain_speed", "sprocket_speed", "link_tension", "closure_residual", "s0", "contact_force")
CONSERVATIVE = {"gravity": {"g": 9.81}, "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0}}


def scene_for(duration):
    scene = load_scene(ROOT / "sim" / "thesis-forward.toml")
    out = dict(scene.outputs, variables=OUTPUTS)
    sections = dict(scene.sections)
    sections["run"] = dict(sections["run"], duration=duration, output_step=0.005)
    return replace(scene, outputs=out, sections=sections)


def conservative_for(scene):
    sections = dict(scene.sections)
    sections["run"] = dict(sections["run"], initial_speed=0.5)
    return replace(scene, effects=CONSERVATIVE, sections=sections, outputs=dict(scene.outputs, variables=("energy",)))


def run_ours(scene, method, rtol, budget, events=True, closure="table"):
    sections = dict(scene.sections)
    sections["solver"] = {
        "method": method,
        "rtol": rtol,
        "atol": rtol * 1e-2,
        "max_wall_time": budget,
        "events": events,
        "closure": closure,
    }
    t0 = time.perf_counter()
    ds = vibkit.simulate(replace(scene, sections=sections), progress=False)
    return ds, time.perf_counter() - t0


def contact_history(ds):
    """Episodes of tooth contact (runs of output samples where any tooth carries force) and the time
    of the last contact. [-], [s]"""
    on = (np.abs(ds.contact_force.values) > 0).any(axis=1)
    n = int(on[0]) + int(np.count_nonzero(np.diff(on.astype(int)) == 1))
    return n, float(ds.time.values[np.flatnonzero(on)[-1]]) if on.any() else float("nan")


def physics(ds):
    n, last = contact_history(ds)
    w = ds.sprocket_speed.sel(time=slice(8.0, None)).values
    ripple = 100.0 * float((w.max() - w.min()) / abs(w.mean())) if w.size else float("nan")
    return {"contact_episodes": n, "last_contact_s": last, "ripple_percent": ripple}


def energy_error(scene, method, rtol, budget, events=True, closure="table"):
    """Largest change of kinetic + gravitational + contact energy over the conservative run. [J]"""
    try:
        ds, _ = run_ours(conservative_for(scene), method, rtol, budget, events, closure)
    except (IntegrationError, ValueError):
        return float("nan")
    e = (ds.kinetic_energy + ds.potential_energy + ds.contact_energy).values
    return float(np.abs(e - e[0]).max())


def link_pass(ds, steady_from):
    """The chain's mean link-pass frequency after ``steady_from``: roller 1's advance over the window
    in link pitches per second (the sprocket's speed is not the chain's while they are out of
    contact within the tooth backlash). [Hz]"""
    t = ds.time.values
    i0 = int(np.searchsorted(t, steady_from))
    s0 = ds.s0.values if "s0" in ds else None
    if s0 is None:  # the study's result: from its chain speed
        return float(ds.chain_speed.values[i0:].mean()) / (0.4 / 3)
    return (s0[-1] - s0[i0]) / (t[-1] - t[i0]) / (0.4 / 3)


def errors(ds, ref, steady_from):
    f = link_pass(ds, steady_from)
    f_ref = link_pass(ref, steady_from)
    return {
        "err_delta_m": float(np.abs(ds.delta - ref.delta).max()),
        "err_chain_speed_m_s": float(np.abs(ds.chain_speed - ref.chain_speed).max()),
        "err_link_tension_N": float(np.abs(ds.link_tension - ref.link_tension).max()),
        "err_link_pass_rel": abs(f / f_ref - 1.0),
        "closure_residual_m": float(ds.closure_residual.max()),
    }


def forward(quick, skip_study=False):
    duration = 1.0 if quick else 44.0
    scene = scene_for(duration)
    print(f"reference: dopri5 at rtol 1e-11 over {duration:g} s, exact closure ...", file=sys.stderr, flush=True)
    ref, t_ref = run_ours(scene, "dopri5", 1e-11, math.inf, closure="exact")
    # (method, steps end on breakpoints, tolerances); the closure is read from the pitch table
    # (the default) except in the "exact closure" ladder
    ladders = [
        ("dopri5", True, [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9] if not quick else [1e-6]),
        ("dopri5 exact", True, [1e-6, 1e-7, 1e-9] if not quick else [1e-6]),
        ("dopri5", False, [1e-5, 1e-7, 1e-9] if not quick else [1e-6]),
        ("dop853", False, [1e-4, 1e-6, 1e-8] if not quick else [1e-6]),
        ("rk45", False, [1e-4, 1e-6] if not quick else [1e-4]),
        ("bdf", False, [1e-4, 1e-6] if not quick else [1e-4]),
        ("radau", False, [1e-4, 1e-6] if not quick else [1e-4]),
        ("lsoda", False, [1e-4, 1e-6] if not quick else [1e-4]),
        ("cvode-bdf", False, [1e-4, 1e-6, 1e-8] if not quick else [1e-4]),
        ("cvode-adams", False, [1e-4, 1e-6, 1e-8] if not quick else [1e-4]),
    ]
    if quick:  # a smoke run: the default and one scipy method
        ladders = [lad for lad in ladders if lad[0] in ("dopri5", "rk45")]
    budget = 300.0 if not quick else 60.0
    rows = []
    for method, events, tols in ladders:
        closure = "exact" if method.endswith(" exact") else "table"
        method = method.split()[0]
        label = (
            method
            + ("" if events or method != "dopri5" else " (steps over breakpoints)")
            + (", exact closure" if closure == "exact" else "")
        )
        for rtol in tols:
            print(f"{label} rtol {rtol:g} ...", file=sys.stderr, flush=True)
            try:
                ds, wall = run_ours(scene, method, rtol, budget, events, closure)
            except (IntegrationError, ValueError) as exc:  # ValueError: an optional solver not installed
                rows.append(
                    {
                        "formulation": "vibkit",
                        "method": label,
                        "tolerance": rtol,
                        "wall_time_s": float("nan"),
                        "realtime_factor": float("nan"),
                        "note": str(exc).split(" at t")[0],
                    }
                )
                continue
            row = {
                "formulation": "vibkit",
                "method": label,
                "tolerance": rtol,
                "wall_time_s": wall,
                "realtime_factor": duration / wall,
            }
            row.update(errors(ds, ref, 0.5 if quick else 10.0))
            row.update(physics(ds))
            row["energy_error_J"] = energy_error(scene, method, rtol, budget, events, closure)
            row["evaluations"] = int(ds.attrs["solver_evaluations"])
            rows.append(row)
    ref_row = {
        "formulation": "vibkit (reference)",
        "method": "dopri5, exact closure",
        "tolerance": 1e-11,
        "wall_time_s": t_ref,
        "realtime_factor": duration / t_ref,
        "evaluations": int(ref.attrs["solver_evaluations"]),
    }
    ref_row.update(physics(ref))
    ref_row["energy_error_J"] = energy_error(scene, "dopri5", 1e-11, math.inf, closure="exact")
    rows.append(ref_row)
    # the study's formulation (Baumgarte, BDF), at its own settings (RelTol = AbsTol = MaxStep = 1e-3)
    from vibkit.analyses.reference import run_study

    study_cases = [] if skip_study else [1e-3]
    study_duration = duration if not quick else duration
    for rtol in study_cases:
        print(f"study formulation BDF rtol {rtol:g} over {study_duration:g} s ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        try:
            ds = run_study(
                scene,
                duration=study_duration,
                rtol=rtol,
                atol=rtol,
                max_step=1e-3,
                output_step=0.01,
                max_wall_time=900.0,
            )
            wall = time.perf_counter() - t0
            row = {
                "formulation": "study (Baumgarte)",
                "method": "BDF",
                "tolerance": rtol,
                "wall_time_s": wall,
                "realtime_factor": study_duration / wall,
            }
            row.update(errors(ds, ref, 0.5 if quick else 10.0))
            if "contact_force" in ds:
                row.update(physics(ds))
            row["evaluations"] = int(ds.attrs.get("solver_evaluations", -1))
            rows.append(row)
        except IntegrationError as exc:
            rows.append(
                {
                    "formulation": "study (Baumgarte)",
                    "method": "BDF",
                    "tolerance": rtol,
                    "wall_time_s": float("nan"),
                    "note": str(exc),
                }
            )
    keys = [
        "formulation",
        "method",
        "tolerance",
        "wall_time_s",
        "realtime_factor",
        "err_delta_m",
        "err_chain_speed_m_s",
        "err_link_tension_N",
        "err_link_pass_rel",
        "closure_residual_m",
        "contact_episodes",
        "last_contact_s",
        "ripple_percent",
        "energy_error_J",
        "evaluations",
        "note",
    ]
    rows = [{k: r.get(k, "") for k in keys} for r in rows]
    return rows, duration, t_ref


def kinematics(quick):
    ch = Chain(Guide(reference_guide()), reference_chain())
    L = ch.pitch
    s = np.arange(3.0, 3.0 + L, 1e-5 if not quick else 1e-3)
    ch.tol = 1e-15
    exact, _ = ch.sweep(s)
    rows = []
    for tol in (1e-6, 1e-8, 1e-10, 1e-12, 1e-13):
        ch.tol = tol
        t0 = time.perf_counter()
        d, _ = ch.sweep(s)
        wall = time.perf_counter() - t0
        rows.append(
            {
                "study": "closure tolerance",
                "value": tol,
                "err_delta_m": float(np.abs(d - exact).max()),
                "us_per_configuration": wall / s.size * 1e6,
            }
        )
    ch.tol = 1e-13
    fine_mean, fine_ptp = exact.mean(), np.ptp(exact)
    for step in (1e-2, 1e-3, 1e-4, 1e-5):
        grid = np.arange(3.0, 3.0 + L, step)
        d, _ = ch.sweep(grid)
        # delta between the samples, by linear interpolation, against the 0.01 mm sweep
        interp = np.interp(s, grid, d, period=None)
        rows.append(
            {
                "study": "sweep step [m]",
                "value": step,
                "err_delta_m": float(np.abs(interp - exact).max()),
                "err_mean_m": abs(d.mean() - fine_mean),
                "err_peak_to_peak_m": abs(np.ptp(d) - fine_ptp),
            }
        )
    keys = ["study", "value", "err_delta_m", "us_per_configuration", "err_mean_m", "err_peak_to_peak_m"]
    return [{k: r.get(k, "") for k in keys} for r in rows]


def plot(rows, path, duration):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator, NullFormatter

    fig, axes = plt.subplots(1, 4, figsize=(17, 5.0))
    labels = {}
    for r in rows:
        if not isinstance(r["wall_time_s"], float) or not math.isfinite(r["wall_time_s"]) or r["err_delta_m"] == "":
            continue
        labels.setdefault(f"{r['formulation']} {r['method']}", []).append(r)
    for ax, key, unit in zip(
        axes,
        ("err_delta_m", "err_link_tension_N", "err_link_pass_rel", "energy_error_J"),
        (
            "delta error [m]",
            "link tension error [N]",
            "link-pass frequency error [-]",
            "energy error, conservative scene [J]",
        ),
    ):
        for name, rs in labels.items():
            rs = [r for r in rs if isinstance(r.get(key), float) and math.isfinite(r[key])]
            x = [r["wall_time_s"] for r in rs]
            y = [max(r[key], 1e-16) for r in rs]
            ax.loglog(x, y, "o-", label=name)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(unit)
        # decades only on the time axis: minor labels (2x10^-1, 3x10^-1, ...) overlap
        ax.xaxis.set_major_locator(LogLocator(base=10.0))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.suptitle(f"Work-precision, no-load forward scene, {duration:g} s simulated ({today()})")
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(path, dpi=110)


def _number(text):
    try:
        return float(text)
    except ValueError:
        return text


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="4 s scene and shorter ladders (CI)")
    ap.add_argument(
        "--skip-study",
        action="store_true",
        help="leave out the study's formulation (about 150 s; benchmarks/bench_reference.py times it)",
    )
    ap.add_argument("--plot-only", action="store_true", help="redraw the figure from the CSV of the last run")
    args = ap.parse_args(argv)
    suffix = "_quick" if args.quick else ""
    if args.plot_only:
        import csv

        with open(RESULTS / f"work_precision{suffix}.csv", newline="") as fh:
            rows = [{k: _number(v) for k, v in r.items()} for r in csv.DictReader(fh)]
        plot(rows, RESULTS / f"work_precision{suffix}.png", 4.0 if args.quick else 44.0)
        return 0
    krows = kinematics(args.quick)
    write_csv(RESULTS / f"kinematic_precision{suffix}.csv", krows)
    rows, duration, t_ref = forward(args.quick, args.skip_study)
    write_csv(RESULTS / f"work_precision{suffix}.csv", rows)
    md = [
        f"# Work-precision\n\n{machine()}; {today()}; no-load forward scene, {duration:g} s simulated; "
        f"reference dopri5 rtol 1e-11 ({t_ref:.1f} s).\n",
        markdown_table(rows),
        "",
        "## Kinematic sweep: delta against closure tolerance and sweep step (one pitch on the incline)\n",
        markdown_table(krows),
        "",
    ]
    write_text(RESULTS / f"work_precision{suffix}.md", "\n".join(md))
    plot(rows, RESULTS / f"work_precision{suffix}.png", duration)
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
