"""Does the pitch estimate's sigma cover the truth when the source drifts?  The fraction of records whose truth
lies within 2 sigma, on drifting synthetic sources and on chain signals with speed wander, before and after the
parts check (the sigma each record stated before it is kept in the result's ``parts``); and the verdicts on a
gait-like cadence at every forced speed from 0.3 to 0.75 m/s through ``vibkit pitch --channel X --speed v``.

Run:  python benchmarks/bench_coverage.py [--quick]

Writes ``benchmarks/results/coverage{,_quick}.{md,csv}`` and ``coverage_gait_at_forced_speeds{,_quick}.csv``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from vibkit.diagnose.pitch import estimate_pitch

from _common import RESULTS, machine, markdown_table, support, today, write_csv, write_text

chain, drift = support.chain, support.drift

SPEED = 0.5
NOMINAL = 0.4 / 3.0
FORCED_SPEEDS = tuple(np.round(np.arange(0.30, 0.751, 0.05), 2))
SOURCES = (
    "steady chain",
    "linear drift 1 %",
    "linear drift 3 %",
    "random wander 0.5 %",
    "gait 2.72 Hz +-1 %",
    "chain, +-2 % speed wander",
)


def _record(x, fs):
    return xr.Dataset({"x": ("time", x)}, coords={"time": np.arange(x.size) / fs})


def _source(kind, rng, quick):
    """``(x, fs, speed, centre, record mean)`` of one record of ``kind``; the speed makes the centre a plausible
    link pass of a 133.33 mm chain (the estimate is judged as a chain's)."""
    fs = 50.0
    if kind == "steady chain":
        f = float(rng.uniform(3.0, 4.5))
        x = chain.noisy_family(int(60 * fs), fs, f, rng, float(rng.uniform(-6, 10)))
        return x, fs, f * NOMINAL, f, f
    if kind.startswith("linear drift"):
        d = 0.01 if "1 %" in kind else 0.03
        f = float(rng.uniform(3.0, 4.5))
        x, c, m = drift.linear_drift(120.0, fs, f, d, float(rng.uniform(-3, 10)), rng)
        return x, fs, c * NOMINAL, c, m
    if kind.startswith("random wander"):
        f = float(rng.uniform(3.0, 4.5))
        x, c, m = drift.ou_wander(300.0, fs, f, 0.005, 30.0, float(rng.uniform(-3, 10)), rng)
        return x, fs, c * NOMINAL, c, m
    if kind.startswith("gait"):
        x, c, m = drift.gait(600.0 if not quick else 300.0, 25.0, rng, snr_db=float(rng.uniform(-3, 10)))
        return x, 25.0, c * NOMINAL, c, m
    x, v, pitch = chain.wandering(
        120.0,
        fs,
        float(rng.choice([10.0, 60.0])),
        0.02,
        float(rng.uniform(-3, 10)),
        str(rng.choice(["sine", "walk"])),
        rng,
    )
    return x, fs, v, v / pitch, v / pitch


def coverage(quick):
    n = 4 if quick else 60
    rng = np.random.default_rng(30)
    rows = []
    for kind in SOURCES:
        c = dict(records=0, numbers=0, refused=0, inconclusive=0, verdicts=0, widened=0, verdicts_covered=0)
        cov = dict(before_mean=0, after_mean=0, before_centre=0, after_centre=0)
        for _ in range(n):
            x, fs, v, centre, mean = _source(kind, rng, quick)
            est = estimate_pitch(_record(x, fs), speed=v, nominal_pitch=NOMINAL)
            c["records"] += 1
            if not est.has_link_pass:
                c["refused"] += 1
                continue
            c["numbers"] += 1
            c["inconclusive"] += est.status == "inconclusive"
            c["verdicts"] += est.status == "ok"
            s_after = est.fundamental_sigma_hz
            s_before = est.parts.get("sigma_before_hz", s_after)
            c["widened"] += bool(est.parts.get("widened"))
            f = est.fundamental_hz
            cov["before_mean"] += abs(f - mean) <= 2 * s_before
            cov["after_mean"] += abs(f - mean) <= 2 * s_after
            cov["before_centre"] += abs(f - centre) <= 2 * s_before
            cov["after_centre"] += abs(f - centre) <= 2 * s_after
            c["verdicts_covered"] += est.status == "ok" and abs(f - centre) <= 2 * s_after
        k = max(c["numbers"], 1)
        rows.append(
            {
                "source": kind,
                "records": c["records"],
                "refused": c["refused"],
                "inconclusive": c["inconclusive"],
                "verdict (ok)": c["verdicts"],
                "sigma widened": c["widened"],
                "2-sigma coverage of the record mean, before": cov["before_mean"] / k,
                "after": cov["after_mean"] / k,
                "2-sigma coverage of the centre, before": cov["before_centre"] / k,
                "after ": cov["after_centre"] / k,
                "refused or record mean covered": (c["refused"] + cov["after_mean"]) / c["records"],
                "refused or centre covered": (c["refused"] + cov["after_centre"]) / c["records"],
                "no verdict or centre covered": (c["refused"] + c["inconclusive"] + c["verdicts_covered"])
                / c["records"],
            }
        )
        print(f"  {kind}: {rows[-1]}", file=sys.stderr, flush=True)
    return rows


def _csv(path, x, fs, rng):
    """A three-channel CSV: the gait on ``wrist``, the same gait scaled on ``other`` with noise, noise on ``z``."""
    t = np.arange(x.size) / fs
    cols = np.column_stack([t, x, 0.5 * x + 0.3 * rng.standard_normal(x.size), rng.standard_normal(x.size)])
    np.savetxt(path, cols, delimiter=",", header="time (s),wrist (m/s^2),other (m/s^2),z (m/s^2)", comments="")


def forced_speeds(quick):
    """``vibkit pitch REC --channel wrist --speed v`` (and with a nominal pitch that makes the cadence a plausible
    link pass at that speed) on gait-like records, at every speed from 0.3 to 0.75 m/s."""
    from vibkit.cli import main

    n = 1 if quick else 5
    rng = np.random.default_rng(31)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i in range(n):
            x, c, _ = drift.gait(300.0 if quick else 600.0, 25.0, rng, snr_db=float(rng.uniform(0, 10)))
            p = Path(tmp) / f"gait{i}.csv"
            _csv(p, x, 25.0, rng)
            paths.append((p, c))
        for v in FORCED_SPEEDS:
            codes = {0: 0, 1: 0, 3: 0}
            other = 0
            for p, c in paths:
                for extra in ([], ["--nominal-pitch", f"{v / c * 1.005:.6f}"]):
                    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                        rc = main(["pitch", str(p), "--channel", "wrist", "--speed", str(v), *extra])
                    if rc in codes:
                        codes[rc] += 1
                    else:
                        other += 1
            rows.append(
                {
                    "forced speed [m/s]": float(v),
                    "runs": 2 * len(paths),
                    "verdicts (exit 0)": codes[0],
                    "refused (exit 1)": codes[1],
                    "inconclusive (exit 3)": codes[3],
                    "other exit": other,
                }
            )
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="a few records of each kind, 5-minute gaits")
    args = p.parse_args()
    suffix = "_quick" if args.quick else ""
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    parts = {}
    for name, fn in (("coverage", coverage), ("gait at forced speeds", forced_speeds)):
        print(f"{name} ...", file=sys.stderr, flush=True)
        parts[name] = fn(args.quick)
        stem = "coverage" if name == "coverage" else f"coverage_{name.replace(' ', '_')}"
        write_csv(RESULTS / f"{stem}{suffix}.csv", parts[name])
    text = (
        f"# bench_coverage{suffix}\n\n{machine()}; {today()}; load average (1 min) at start {load:.2f}, at end "
        f"{os.getloadavg()[0]:.2f} (other jobs share the machine); total {time.perf_counter() - t0:.0f} s\n\n"
        "Coverage: the fraction of records with a frequency (ok or inconclusive) whose truth lies within 2 sigma of "
        "it, with the sigma before the parts check and after; the record mean is the total phase over the time, the "
        "centre the frequency the source wanders about. Every record is judged as a 133.33 mm chain's at the speed "
        "that makes its centre a plausible link pass.\n"
    )
    for name, rows in parts.items():
        text += f"\n## {name}\n\n" + markdown_table(rows) + "\n"
    write_text(RESULTS / f"coverage{suffix}.md", text)
    print(text)


if __name__ == "__main__":
    main()
