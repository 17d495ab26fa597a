"""What a user waits for, each as a ratio to the baseline named beside it, measured side by side in one run.

Run:  python benchmarks/bench_user_costs.py [--quick] [--rows NAME,...] [--merge]

Every case runs in a fresh Python process (``sys.executable``, the vibkit beside this script) and is timed in
CPU seconds (user + system of the child, ``resource.getrusage(RUSAGE_CHILDREN)``): the project's machines
are shared with other jobs, and CPU time moves far less with their load than wall time does (the wall
time and the 1-minute load average are recorded too). Cases and their baselines alternate, the median of
``--repeat`` runs is kept. Peak memory is the child's own peak resident set (``VmHWM``: ``ru_maxrss`` keeps
the parent's peak across fork and exec; it is the fallback where there is no ``/proc``).

A vibkit command run as its own process freezes its objects once its output is flushed (``gc.freeze``: the
interpreter's exit then does not collect them). The issue's import baseline is ``python -c "import numpy,
scipy.signal, pandas, xarray"`` as a user runs it, which pays those collections; ``spectrum`` is also set against the
same imports frozen at the end (:data:`FROZEN`), which leaves vibkit's own imports and work in the ratio. pandas' read
(``pitch8h``), the links' and the report's import baselines freeze at the end as the command does.

Rows (``--rows`` picks some):

* ``first``: the first command after install (``vibkit simulate leon`` of 2 s, every kernel it needs compiled
  into an empty ``NUMBA_CACHE_DIR``) against the same command warm (the cache it filled);
* ``import``: ``import vibkit.cli.app, vibkit.io, vibkit.signal`` against
  ``import numpy, scipy.signal, pandas, xarray``;
* ``spectrum``: ``vibkit spectrum`` of a 10 s recording (whole command) against the same import baseline,
  and against that baseline plus one ``xarray.Dataset`` with a time index (xarray then imports dask, when
  installed: what reading any file into a Dataset costs);
* ``pitch8h``: ``vibkit pitch`` of 8 h at 200 Hz (5.76 million rows; ``--quick``: 20 min) against
  ``pandas.read_csv`` of the same file (its process: import and read); peak memory against the samples' bytes,
  whole (the process's peak RSS) and over the interpreter with the command's imports (peak RSS minus that of a
  process that only imports them and builds one small Dataset), and the peak of reading the file alone
  (``vibkit.io.read_recording``) over the same interpreter: where the command's peak is when it is the reader's;
* ``report``: ``vibkit report`` of the Las Palmas recording with its scene, warm (kernels cached, its simulation
  kept on disk), against the 5 CPU-s a user should wait at most and against what any report imports (the readers'
  packages, one Dataset, matplotlib's PDF backend; without dask, as the report's own process runs xarray, and its
  objects frozen at the end, as the report's process leaves them to the interpreter's exit);
* ``links``: ``vibkit links --escalator`` of 10 loops of the tests' 90-link profile (``--quick``: 3 loops), after
  the first call (the worn link's signature runs kept on disk), against the import baseline above (reading the
  netCDF recording into a Dataset needs those anyway) and ``python -c "import numpy"``;
* ``fleet``: ``vibkit fleet scan`` of 200 recordings of 30 s (``--quick``: 8), in process, files per CPU
  second, against ``pandas.read_csv`` of the same files in one process;
* ``simulate``: ``vibkit.simulate`` of the shipped ``leon`` scene with its shipped outputs, in one process after a
  warm-up: simulated seconds per CPU second (x real time).
* ``sweep``: ``vibkit.sweep`` of 16 runs of 10 s and of 16 runs of 120 s (the no-load forward scene from 0.5 m/s,
  delta only; ``--quick``: 4 runs of 1 s and of 2 s) on a fresh local cluster of 2 workers against 1 (wall time: the
  target), and the default sweep (runs in the process unless a cluster pays; the row says which it chose) against a
  plain Python loop of ``vibkit.simulate`` over the same varied scenes (CPU time). The short sweep is a cluster's
  start-up and little else; the long one is where the runs outweigh it.

Writes benchmarks/results/user_costs.md (``--quick``: user_costs_quick.md); ``--merge`` keeps the rows of the table
already there that this run does not measure (several people regenerate different rows).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from _common import RESULTS, machine, markdown_table, today, write_text

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SPEED = 0.5  # [m/s]
PITCH = 0.1333  # [m]
ROWS = ("first", "import", "spectrum", "pitch8h", "report", "links", "fleet", "simulate", "sweep")
BASE_IMPORT = "import numpy, scipy.signal, pandas, xarray"
#: what a vibkit command run as its own process does once its output is flushed (``cli.app.main``): its objects
#: frozen, so that the interpreter's exit does not collect them; every import baseline a command is set against does
#: the same, so that the ratio is of the work, not of that saving
FROZEN = "import gc\ngc.freeze()\n"
#: the interpreter with what ``vibkit pitch`` imports before it reads (xarray's dask included, which its first
#: Dataset imports): the baseline of the command's peak memory
#: what any report imports before its work: the readers' packages, one Dataset and matplotlib's PDF backend; dask
#: marked not importable first, as ``vibkit report`` run as its own process does (``runtime.duck_arrays.without_dask``),
#: and its objects frozen at the end, as that process leaves them to the interpreter's exit (``cli.app.main``)
REPORT_IMPORTS = (
    "import sys\nsys.modules['dask'] = None\n"
    "import numpy, scipy.signal, pandas, xarray, matplotlib\nmatplotlib.use('Agg')\n"
    "import matplotlib.pyplot\nfrom matplotlib.backends import backend_pdf\n"
    "xarray.Dataset({'x': ('time', numpy.zeros(3))}, coords={'time': numpy.arange(3.0)})\n" + FROZEN
)
PITCH_IMPORTS = (
    "import numpy, xarray, vibkit.cli.app, vibkit.io, vibkit.diagnose.channels\n"
    "xarray.Dataset({'x': ('time', numpy.zeros(3))}, coords={'time': numpy.arange(3.0)})\n"
)


def child(code, env=None, cwd=None):
    """Run ``code`` in a fresh interpreter: (CPU seconds, wall seconds, peak RSS [MB], its last stdout line)."""
    probe = (
        textwrap.dedent(code)
        + "\nimport resource as _r, sys as _s\n"
        # the peak of this process's own memory (VmHWM, reset by exec): ru_maxrss keeps the parent's peak across
        # fork and exec, so every child of a parent that has held a large recording would show at least that much
        + "try:\n    _kb = [int(_l.split()[1]) for _l in open('/proc/self/status') if _l.startswith('VmHWM:')][0]\n"
        + "except (OSError, IndexError):\n    _kb = _r.getrusage(_r.RUSAGE_SELF).ru_maxrss\n"
        + "print('maxrss_kb', _kb, file=_s.stderr)\n"
    )
    penv = dict(os.environ, **(env or {}))
    penv["PYTHONPATH"] = str(ROOT) + os.pathsep + penv.get("PYTHONPATH", "")  # this checkout's vibkit
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=penv, cwd=cwd or ROOT)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"child failed ({proc.returncode}):\n{code}\n{proc.stderr[-2000:]}")
    rss = [ln for ln in proc.stderr.splitlines() if ln.startswith("maxrss_kb")][-1]
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return cpu, wall, int(rss.split()[1]) / 1024.0, (proc.stdout.strip().splitlines() or [""])[-1]


def cli(args):
    """Code running ``vibkit ARGS`` as the ``vibkit`` script does: its own command line, ``vibkit.cli.main()``."""
    return (
        f"import sys\nsys.argv = ['vibkit', *{list(map(str, args))!r}]\n"
        "from vibkit.cli import main\nrc = main()\nassert rc in (0, 1, 3), rc\n"
    )


def compile_sources():
    """vibkit's modules compiled to bytecode, as an installed vibkit has them (pip compiles a wheel's modules when
    it installs it): a checkout run with ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module it
    imports from source in every child (about 0.5 CPU-s of the 10 s spectrum's 100 modules)."""
    import compileall

    compileall.compile_dir(ROOT / "vibkit", quiet=1)


def side_by_side(cases, repeat):
    """Run each (name, code, env) ``repeat`` times, interleaved; medians of CPU, wall and peak RSS per name."""
    runs = {name: [] for name, _c, _e in cases}
    for _ in range(repeat):
        for name, code, env in cases:
            runs[name].append(child(code, env))
    return {
        name: {
            "cpu": statistics.median(r[0] for r in rs),
            "wall": statistics.median(r[1] for r in rs),
            "rss": max(r[2] for r in rs),
            "out": rs[-1][3],
        }
        for name, rs in runs.items()
    }


def write_recording(path, duration, fs, seed=1):
    """A link-pass family with noise, ``time_s,accel_m_s2`` (pandas writes it: millions of rows in seconds)."""
    import numpy as np
    import pandas as pd

    from _common import support

    t = np.arange(int(round(duration * fs))) / fs
    x = support.chain.random_phase_family(t, SPEED / PITCH, np.random.default_rng(seed))
    pd.DataFrame({"time_s": t, "accel_m_s2": x}).to_csv(path, index=False, float_format="%.6f")
    return t.size


def row(what, case, baseline, cpu, base_cpu, ratio, target, note=""):
    return {
        "what a user does": what,
        "case": case,
        "baseline": baseline,
        "CPU-s": cpu,
        "baseline CPU-s": base_cpu,
        "ratio": ratio,
        "target": target,
        "note": note,
    }


#: the first cell of each row's table line begins with one of these (the row names of --rows)
ROW_PREFIXES = {
    "first": "first command after install",
    "import": "import the CLI",
    "spectrum": "vibkit spectrum of",
    "pitch8h": "vibkit pitch of",
    "report": "vibkit report of",
    "links": "vibkit links ",
    "fleet": "vibkit fleet scan",
    "simulate": "vibkit.simulate of",
    "sweep": "vibkit sweep of",
}


def row_name(first_cell):
    """The --rows name of a table line's first cell (None for a line of no known row)."""
    return next((name for name, prefix in ROW_PREFIXES.items() if first_cell.startswith(prefix)), None)


def kept_rows(path, measured):
    """The table lines of ``path`` (as written: ``| ... |``) of the rows not measured in this run, by row name."""
    if not path.exists():
        return {}
    kept = {}
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        name = row_name(cells[0]) if line.startswith("| ") else None
        if name is not None and name not in measured:
            kept.setdefault(name, []).append(line)
    return kept


def flush(rows, quick, repeat, load0, merge=False):
    """Write the table of the rows measured so far (atomically): a row that fails later leaves the others.

    ``merge``: the rows of the table already there that this run does not measure are kept, in the order of
    :data:`ROWS` (each as its own run wrote it: the header says which rows this run measured)."""
    if not rows:
        return ""
    load1 = os.getloadavg()[0]
    suffix = "_quick" if quick else ""
    path = RESULTS / f"user_costs{suffix}.md"
    table = markdown_table(rows)
    measured = {row_name(r["what a user does"]) for r in rows}
    note = ""
    if merge:
        kept = kept_rows(path, measured)
        if kept:
            lines = table.splitlines()
            mine = {}
            for line in lines[2:]:
                mine.setdefault(row_name(line[2:]), []).append(line)
            body = [ln for name in ROWS for ln in (mine.get(name) or kept.get(name) or [])]
            table = "\n".join(lines[:2] + body)
            note = (
                f" Rows measured in this run: {', '.join(n for n in ROWS if n in measured)}; the others ("
                f"{', '.join(n for n in ROWS if n in kept)}) are kept from the table as an earlier run wrote them "
                "(`--merge`)."
            )
    text = (
        "# What a user waits for (`benchmarks/bench_user_costs.py`)\n\n"
        f"{today()}, {machine()}; 1-minute load average {load0:.1f} at the start, {load1:.1f} after the last row (the "
        "machine is shared with other jobs: times are CPU seconds of the whole child process, user + system, "
        f"which move far less with the load than wall time). Median of {repeat} interleaved runs per case"
        + (" (quick: smoke sizes)" if quick else "")
        + "; every case a fresh `python` process, vibkit's modules from bytecode as an installed vibkit has them, "
        "a command run as the `vibkit` script runs it (its own command line). Ratio: case / baseline (for the "
        "simulation: simulated over CPU seconds)." + note + "\n\n" + table + "\n"
    )
    write_text(path, text)
    return text


def links_rows(tmp, loops, repeat):
    """``vibkit links`` of ``loops`` loops, first call and the calls after it, against the imports baselines."""
    from bench_links_cache import PROFILE_90, _recording

    folder = tmp / "links"
    folder.mkdir()
    text = PROFILE_90.replace("teeth = 28", 'teeth = 28\ndirection = "down"')
    profile = folder / "E90-down.toml"
    profile.write_text(text)
    saved = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(folder / "recording-cache")  # the recording's own scene: not the user's
    try:
        rec = _recording(folder, text, loops)
    finally:
        if saved is None:
            os.environ.pop("XDG_CACHE_HOME")
        else:
            os.environ["XDG_CACHE_HOME"] = saved
    env = {"XDG_CACHE_HOME": str(folder / "cache")}  # the signature's runs kept here by the first call
    code = cli(["links", rec, "--escalator", profile, "--json"])
    first = child(code, env)
    got = side_by_side(
        [("base", BASE_IMPORT + "\n" + FROZEN, None), ("numpy", "import numpy\n" + FROZEN, None), ("links", code, env)],
        repeat,
    )
    c, b, n = got["links"]["cpu"], got["base"]["cpu"], got["numpy"]["cpu"]
    what = f"vibkit links --escalator of {loops} loops (90 links), after the first call"
    note = f"first call {first[0]:.2f} CPU-s (the signature's runs simulated and kept); target 1.5 CPU-s"
    return [
        row(what, "whole command", BASE_IMPORT, c, b, c / b, "<= 1.5 CPU-s", note),
        row(what, "whole command", 'python -c "import numpy"', c, n, c / n, "-"),
    ]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a smoke run: small inputs, one repeat")
    ap.add_argument("--repeat", type=int, help="runs per case (median kept; default 3, quick 1)")
    ap.add_argument("--rows", default=",".join(ROWS), help=f"rows to measure (default all: {','.join(ROWS)})")
    ap.add_argument(
        "--merge",
        action="store_true",
        help="keep the rows of the table already written that this run does not measure (default: a new table)",
    )
    a = ap.parse_args(argv)
    repeat = a.repeat or (1 if a.quick else 3)
    wanted = [r.strip() for r in a.rows.split(",") if r.strip()]
    unknown = set(wanted) - set(ROWS)
    if unknown:
        ap.error(f"--rows: unknown {sorted(unknown)}; expected some of {','.join(ROWS)}")
    compile_sources()
    load0 = os.getloadavg()[0]
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-user-costs-") as tmp:
        tmp = Path(tmp)

        if "first" in wanted:
            cache = tmp / "numba-cache"
            env = {"NUMBA_CACHE_DIR": str(cache)}
            code = cli(["simulate", "leon", "--duration", "2", "-o", str(tmp / "first.nc"), "--force"])
            cold = child(code, env)  # an empty kernel cache: what the first command after install pays
            warm = side_by_side([("warm", code, env)], repeat)["warm"]
            rows.append(
                row(
                    "first command after install (simulate leon, 2 s)",
                    "cold: empty NUMBA_CACHE_DIR",
                    "the same command warm",
                    cold[0],
                    warm["cpu"],
                    cold[0] / warm["cpu"],
                    "<= 10",
                    f"wall {cold[1]:.0f} s cold, {warm['wall']:.1f} s warm",
                )
            )

        flush(rows, a.quick, repeat, load0, a.merge)

        if "import" in wanted or "spectrum" in wanted:
            ten = tmp / "ten-seconds.csv"
            write_recording(ten, 10.0, 200.0)
            cases = [
                ("base", BASE_IMPORT + "\n", None),
                ("base-frozen", BASE_IMPORT + "\n" + FROZEN, None),
                (
                    "base+dataset",
                    BASE_IMPORT
                    + "\nxarray.Dataset({'x': ('time', numpy.zeros(3))}, coords={'time': numpy.arange(3.0)})\n",
                    None,
                ),
            ]
            if "import" in wanted:
                cases.append(("import", "import vibkit.cli.app, vibkit.io, vibkit.signal\n", None))
            if "spectrum" in wanted:
                cases.append(("spectrum", cli(["spectrum", ten, "--band", "2.5:6"]), None))
            got = side_by_side(cases, repeat)
            base, based = got["base"]["cpu"], got["base+dataset"]["cpu"]
            if "import" in wanted:
                c = got["import"]["cpu"]
                rows.append(
                    row("import the CLI, readers, signal", "import vibkit...", BASE_IMPORT, c, base, c / base, "-")
                )
            if "spectrum" in wanted:
                c = got["spectrum"]["cpu"]
                rows.append(
                    row("vibkit spectrum of 10 s at 200 Hz", "whole command", BASE_IMPORT, c, base, c / base, "<= 1.1")
                )
                frozen = got["base-frozen"]["cpu"]
                rows.append(
                    row(
                        "vibkit spectrum of 10 s at 200 Hz",
                        "whole command",
                        "the same imports, their objects frozen at the end as the command leaves its own (what is left: "
                        "vibkit's imports and work)",
                        c,
                        frozen,
                        c / frozen,
                        "-",
                    )
                )
                rows.append(
                    row(
                        "vibkit spectrum of 10 s at 200 Hz",
                        "whole command",
                        "the same imports + one xarray.Dataset (xarray imports dask)",
                        c,
                        based,
                        c / based,
                        "-",
                    )
                )

        flush(rows, a.quick, repeat, load0, a.merge)

        if "pitch8h" in wanted:
            hours = 1 / 3 if a.quick else 8.0
            path = tmp / "day.csv"
            t0 = time.perf_counter()
            n = write_recording(path, hours * 3600.0, 200.0)
            print(f"{n} rows written in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
            got = side_by_side(
                [
                    ("pandas", f"import pandas\npandas.read_csv({str(path)!r})\n" + FROZEN, None),
                    ("pitch", cli(["pitch", path, "--speed", SPEED, "--json"]), None),
                    ("imports", PITCH_IMPORTS, None),
                    ("read", PITCH_IMPORTS + f"vibkit.io.read_recording({str(path)!r})\n", None),
                ],
                max(1, repeat - 1),
            )
            c, b = got["pitch"]["cpu"], got["pandas"]["cpu"]
            samples_mb = n * 8 / 2**20
            above = got["pitch"]["rss"] - got["imports"]["rss"]
            rows.append(
                row(
                    f"vibkit pitch of {hours:g} h at 200 Hz ({n:,} rows)",
                    "whole command",
                    "pandas.read_csv of the file (its process)",
                    c,
                    b,
                    c / b,
                    "<= 3 x baseline + 1 s",
                    f"target {3 * b + 1:.1f} CPU-s; peak RSS {got['pitch']['rss']:.0f} MB = "
                    f"{got['pitch']['rss'] / samples_mb:.1f} x the samples' {samples_mb:.0f} MB (pandas "
                    f"{got['pandas']['rss']:.0f} MB); over the interpreter with the command's imports "
                    f"({got['imports']['rss']:.0f} MB): {above:.0f} MB = {above / samples_mb:.1f} x, target <= 4 x; "
                    f"reading the file alone {got['read']['rss'] - got['imports']['rss']:.0f} MB over it "
                    f"({got['read']['cpu']:.2f} CPU-s with its imports)",
                )
            )

        flush(rows, a.quick, repeat, load0, a.merge)

        if "report" in wanted:
            code = cli(
                [
                    "report",
                    ROOT / "data/field/las-palmas-accelerometer.csv",
                    "--scene",
                    ROOT / "sim/las-palmas.toml",
                    "-o",
                    tmp / "lp.pdf",
                    "--force",
                ]
            )
            child(code)  # warm: the kernels it needs in the cache, its simulation kept
            both = side_by_side([("report", code, None), ("imports", REPORT_IMPORTS, None)], repeat)
            got = both["report"]
            rows.append(
                row(
                    "vibkit report of Las Palmas (with its scene), warm",
                    "whole command",
                    "5 CPU-s",
                    got["cpu"],
                    5.0,
                    got["cpu"] / 5.0,
                    "<= 1",
                    "its simulation kept on disk by scene",
                )
            )
            rows.append(
                row(
                    "vibkit report of Las Palmas (with its scene), warm",
                    "whole command",
                    "import numpy, scipy.signal, pandas, xarray, matplotlib's PDF backend; one Dataset (dask blocked and objects frozen at the end, as in the report)",
                    got["cpu"],
                    both["imports"]["cpu"],
                    got["cpu"] / both["imports"]["cpu"],
                    "-",
                    f"the report's own work: {got['cpu'] - both['imports']['cpu']:.1f} CPU-s over its imports",
                )
            )

        flush(rows, a.quick, repeat, load0, a.merge)

        if "links" in wanted:
            rows += links_rows(tmp, 3 if a.quick else 10, repeat)

        flush(rows, a.quick, repeat, load0, a.merge)

        if "fleet" in wanted:
            from bench_fleet import make_fleet

            n = 8 if a.quick else 200
            rec = tmp / "visits"
            cat = make_fleet(rec, n, 30.0)
            files = sorted(str(p) for p in rec.iterdir())
            scan = (
                "from vibkit.fleet import FleetDB\n"
                "import tempfile, os\n"
                "with FleetDB(os.path.join(tempfile.mkdtemp(), 'f.sqlite')) as db:\n"
                f"    res = db.scan({str(rec)!r}, {str(cat)!r}, parallel=False)\n"
                f"assert len(res.added) == {n}, res.failed[:3]\n"
            )
            got = side_by_side(
                [
                    ("pandas", f"import pandas\nfor p in {files!r}:\n    pandas.read_csv(p)\n", None),
                    ("scan", scan, None),
                ],
                repeat,
            )
            c, b = got["scan"]["cpu"], got["pandas"]["cpu"]
            rows.append(
                row(
                    f"vibkit fleet scan of {n} files of 30 s, in process",
                    "FleetDB.scan(parallel=False)",
                    "pandas.read_csv of the same files",
                    c,
                    b,
                    c / b,
                    ">= 100 files per CPU-s",
                    f"{n / c:.1f} files per CPU-s (pandas {n / b:.0f})",
                )
            )

        flush(rows, a.quick, repeat, load0, a.merge)

        if "simulate" in wanted:
            duration = 10.0 if a.quick else 44.0
            code = textwrap.dedent(
                f"""
                import resource, vibkit
                scene = vibkit.load_scene("leon")
                vibkit.simulate(scene, duration=1.0)  # warm: kernels loaded
                r0 = resource.getrusage(resource.RUSAGE_SELF)
                vibkit.simulate(scene, duration={duration})
                r1 = resource.getrusage(resource.RUSAGE_SELF)
                print((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
                """
            )
            got = [float(child(code)[3]) for _ in range(repeat)]
            c = statistics.median(got)
            rows.append(
                row(
                    f"vibkit.simulate of leon, {duration:g} s, shipped outputs",
                    "the call (in process, warm)",
                    "real time",
                    c,
                    duration,
                    duration / c,
                    ">= 500 x real time",
                    "ratio: simulated seconds per CPU second",
                )
            )

        if "sweep" in wanted:
            rows += sweep_rows(tmp, *((4, 1.0) if a.quick else (16, 10.0)), repeat)
            # a sweep whose runs outweigh a cluster's start-up (about 2 s of simulation a run)
            rows += sweep_rows(tmp, *((4, 2.0) if a.quick else (16, 120.0)), repeat)

    print(flush(rows, a.quick, repeat, load0, a.merge))
    return 0


def sweep_rows(tmp, n, duration, repeat):
    """Row ``sweep``: ``n`` runs of ``duration`` [s] of the study's forward scene, 2 workers against 1 on fresh
    local clusters (wall), the default sweep against a plain loop of ``vibkit.simulate`` (CPU); every case a fresh
    process, interleaved."""
    import tomllib

    from vibkit.sweep.plan import to_toml

    data = tomllib.loads((ROOT / "sim" / "thesis-forward.toml").read_text())
    data["run"].update(duration=duration, initial_speed=0.5)
    data["outputs"] = {"variables": ["delta"]}
    scene = tmp / f"sweep-scene-{duration:g}.toml"
    scene.write_text(to_toml(data))
    vary = {"effects.contact.stiffness": f"5e5:2e6:{n}"}
    head = f"import vibkit\nscene, vary = {str(scene)!r}, {vary!r}\n"
    guard = "if __name__ == '__main__':\n"  # the local cluster's workers import the main module again
    cases = [
        (
            "loop",
            head
            + "from vibkit.model.scene import parse_scene\nfrom vibkit.sweep.plan import plan_sweep, varied_text\n"
            + "plan = plan_sweep(scene, vary)\n"
            + "for p in plan.points:\n    vibkit.simulate(parse_scene(varied_text(plan.text, p)), progress=False)\n",
            None,
        ),
        (
            "default",
            head
            + guard
            + f"    ds = vibkit.sweep(scene, vary, progress=False)\n    assert int(ds.attrs['runs_ok']) == {n}\n"
            + "    import sys\n    print('on a local Dask cluster' if 'distributed' in sys.modules else 'in process')\n",
            None,
        ),
    ]
    for w in (1, 2):
        cases.append(
            (
                f"dask{w}",
                head
                + guard
                + f"    ds = vibkit.sweep(scene, vary, n_workers={w}, parallel=True, progress=False)\n"
                + f"    assert int(ds.attrs['runs_ok']) == {n}\n",
                None,
            )
        )
    got = side_by_side(cases, repeat)
    what = f"vibkit sweep of {n} runs of {duration:g} s"
    d1, d2 = got["dask1"], got["dask2"]
    loop, auto = got["loop"], got["default"]
    return [
        row(
            what + ", fresh local cluster",
            "2 workers (wall)",
            "1 worker (wall)",
            d2["cpu"],
            d1["cpu"],
            d2["wall"] / d1["wall"],
            "< 1 (wall)",
            f"ratio of wall times: {d2['wall']:.1f} s against {d1['wall']:.1f} s; CPU in the CPU columns",
        ),
        row(
            what + f", as it chooses (here: {auto['out'].strip().splitlines()[-1]})",
            "vibkit.sweep default",
            "a plain Python loop of vibkit.simulate",
            auto["cpu"],
            loop["cpu"],
            auto["cpu"] / loop["cpu"],
            "-",
            f"wall {auto['wall']:.1f} s against {loop['wall']:.1f} s",
        ),
    ]


if __name__ == "__main__":
    sys.exit(main())
