"""``vibkit bench``: run the repository's benchmark scripts (benchmarks/bench_*.py).

The scripts are part of a clone of the repository, not of the installed package (the wheel): an installed
vibkit without ``--root`` says so in one line and exits 1.

The scripts write their tables where ``-o`` says (passed to them as ``VIBKIT_BENCH_RESULTS``); by
default into a new temporary folder, so that a run never rewrites the tables the docs quote:
``make bench`` (``vibkit bench -o benchmarks/results``) is what regenerates those.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .options import add_command, add_json
from .output import CLIError, msg, no_stdout, print_json, table

EPILOG = (
    "examples:\n  vibkit bench --quick                   # a smoke run of every script, into a temporary folder\n"
    "  vibkit bench --only signal -o out/bench\n"
    "  vibkit bench -o benchmarks/results     # what `make bench` runs: the tables the docs quote"
)


def add_parser(subparsers):
    s = add_command(
        subparsers,
        "bench",
        "run the benchmark scripts of a clone of the repository (benchmarks/bench_*.py; not in an installed wheel)",
        EPILOG,
    )
    s.add_argument(
        "--quick",
        action="store_true",
        help="pass --quick to every script (a smoke run: the scripts run side by side, one per core)",
    )
    s.add_argument("--only", help="run only scripts whose name contains this")
    s.add_argument(
        "-o",
        "--output",
        metavar="DIR",
        help="folder the scripts write their tables into (default: a new temporary folder, printed)",
    )
    s.add_argument(
        "--force",
        action="store_true",
        help="write into a -o folder that already holds files (the scripts replace theirs, e.g. read_quick.md)",
    )
    s.add_argument(
        "--root", help="the clone holding benchmarks/ (default: the clone vibkit runs from, if it runs from one)"
    )
    add_json(s, "JSON on stdout")
    s.set_defaults(func=run)
    return s


def _repo_root():
    return Path(__file__).resolve().parents[2]


def run(a):
    root = Path(a.root) if a.root else _repo_root()
    bdir = root / "benchmarks"
    if not bdir.is_dir() and not a.root:
        raise CLIError(
            "the benchmark scripts (benchmarks/) are part of a clone of the repository, not of the installed "
            f"package ({Path(__file__).resolve().parents[1]}): run vibkit bench in a clone, or give --root CLONE"
        )
    if not bdir.is_dir():
        raise CLIError(f"{bdir}: no benchmarks folder (give --root, the repository holding benchmarks/)")
    scripts = sorted(bdir.glob("bench_*.py"))
    if (bdir / "work_precision.py").exists():
        scripts.append(bdir / "work_precision.py")
    if a.only:
        scripts = [s for s in scripts if a.only in s.stem]
        if not scripts:
            raise CLIError(f"--only {a.only!r} matches no script in {bdir}")
    if not scripts:
        raise CLIError(f"{bdir}: no bench_*.py script")
    no_stdout(a.output, "a folder of result tables")
    if a.output is not None:
        _check_output_folder(Path(a.output), a.force)
    out = Path(a.output) if a.output else Path(tempfile.mkdtemp(prefix="vibkit-bench-"))
    out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, VIBKIT_BENCH_RESULTS=str(out.resolve()))
    msg(f"note: results go to {out}")
    # a full run measures: one script at a time, nothing beside it; a quick run is a smoke test of every
    # script, whose timings mean nothing, so it keeps every core busy (one script per core at a time)
    parallel = max(1, os.cpu_count() or 1) if a.quick else 1
    rows = _run_scripts(scripts, root, env, quick=a.quick, parallel=parallel)
    failed = sum(r["returncode"] != 0 for r in rows)
    if a.json:
        print_json("bench", {"root": str(root), "output": str(out), "quick": bool(a.quick), "results": rows})
    else:
        print(
            table(
                [
                    [
                        r["script"],
                        "ok" if r["returncode"] == 0 else f"failed ({r['returncode']})",
                        f"{r['wall_time_s']:.1f}",
                        r["last_line"],
                    ]
                    for r in rows
                ],
                ("script", "status", "wall [s]", "last line"),
            )
        )
        print(f"results in {out}")
    if failed:
        raise CLIError(f"{failed} of {len(rows)} benchmark script(s) failed")
    return 0


def _check_output_folder(out: Path, force: bool):
    """-o names a folder the scripts write their tables into: refused when it is something else, or when it
    already holds files (a script would replace one of the user's, e.g. read_quick.md) unless --force."""
    if not str(out).strip():
        raise CLIError("-o is empty; expected a folder for the benchmark tables")
    if out.exists() and not out.is_dir():
        raise CLIError(f"-o {out}: is not a folder; expected a folder for the benchmark tables")
    if out.is_dir() and not force:
        held = sorted(p.name for p in out.iterdir())
        if held:
            raise CLIError(
                f"-o {out}: the folder already holds {len(held)} file(s) ({', '.join(held[:3])}"
                f"{' ...' if len(held) > 3 else ''}) that the scripts may replace; give --force to write there "
                "anyway, or a new or empty folder"
            )


def _run_scripts(scripts, root, env, *, quick, parallel):
    """Run the scripts, ``parallel`` at a time; one row per script, in the scripts' order."""
    pending = list(enumerate(scripts, 1))
    running = {}
    rows = {}
    while pending or running:
        while pending and len(running) < parallel:
            i, s = pending.pop(0)
            msg(f"[{i}/{len(scripts)}] {s.name} ...")
            out = tempfile.TemporaryFile(mode="w+")
            cmd = [sys.executable, str(s)] + (["--quick"] if quick else [])
            proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=out, stderr=subprocess.STDOUT, text=True)
            running[proc] = (i, s, out, time.perf_counter())
        for proc in list(running):
            if proc.poll() is None:
                continue
            i, s, out, t0 = running.pop(proc)
            wall = time.perf_counter() - t0
            out.seek(0)
            last = (out.read().strip().splitlines() or [""])[-1][:60]
            out.close()
            rows[i] = {"script": s.name, "returncode": proc.returncode, "wall_time_s": wall, "last_line": last}
            msg(f"    {s.name}: {'ok' if proc.returncode == 0 else 'FAILED'} in {wall:.1f} s")
        if running:
            time.sleep(0.05)
    return [rows[i] for i in sorted(rows)]
