"""Benchmark of reading long recordings: vibkit.read_recording against pandas.read_csv of the same file.

Run:  python benchmarks/bench_read.py [--quick]

For 1, 5 and 20 million rows (``--quick``: 0.2 and 1 million) a two-column CSV
(``time (s),acceleration (m/s^2)``, 2 kHz, a link-pass signal with harmonics and
noise) is written to a temporary folder (never committed) and read

* by ``pandas.read_csv(path)`` (pandas' C reader, all defaults): the baseline;
* by ``vibkit.read_recording(path)`` (dialect sniffed on the first lines, rows
  parsed by pandas' C reader, every check of the reader: time order, repeats,
  gaps, jitter, units, counters ...),

each case in a fresh Python process that reports its wall time for the read
alone and its peak resident memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``),
also after subtracting the memory it held right after its imports.  Then
``vibkit pitch`` runs on the largest file end to end (``vibkit.cli.main`` in a
subprocess: imports, reading, analysis).

Writes benchmarks/results/read.{md,csv} (``--quick``: read_quick.{md,csv}).
The machine is shared with other jobs; the 1-minute load average is recorded.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

HERE = Path(__file__).resolve().parent

FS = 2000.0  # [Hz]
F0 = 3.75  # link-pass frequency [Hz]: 0.5 m/s over a 133.33 mm pitch


def rss_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def current_rss_mb() -> float:
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return float("nan")


def worker(kind: str, path: str) -> None:
    """Runs in a fresh process: one read, then a JSON line with time and memory."""
    if kind == "pandas":
        import pandas as pd

        pd.read_csv(io.StringIO("time (s),x (m)\n0,1\n0.5,2\n1,3\n"))  # the same warm-up as vibkit's
        base = current_rss_mb()
        t0 = time.perf_counter()
        df = pd.read_csv(path)
        wall = time.perf_counter() - t0
        n = len(df)
    elif kind == "vibkit":
        from vibkit.io import read_recording

        warm = Path(path).with_name("warm-up.csv")  # imports done on first use (xarray, dask) are not reading
        warm.write_text("time (s),x (m)\n0,1\n0.5,2\n1,3\n")
        read_recording(warm)
        warm.unlink()
        base = current_rss_mb()
        t0 = time.perf_counter()
        ds = read_recording(path)
        wall = time.perf_counter() - t0
        n = ds.sizes["time"]
        assert "parsed by pandas' C reader" in ds.attrs["history"], "the fast path was not taken"
    elif kind == "pitch":
        from vibkit.cli import main

        base = current_rss_mb()
        t0 = time.perf_counter()
        rc = main(["pitch", path, "--speed", "0.5", "--json"])
        wall = time.perf_counter() - t0
        n = -1
        if rc != 0:
            raise SystemExit(rc)
    else:
        raise SystemExit(f"unknown worker {kind!r}")
    print(
        json.dumps({"kind": kind, "rows": n, "wall_s": wall, "peak_rss_mb": rss_mb(), "rss_after_import_mb": base}),
        file=sys.stderr if kind == "pitch" else sys.stdout,
    )


def make_file(path: Path, rows: int, seed: int = 7) -> int:
    """A 2 kHz link-pass recording (fundamental, 2 harmonics, noise), written in chunks. Returns bytes."""
    import numpy as np

    rng = np.random.default_rng(seed)
    chunk = 1_000_000
    with open(path, "w", encoding="ascii", newline="\n") as fh:
        fh.write("time (s),acceleration (m/s^2)\n")
        for start in range(0, rows, chunk):
            k = np.arange(start, min(rows, start + chunk))
            t = k / FS
            x = (
                0.3 * np.sin(2 * np.pi * F0 * t)
                + 0.1 * np.sin(2 * np.pi * 2 * F0 * t + 0.4)
                + 0.05 * np.sin(2 * np.pi * 3 * F0 * t + 1.1)
                + 0.05 * rng.standard_normal(k.size)
            )
            # time to 0.1 us with fixed decimals, values to 6 significant digits: what loggers write
            tt = np.char.mod("%.7f", t)
            xx = np.char.mod("%.6e", x)
            fh.write("\n".join(np.char.add(np.char.add(tt, ","), xx).tolist()))
            fh.write("\n")
    return path.stat().st_size


def run_worker(kind: str, path: Path, timeout: float = 1800) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(HERE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--worker", kind, str(path)],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )
    outer = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"worker {kind} failed ({proc.returncode}): {proc.stderr.strip()[-2000:]}")
    stream = proc.stderr if kind == "pitch" else proc.stdout
    line = [ln for ln in stream.splitlines() if ln.startswith('{"kind"')][-1]
    d = json.loads(line)
    d["process_wall_s"] = outer
    if kind == "pitch":
        d["output"] = json.loads(proc.stdout)
    return d


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.2 and 1 million rows; writes read_quick.*")
    ap.add_argument("--worker", nargs=2, metavar=("KIND", "PATH"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        worker(*a.worker)
        return 0
    sizes = [50_000] if a.quick else [1_000_000, 5_000_000, 20_000_000]
    load0 = os.getloadavg()[0]
    rows = []
    with tempfile.TemporaryDirectory(prefix="vibkit-bench-read-") as tmp:
        for n in sizes:
            path = Path(tmp) / f"rec_{n}.csv"
            t0 = time.perf_counter()
            size = make_file(path, n)
            print(f"{n:>10} rows: file {size / 1e6:.0f} MB written in {time.perf_counter() - t0:.1f} s", flush=True)
            pd_ = run_worker("pandas", path)
            vk = run_worker("vibkit", path)
            row = {
                "rows": n,
                "file_MB": round(size / 1e6, 1),
                "pandas_s": pd_["wall_s"],
                "vibkit_s": vk["wall_s"],
                "time_ratio": vk["wall_s"] / pd_["wall_s"],
                "pandas_peak_MB": pd_["peak_rss_mb"],
                "vibkit_peak_MB": vk["peak_rss_mb"],
                "peak_ratio": vk["peak_rss_mb"] / pd_["peak_rss_mb"],
                "pandas_read_MB": pd_["peak_rss_mb"] - pd_["rss_after_import_mb"],
                "vibkit_read_MB": vk["peak_rss_mb"] - vk["rss_after_import_mb"],
            }
            row["read_mem_ratio"] = row["vibkit_read_MB"] / row["pandas_read_MB"]
            rows.append(row)
            print(
                f"    pandas {pd_['wall_s']:.2f} s {pd_['peak_rss_mb']:.0f} MB | vibkit {vk['wall_s']:.2f} s "
                f"{vk['peak_rss_mb']:.0f} MB | ratios time {row['time_ratio']:.2f} peak {row['peak_ratio']:.2f} "
                f"read-memory {row['read_mem_ratio']:.2f}",
                flush=True,
            )
            if n == sizes[-1]:
                pitch = run_worker("pitch", path)
                out = pitch["output"]
                print(
                    f"    vibkit pitch end to end: {pitch['process_wall_s']:.1f} s, "
                    f"peak {pitch['peak_rss_mb']:.0f} MB,"
                    f" link pass {out.get('fundamental_hz')} Hz",
                    flush=True,
                )
            path.unlink()
    load1 = os.getloadavg()[0]
    suffix = "_quick" if a.quick else ""
    write_csv(RESULTS / f"read{suffix}.csv", rows)
    md = [
        f"# Reading long recordings: vibkit.read_recording vs pandas.read_csv ({today()})",
        "",
        f"Machine: {machine()}; load average (1 min) {load0:.2f} at start, {load1:.2f} at end "
        "(the machine is shared with other jobs). Each read in a fresh process; peak = peak resident memory "
        "of that process (ru_maxrss), read = peak minus the memory held after the imports.",
        "",
        "File: `time (s),acceleration (m/s^2)` at 2 kHz (time to 0.1 us, values to 6 digits), written to a "
        "temporary folder.",
        "",
        markdown_table(rows),
        "",
        f"`vibkit pitch` on the {sizes[-1]:,}-row file ({sizes[-1] / FS / 3600:.2f} h at 2 kHz), end to end in a "
        f"subprocess (imports, reading, analysis): **{pitch['process_wall_s']:.1f} s** wall, "
        f"peak {pitch['peak_rss_mb']:.0f} MB; link-pass {out.get('fundamental_hz')} Hz "
        f"(signal built at {F0} Hz).",
        "",
    ]
    write_text(RESULTS / f"read{suffix}.md", "\n".join(md))
    print(f"wrote {RESULTS / f'read{suffix}.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
