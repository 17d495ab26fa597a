"""Shared helpers of the benchmark scripts: machine description, timing, atomic result files, and
``support`` (tests/support: the synthetic chain signals the tests use)."""

from __future__ import annotations

import datetime as dt
import importlib.util
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

# where the scripts write: benchmarks/results/ (what the docs quote; `make bench`), or the folder
# `vibkit bench -o DIR` gives them in VIBKIT_BENCH_RESULTS (default there: a new temporary folder)
RESULTS = Path(os.environ.get("VIBKIT_BENCH_RESULTS") or Path(__file__).resolve().parent / "results")


def _support():
    """tests/support, the helpers the tests use (synthetic chain signals), imported from its folder as
    ``support``: the scripts build the signals the tests check, with no path set up beforehand."""
    if "support" in sys.modules:
        return sys.modules["support"]
    folder = Path(__file__).resolve().parents[1] / "tests" / "support"
    spec = importlib.util.spec_from_file_location(
        "support", folder / "__init__.py", submodule_search_locations=[str(folder)]
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules["support"] = mod
    spec.loader.exec_module(mod)
    return mod


def __getattr__(name):
    # `from _common import support` loads tests/support on first use: the scripts that need no
    # synthetic signal run without tests/ beside them
    if name == "support":
        return _support()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, {platform.system()}"


def today() -> str:
    return dt.date.today().isoformat()


def best_of(fn, repeat=3, number=1):
    """Best wall time of ``repeat`` runs of ``number`` calls. [s per call]"""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def write_text(path: Path, text: str) -> None:
    """Atomic write: a temporary file in the same folder, then os.replace."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


def write_csv(path: Path, rows: list[dict]) -> None:
    """Rows as CSV (fields with commas or quotes quoted, as the csv module reads them)."""
    import csv
    import io

    cols = list(rows[0])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    w.writerows([[_fmt(r[c]) for c in cols] for r in rows])
    write_text(path, buf.getvalue())


def markdown_table(rows: list[dict]) -> str:
    cols = list(rows[0])
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(_fmt(r[c]) for c in cols) + " |" for r in rows]
    return "\n".join(out)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)
