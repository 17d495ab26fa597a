"""``vibkit bench``: run the repository's benchmark scripts (benchmarks/bench_*.py)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from .options import add_command, add_json
from .output import CLIError, msg, print_json, table

EPILOG = "example:\n  vibkit bench --quick --only signal"


def add_parser(subparsers):
    s = add_command(subparsers, "bench", "run the repository's benchmark scripts (benchmarks/bench_*.py)", EPILOG)
    s.add_argument("--quick", action="store_true", help="pass --quick to every script")
    s.add_argument("--only", help="run only scripts whose name contains this")
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
    rows = []
    failed = 0
    for i, s in enumerate(scripts, 1):
        msg(f"[{i}/{len(scripts)}] {s.name} ...")
        cmd = [sys.executable, str(s)] + (["--quick"] if a.quick else [])
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.perf_counter() - t0
        ok = proc.returncode == 0
        failed += not ok
        last = (proc.stdout.strip().splitlines() or [""])[-1][:100]
        rows.append({"script": s.name, "returncode": proc.returncode, "wall_time_s": wall, "last_line": last})
        msg(f"    {'ok' if ok else 'FAILED'} in {wall:.1f} s")
    if a.json:
        print_json("bench", {"root": str(root), "quick": bool(a.quick), "results": rows})
    else:
        print(table([[r["script"], "ok" if r["returncode"] == 0 else f"failed ({r['returncode']})",
                      f"{r['wall_time_s']:.1f}", r["last_line"]] for r in rows],
                    ("script", "status", "wall [s]", "last line")))
    if failed:
        raise CLIError(f"{failed} of {len(rows)} benchmark script(s) failed")
    return 0
