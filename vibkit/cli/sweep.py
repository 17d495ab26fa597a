"""``vibkit sweep``: run a scene over a grid (or random draws) of its keys on Dask; results to Zarr."""

from __future__ import annotations

import argparse
import os
import shlex
import time

from vibkit.sweep.plan import _number, parse_vary

from .options import add_command, add_json, byte_size, positive
from .output import CLIError, msg, no_stdout, print_json, table

EPILOG = (
    "examples:\n  vibkit sweep sim/thesis-forward.toml --vary chain.link_pitch=0.1333:0.1373:9 \\\n"
    "      --vary effects.contact.stiffness=1e5,1e6,1e7 --duration 10 -o out/sweep.zarr\n"
    "  vibkit sweep sim/leon.toml --vary motion.speed=0.45:0.55 --samples 50 --seed 1 --keep delta \\\n"
    "      -o out/mc.zarr\n"
    "re-running the same command resumes an interrupted sweep;\n"
    "xarray.open_zarr('out/sweep.zarr') reads it; open_sweep('out/sweep.zarr') (from vibkit.sweep\n"
    "import open_sweep) also reads the runs of an interrupted one"
)


def vary(text):
    """argparse type of --vary KEY=SPEC (see :func:`vibkit.sweep.plan.parse_vary`)."""
    try:
        return parse_vary(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _whole(text):
    """A whole number >= 0 written plainly (``1_000`` and ``1e3`` are refused)."""
    if not text.strip().isdigit() or not text.strip().isascii():
        raise argparse.ArgumentTypeError(f"expected a whole number such as 50, got {text!r}")
    return int(text)


def _settle(text):
    """Seconds >= 0, a plain decimal number (``0_5`` is refused)."""
    try:
        return _number(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a time in seconds such as 2.5, got {text!r}") from None


def add_parser(subparsers):
    s = add_command(
        subparsers, "sweep", "run a scene over a grid (or random draws) of its keys on Dask; results to Zarr", EPILOG
    )
    s.add_argument("scene", help="scene file (.toml)")
    s.add_argument(
        "--vary",
        action="append",
        type=vary,
        required=True,
        metavar="KEY=SPEC",
        help="a dotted scene key and its values: A:B:N (linspace), a,b,c (list), A:B (a range, "
        "with --samples); repeat for more keys",
    )
    s.add_argument("-o", "--output", required=True, help="Zarr directory to write (re-run to resume)")
    s.add_argument("--samples", type=_whole, help="Monte Carlo: draw this many scenes (uniformly in each A:B)")
    s.add_argument("--seed", type=_whole, help="seed of the Monte Carlo draws (default 0)")
    s.add_argument(
        "--keep", action="append", metavar="OUTPUT", help="keep this output's full series (e.g. delta); repeat for more"
    )
    s.add_argument(
        "--settle", type=_settle, help="start-up left out of the summaries [s] (default: a quarter of a forward run)"
    )
    s.add_argument("--duration", type=positive, help="override every run's duration [s] (kinematics: [m])")
    s.add_argument(
        "--scheduler", help="address of a running Dask scheduler (default: Dask's configuration, else a local cluster)"
    )
    s.add_argument(
        "--workers",
        type=_whole,
        help="worker processes of a local cluster, started where it pays (default: one per core; 0: every run in "
        "this process)",
    )
    s.add_argument("--max-runs", type=_whole, help="compute at most this many runs now (resume later)")
    s.add_argument(
        "--max-result-bytes",
        type=byte_size,
        metavar="SIZE",
        help="refuse sweeps whose result (runs x summaries and kept series) would be larger, e.g. 4GiB "
        "(default: the scene's [solver] max_result_bytes, $VIBKIT_MAX_RESULT_BYTES or 2GiB; 0: no "
        "limit)",
    )
    s.add_argument("--force", action="store_true", help="discard a store at -o that holds a different sweep")
    s.add_argument(
        "--check",
        action="store_true",
        help="forward scenes: check each run's convergence (a converged flag per run; see simulate --check)",
    )
    s.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_json(s)
    s.set_defaults(func=run)
    return s


def run(a):
    no_stdout(a.output, "a Zarr store (a folder)")
    # a Zarr store is a folder, re-used to resume: only refuse one that is the scene itself (the
    # library refuses a folder that is not this sweep's store unless --force)
    if os.path.exists(a.output) and os.path.exists(a.scene) and os.path.samefile(a.output, a.scene):
        raise CLIError(f"output {a.output!r} is the scene file; refusing to overwrite it")
    varied = {}
    for key, spec in a.vary:
        if key in varied:
            raise CLIError(f"--vary {key} given twice")
        varied[key] = spec
    t0 = time.perf_counter()
    try:
        ds = _sweep(a, varied)
    except OSError as exc:
        if getattr(exc, "vibkit_resume", False):  # a full disk with runs stored: the command that resumes
            exc.vibkit_note += f": {shlex.join(['vibkit', *a.argv])}"
        raise
    wall = time.perf_counter() - t0
    return _print(a, ds, wall)


def _sweep(a, varied):
    import vibkit

    return vibkit.sweep(
        a.scene,
        varied,
        output=a.output,
        samples=a.samples,
        seed=a.seed,
        keep=a.keep or (),
        settle=a.settle,
        duration=a.duration,
        scheduler=a.scheduler,
        n_workers=a.workers or None,
        parallel=False if a.workers == 0 else None,  # None: on Dask where that pays
        force=a.force,
        progress=not a.quiet,
        max_runs=a.max_runs,
        check=a.check,
        max_result_bytes=a.max_result_bytes,
    )


def _print(a, ds, wall):
    import numpy as np

    st = ds["status"]
    keys = [k.strip() for k in ds.attrs["varied_keys"].split(",")]
    meaning = dict(zip((int(v) for v in st.attrs["flag_values"]), st.attrs["flag_meanings"].split()))
    cols = {
        name: ds[name].values
        for name in (
            "status",
            "error",
            "link_pass_frequency",
            "delta_mean",
            "delta_ripple",
            "peak_link_tension",
            "wall_time",
        )
    }
    runs = []
    for idx in np.ndindex(*st.shape):
        at = dict(zip(st.dims, idx))
        row = {
            "values": {k: ds[k].isel({d: at[d] for d in ds[k].dims}).item() for k in keys},
            "status": meaning.get(int(cols["status"][idx]), str(int(cols["status"][idx]))),
            "error": str(cols["error"][idx]),
        }
        for name in ("link_pass_frequency", "delta_mean", "delta_ripple", "peak_link_tension", "wall_time"):
            row[name] = float(cols[name][idx])
        if a.check:
            c = float(ds["converged"].values[idx])
            row["converged"] = None if c != c else bool(c)
        runs.append(row)
    complete = ds.attrs.get("runs_pending", 0) == 0 and ds.attrs.get("vibkit_sweep_state", "") != "running"
    summary = {
        "scene": a.scene,
        "output": os.fspath(a.output),
        "sweep": ds.attrs["sweep"],
        "dims": {k: int(v) for k, v in ds["status"].sizes.items()},
        "runs": int(ds.attrs["runs"]),
        "ok": int(ds.attrs["runs_ok"]),
        "failed": int(ds.attrs["runs_failed"]),
        "invalid": int(ds.attrs["runs_invalid"]),
        "pending": int(ds.attrs.get("runs_pending", 0)),
        "computed": int(ds.attrs["runs_computed"]),
        "reused": int(ds.attrs["runs_reused"]),
        "complete": bool(complete),
        "seed": ds.attrs.get("seed"),
        "wall_time_s": wall,
        "units": {
            "link_pass_frequency": "Hz",
            "delta_mean": "m",
            "delta_ripple": "m",
            "peak_link_tension": "N",
            "wall_time": "s",
        },
        "run_results": runs,
    }
    if a.json:
        print_json("sweep", summary)
    else:
        print(f"scene     {a.scene} ({ds.attrs['sweep']}: {', '.join(f'{k}={v}' for k, v in summary['dims'].items())})")
        print(f"output    {summary['output']}" + ("" if complete else " (incomplete: run the same command to resume)"))
        print(
            f"runs      {summary['runs']}: {summary['ok']} ok, {summary['failed']} failed, "
            f"{summary['invalid']} invalid"
            + (f", {summary['pending']} pending" if summary["pending"] else "")
            + f" ({summary['computed']} computed now, {summary['reused']} from the store)"
        )
        print(f"wall time {wall:.1f} s")
        shown = runs[:40]
        conv = {True: "yes", False: "no", None: "-"}
        print(
            table(
                [
                    [
                        *(f"{v:.6g}" if isinstance(v, float) else v for v in r["values"].values()),
                        r["status"],
                        *([conv[r["converged"]]] if a.check else []),
                        f"{r['link_pass_frequency']:.5f}",
                        f"{1e3 * r['delta_mean']:.4f}",
                        f"{1e3 * r['delta_ripple']:.4f}",
                        f"{r['peak_link_tension']:.1f}",
                        f"{r['wall_time']:.2f}",
                    ]
                    for r in shown
                ],
                (
                    *keys,
                    "status",
                    *(["converged"] if a.check else []),
                    "link pass [Hz]",
                    "delta [mm]",
                    "ripple [mm]",
                    "peak tension [N]",
                    "wall [s]",
                ),
            )
        )
        if len(runs) > len(shown):
            print(f"... {len(runs) - len(shown)} more runs in {summary['output']}")
        for r in runs:
            if r["error"]:
                msg(f"run {', '.join(f'{k}={v}' for k, v in r['values'].items())}: {r['status']}: {r['error']}")
    if summary["runs"] and not summary["ok"] and not summary["pending"]:
        # every run failed or was refused: nothing was computed, bad data (the store keeps what each run said)
        msg(f"vibkit sweep: no run could be made ({summary['failed']} failed, {summary['invalid']} invalid)")
        return 1
    return 0
