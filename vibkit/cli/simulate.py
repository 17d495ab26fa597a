"""``vibkit simulate``: simulate a scene and write the result file."""

from __future__ import annotations

import json
import os
import textwrap
import time

from .options import add_command, add_force_overwrite, add_json, byte_size, positive, seconds_or_none
from .output import check_output, is_stdout, msg, output_path, print_json, table

EPILOG = (
    "examples:\n  vibkit simulate sim/leon.toml -o reports/leon.nc --duration 10\n"
    "  vibkit simulate las-palmas -o - > lp.nc   (a shipped scene by name; netCDF on stdout)"
)


def add_parser(subparsers):
    s = add_command(subparsers, "simulate", "simulate a scene and write the result (netCDF4/HDF5)", EPILOG)
    s.add_argument("scene", help="scene file (.toml), or the name of a shipped scene (las-palmas, leon ...)")
    s.add_argument(
        "-o", "--output", required=True, help="result file to write (.nc); a new path unless --force; '-': stdout"
    )
    add_force_overwrite(s, "result file")
    s.add_argument("--duration", type=positive, help="override the scene's duration [s] (kinematics: [m])")
    s.add_argument(
        "--max-result-bytes",
        type=byte_size,
        metavar="SIZE",
        help="refuse runs whose result would be larger, e.g. 500MB (default: the scene's "
        "[solver] max_result_bytes, $VIBKIT_MAX_RESULT_BYTES or 2GiB; 0: no limit)",
    )
    s.add_argument(
        "--max-wall-time",
        type=seconds_or_none,
        metavar="SECONDS",
        help="stop a forward integration after this long (default: the scene's [solver] max_wall_time, "
        "$VIBKIT_MAX_WALL_TIME or 600 s; 0: no limit)",
    )
    s.add_argument(
        "--check",
        action="store_true",
        default=None,
        help="forward scenes: say whether the result has converged: run again at tighter tolerances "
        "and compare the contact history, ripples, peak tension and frequencies (the scene's "
        "[solver] check = true does the same); the verdict is in the result's attrs",
    )
    add_json(s)
    s.set_defaults(func=run)
    return s


def run(a):
    import vibkit
    from vibkit.io import write_result

    check_output(a.output, [a.scene], a.force, json_flag=a.json)
    scene = vibkit.load_scene(a.scene)
    with output_path(a.output, ".nc") as target:  # '-o -': written to a temporary file, then to stdout
        return _run(a, vibkit, write_result, scene, target)


def _run(a, vibkit, write_result, scene, target):
    t0 = time.perf_counter()
    ds = vibkit.simulate(
        scene,
        duration=a.duration,
        progress=True,
        max_result_bytes=a.max_result_bytes,
        max_wall_time=a.max_wall_time,
        check=a.check,
    )
    wall = time.perf_counter() - t0
    path = write_result(ds, target, overwrite=a.force, inputs=[a.scene])
    path = a.output if is_stdout(a.output) else path
    resid = (
        float(ds["closure_residual"].max())
        if "closure_residual" in ds
        else float(ds.attrs.get("closure_residual_max", float("nan")))
    )
    summary = {
        "scene": scene.name,
        "analysis": scene.analysis,
        "output": os.fspath(path),
        "dims": {k: int(v) for k, v in ds.sizes.items()},
        "variables": {
            str(k): {"dims": list(v.dims), "units": v.attrs.get("units", "")} for k, v in ds.data_vars.items()
        },
        "closure_residual_max_m": resid,
        "wall_time_s": wall,
    }
    if "convergence" in ds.attrs:
        summary["convergence"] = json.loads(ds.attrs["convergence"])
    summary["warnings"] = [w for w in ds.attrs.get("warnings", "").split("\n") if w]
    summary["unchecked"] = [w for w in ds.attrs.get("unchecked", "").split("\n") if w]
    summary["notes"] = [w for w in ds.attrs.get("notes", "").split("\n") if w]
    for w in summary["warnings"]:
        msg(textwrap.fill(f"warning: {w}", 100, subsequent_indent="  "))
    for w in summary["unchecked"] + summary["notes"]:
        msg(f"note: {w}")
    if a.json:
        print_json("simulate", summary)
    else:
        print(f"scene     {scene.name} ({scene.analysis})")
        print(f"output    {summary['output']}")
        print(f"dims      {', '.join(f'{k}={v}' for k, v in summary['dims'].items())}")
        print(f"closure   max residual {resid:.3g} m")
        print(f"wall time {wall:.2f} s")
        if "convergence" in summary:
            print(f"check     {summary['convergence']['message']}")
        print(
            table(
                [[k, ",".join(v["dims"]), v["units"]] for k, v in summary["variables"].items()],
                ("variable", "dims", "units"),
            )
        )
    return 0
