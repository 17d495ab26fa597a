"""``vibkit bench``: run the repository's benchmark scripts (benchmarks/bench_*.py).

The scripts write their tables where ``-o`` says (passed to them as ``VIBKIT_BENCH_RESULTS``); by
default into a new temporary folder, so that a run never rewrites the tables the README quotes:
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
from .output import CLIError, msg, print_json, table

EPILOG = ("examples:\n  vibkit bench --quick                   # a smoke run of every script, into a temporary folder\n"
          "  vibkit bench --only signal -o out/bench\n"
          "  vibkit bench -o benchmarks/results     # what `make bench` runs: the tables the README quotes")


def add_parser(subparsers):
    s = add_command(subparsers, "bench", "run the repository's benchmark scripts (benchmarks/bench_*.py)", EPILOG)
    s.add_argument("--quick", action="store_true", help="pass --quick to every script")
    s.add_argument("--only", help="run only scripts whose name contains this")
    s.add_argument("-o", "--output", metavar="DIR", help="folder the scripts write their tables into "
                   "(default: a new temporary folder, printed)")
    s.add_argument("--root", help="repository root holding benchmarks/ (default: next to the vibkit package)")
    add_json(s, "JSON on stdout")
    s.set_defaults(func=run)
    return s


def _repo_root():
    return Path(__file__).resolve().parents[2]


def run(a):
    root = Path(a.root) if a.root else _repo_root()
    bdir = root / "benchmarks"
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
    out = Path(a.output) if a.output else Path(tempfile.mkdtemp(prefix="vibkit-bench-"))
    out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, VIBKIT_BENCH_RESULTS=str(out.resolve()))
    msg(f"note: results go to {out}")
    rows = []
    failed = 0
    for i, s in enumerate(scripts, 1):
        msg(f"[{i}/{len(scripts)}] {s.name} ...")
        cmd = [sys.executable, str(s)] + (["--quick"] if a.quick else [])
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.perf_counter() - t0
        ok = proc.returncode == 0
        failed += not ok
        last = (proc.stdout.strip().splitlines() or [""])[-1][:60]
        rows.append({"script": s.name, "returncode": proc.returncode, "wall_time_s": wall, "last_line": last})
        msg(f"    {'ok' if ok else 'FAILED'} in {wall:.1f} s")
    if a.json:
        print_json("bench", {"root": str(root), "output": str(out), "quick": bool(a.quick), "results": rows})
    else:
        print(table([[r["script"], "ok" if r["returncode"] == 0 else f"failed ({r['returncode']})",
                      f"{r['wall_time_s']:.1f}", r["last_line"]] for r in rows],
                    ("script", "status", "wall [s]", "last line")))
        print(f"results in {out}")
    if failed:
        raise CLIError(f"{failed} of {len(rows)} benchmark script(s) failed")
    return 0
