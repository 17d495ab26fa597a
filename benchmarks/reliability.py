"""Reliability table: a corpus of bad inputs run through ``vibkit.cli.main``, each in a fresh process.

    python benchmarks/reliability.py            # every case -> benchmarks/results/reliability.{md,csv}
    python benchmarks/reliability.py --quick    # without the heavy cases -> reliability_quick.{md,csv}

The corpus is ``tests/reliability/corpus.py`` plus every ``tests/reliability/corpus_*.py`` (their
``CASES`` lists), so a case added there is picked up here and by the tests without other edits.
Each case runs in its own work folder in a subprocess (faults injected in the child where a case
says so: a full disk, a signal during the write) and is judged: a clean one-line error (exit 1 or 2),
a result (exit 0), an interruption (exit 130/143), or a traceback/crash/hang; and whether any file
it protects (inputs, existing outputs, links, devices) changed or a temporary file was left.
"""

from __future__ import annotations

import argparse
import csv
import datetime as _dt
import importlib.util
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def _corpus():
    spec = importlib.util.spec_from_file_location(
        "vibkit_reliability_corpus", ROOT / "tests" / "reliability" / "corpus.py"
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _machine() -> str:
    try:
        load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    except OSError:
        load = "n/a"
    try:
        commit = (
            subprocess.run(
                ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
            ).stdout.strip()
            or "n/a"
        )
    except OSError:
        commit = "n/a"
    import vibkit

    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"vibkit {vibkit.__version__} (commit {commit}), user uid {os.getuid() if hasattr(os, 'getuid') else 'n/a'}, "
        f"load average {load} (the machine is shared)"
    )


def _md_cell(text: str, n: int = 110) -> str:
    text = " ".join(str(text).split()).replace("|", "\\|")
    return text if len(text) <= n else text[: n - 3] + "..."


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="leave out the heavy cases; write *_quick.* files")
    ap.add_argument("--only", help="run only cases whose name contains this (no files written)")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds before a case counts as a hang")
    ap.add_argument(
        "--code",
        help="run the vibkit package found in this folder instead (e.g. an older version "
        "unpacked with `git archive COMMIT vibkit | tar -x -C DIR`); writes "
        "reliability_<label>.{md,csv}; cases that write near system paths "
        "(/dev/null ...) or inject faults into new modules are not run, and "
        "--force/--overwrite are dropped (older code had no such flag)",
    )
    ap.add_argument("--label", default="before", help="label of a --code run (default: before)")
    a = ap.parse_args(argv)

    corpus = _corpus()
    cases = corpus.all_cases()
    if a.quick:
        cases = [c for c in cases if not c.heavy]
    if a.only:
        cases = [c for c in cases if a.only in c.name]
    left_out = []
    if a.code:
        left_out = [c.name for c in cases if corpus.touches_system(c) or c.prelude]
        cases = [c for c in cases if c.name not in left_out]
    rows = []
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="vibkit-reliability-") as top:
        for i, case in enumerate(cases, 1):
            t0 = time.perf_counter()
            res = corpus.run_case(
                case,
                Path(top) / f"case{i:03d}",
                inprocess=False,
                timeout=a.timeout,
                code_root=os.path.abspath(a.code) if a.code else None,
            )
            res["wall_s"] = time.perf_counter() - t0
            res["expect"] = case.expect
            res["note"] = case.note
            res["message"] = res["message"].replace(str(Path(top) / f"case{i:03d}"), "WORK")
            rows.append(res)
            print(
                f"[{i}/{len(cases)}] {case.name}: {res['outcome']}{'' if res['passed'] else ' FAILED ' + str(res['problems'])}"
                f" ({res['wall_s']:.1f} s)",
                file=sys.stderr,
            )
    wall = time.perf_counter() - t_all

    outcomes = Counter(r["outcome"] for r in rows)
    lost = sum(1 for r in rows if r["lost"])
    failed = [r for r in rows if not r["passed"]]
    summary = [
        ("inputs tried", len(rows)),
        ("clean one-line errors (exit 1 bad data / 2 usage)", outcomes["clean"]),
        ("successful results (exit 0)", outcomes["ok"]),
        ("interrupted cleanly (exit 130 / 143, nothing written)", outcomes["interrupted"]),
        ("tracebacks, crashes or hangs", outcomes["traceback"] + outcomes["hang"]),
        ("unclear exits", outcomes["unclear"]),
        ("cases with files lost, clobbered or temporaries left", lost),
        ("cases not as expected (exit code, message naming file/key, outputs)", len(failed)),
    ]
    if a.only:
        for k, v in summary:
            print(f"{k}: {v}")
        return 1 if failed else 0

    suffix = ("_quick" if a.quick else "") + (f"_{a.label}" if a.code else "")
    RESULTS.mkdir(parents=True, exist_ok=True)
    date = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    cmdline = (
        "python benchmarks/reliability.py"
        + (" --quick" if a.quick else "")
        + (f" --code {a.code} --label {a.label}" if a.code else "")
    )
    lines = [
        f"# Reliability: bad inputs through `vibkit.cli.main`{' (quick)' if a.quick else ''}"
        f"{f' ({a.label})' if a.code else ''}",
        "",
        f"Written by `{cmdline}` on {date}; "
        f"{_machine()}; {wall:.0f} s in all. Each case runs in a fresh process in its own folder; the corpus is "
        "`tests/reliability/corpus.py` (+ `corpus_*.py`)."
        + (
            f" Code run: `{a.code}` ({a.label}); not run against it (system paths or fault injection into "
            f"new modules): {', '.join(left_out) or 'none'}."
            if a.code
            else ""
        ),
        "",
        "| | count |",
        "|---|---:|",
    ]
    lines += [f"| {k} | {v} |" for k, v in summary]
    items = sorted({r["item"] for r in rows})
    lines += [
        "",
        "| item | tried | clean errors | results | interrupted | tracebacks | files lost | not as expected |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for it in items:
        rs = [r for r in rows if r["item"] == it]
        c = Counter(r["outcome"] for r in rs)
        lines.append(
            f"| {it} | {len(rs)} | {c['clean']} | {c['ok']} | {c['interrupted']} | "
            f"{c['traceback'] + c['hang']} | {sum(1 for r in rs if r['lost'])} | "
            f"{sum(1 for r in rs if not r['passed'])} |"
        )
    lines += [
        "",
        "| item | input tried | expected | outcome | exit | message (or note) |",
        "|---|---|---|---|---:|---|",
    ]
    for r in rows:
        msg = r["message"] or r["note"]
        mark = "" if r["passed"] else " **(not as expected: " + "; ".join(r["problems"]) + ")**"
        lines.append(
            f"| {r['item']} | {_md_cell(r['case'], 50)} | {r['expect']} | {r['outcome']}{mark} | "
            f"{r['returncode']} | {_md_cell(msg)} |"
        )
    (RESULTS / f"reliability{suffix}.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    with open(RESULTS / f"reliability{suffix}.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["item", "case", "expect", "outcome", "returncode", "passed", "files_lost", "wall_s", "message"])
        for r in rows:
            w.writerow(
                [
                    r["item"],
                    r["case"],
                    r["expect"],
                    r["outcome"],
                    r["returncode"],
                    r["passed"],
                    ";".join(r["lost"]),
                    f"{r['wall_s']:.2f}",
                    r["message"],
                ]
            )
    print(f"wrote {RESULTS / f'reliability{suffix}.md'}: " + ", ".join(f"{k} {v}" for k, v in summary))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
