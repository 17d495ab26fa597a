"""Pitch you can trust (issue 11): the detector's false-alarm rate and detection probability, the
accuracy of the spectral and mean-phase estimators under a wandering speed, and the end-to-end time of
a 20 M-sample recording.

Run:  python benchmarks/bench_pitch.py [--quick]

Writes ``benchmarks/results/pitch{,_quick}.{md,csv}``.  Baselines side by side in the same process:
the spectral estimator alone (``link_pass_estimate``, what ``vibkit pitch`` did before) for the
wander accuracy and for the long record.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, machine, markdown_table, today, write_csv, write_text  # noqa: E402

from vibkit.diagnose.pitch import estimate_pitch  # noqa: E402
from vibkit.signal import link_pass_estimate  # noqa: E402
from vibkit.signal.detect import detect_link_pass  # noqa: E402

BAND = (2.45, 6.125)


def false_alarms(quick):
    n_rec = 100 if quick else 10000
    rng = np.random.default_rng(11)
    pv = np.array([detect_link_pass(rng.standard_normal(3000), 100.0, band=BAND).p_value for _ in range(n_rec)])
    rows = []
    for p in (0.05, 0.01, 1e-3):
        k = int(np.sum(pv < p))
        rows.append({"stated P_fa": p, "records": n_rec, "false alarms": k, "measured rate": k / n_rec,
                     "binomial sd": float(np.sqrt(p * (1 - p) / n_rec))})
    return rows


def _family(n, fs, f, rng, snr_db, amps=(1.0, 0.5, 0.3)):
    t = np.arange(n) / fs
    x = sum(a * np.cos(2 * np.pi * (k + 1) * f * t + 0.7 * k) for k, a in enumerate(amps))
    sigma = np.sqrt(sum(a * a / 2 for a in amps) / 10 ** (snr_db / 10))
    return x + sigma * rng.standard_normal(n)


def detection_probability(quick):
    trials = 10 if quick else 500
    rng = np.random.default_rng(12)
    rows = []
    for snr in (-21, -18, -15, -12, -9, -6):
        hits = 0
        for _ in range(trials):
            det = detect_link_pass(_family(3000, 100.0, 3.75, rng, snr), 100.0, band=BAND)
            hits += det.detected and abs(det.frequency_hz - 3.75) < 0.2
        rows.append({"SNR per sample [dB]": snr, "record [s]": 30, "trials": trials, "P_fa": 1e-3,
                     "detection probability": hits / trials})
    return rows


def _wandering(duration, fs, period, amp, snr_db, kind, rng, pitch=0.13333, v0=0.5):
    n = int(duration * fs)
    t = np.arange(n) / fs
    if kind == "sine":
        w = amp * np.sin(2 * np.pi * t / period + rng.uniform(0, 2 * np.pi))
    else:
        m = int(duration / period * 4) + 2
        knots = np.cumsum(rng.standard_normal(m))
        w = np.interp(t, np.linspace(0, duration, m), knots - knots.mean())
        w = amp * w / np.max(np.abs(w))
    v = v0 * (1 + w)
    f = v / pitch
    phi = 2 * np.pi * np.concatenate(([0.0], np.cumsum((f[1:] + f[:-1]) / 2) / fs))
    amps = (1.0, 0.5, 0.3)
    x = sum(a * np.cos((k + 1) * phi + 0.7 * k) for k, a in enumerate(amps))
    x = x + np.sqrt(sum(a * a / 2 for a in amps) / 10 ** (snr_db / 10)) * rng.standard_normal(n)
    return x, float(np.trapezoid(v, t) / t[-1]), pitch


def wander(quick):
    trials = 1 if quick else 10
    rng = np.random.default_rng(13)
    rows = []
    for duration in (30.0, 120.0, 600.0):
        for period in (10.0, 60.0, 300.0):
            es, ep, chosen = [], [], []
            for _ in range(trials):
                for kind in ("sine", "walk"):
                    snr = float(rng.uniform(0, 20))
                    fs = 50.0
                    x, v, pitch = _wandering(duration, fs, period, 0.02, snr, kind, rng)
                    spec = link_pass_estimate(x, fs, band=(v / 0.2, v / 0.08))
                    es.append(abs(v / spec.fundamental_hz / pitch - 1))
                    t = np.arange(x.size) / fs
                    est = estimate_pitch(xr.Dataset({"x": ("time", x)}, coords={"time": t}), speed=v)
                    ep.append(abs(est.pitch_m / pitch - 1))
                    chosen.append(est.method == "mean-phase")
            rows.append({"record [s]": duration, "wander period [s]": period, "records": len(es),
                         "spectral max err [%]": 100 * max(es), "spectral median err [%]": 100 * float(np.median(es)),
                         "vibkit pitch max err [%]": 100 * max(ep), "vibkit pitch median err [%]": 100 * float(np.median(ep)),
                         "mean-phase chosen": f"{sum(chosen)}/{len(chosen)}"})
    return rows


def long_record(quick):
    n = 200_000 if quick else 20_000_000
    fs = 2000.0
    rng = np.random.default_rng(14)
    t = np.arange(n) / fs
    f = 3.75 * (1 + 0.01 * np.sin(2 * np.pi * t / 120.0))
    phi = 2 * np.pi * np.cumsum(f) / fs
    del f
    x = np.cos(phi) + 0.5 * np.cos(2 * phi + 0.3) + 0.3 * np.cos(3 * phi + 1)
    x += rng.standard_normal(n)
    truth = float((phi[-1] - phi[0]) / (2 * np.pi * (n - 1) / fs))
    del phi
    rec = xr.Dataset({"x": ("time", x)}, coords={"time": t})
    rows = []
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t0 = time.perf_counter()
    est = estimate_pitch(rec, speed=0.5)
    wall = time.perf_counter() - t0
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rows.append({"analysis": "vibkit pitch (detect, decimate, spectral + mean-phase)", "samples": n,
                 "wall [s]": wall, "peak RSS growth [MB]": rss1 - rss0,
                 "rel. error of mean f": est.fundamental_hz / truth - 1, "method": est.method})
    t0 = time.perf_counter()
    spec = link_pass_estimate(x, fs, band=(2.5, 6.25))
    wall_b = time.perf_counter() - t0
    rss2 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rows.append({"analysis": "baseline: link_pass_estimate at 2 kHz (spectral only)", "samples": n,
                 "wall [s]": wall_b, "peak RSS growth [MB]": rss2 - rss1,
                 "rel. error of mean f": spec.fundamental_hz / truth - 1, "method": "spectral"})
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="fewer records, a 2 M-sample long record")
    args = p.parse_args()
    suffix = "_quick" if args.quick else ""
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    parts = {}
    for name, fn in (("false alarms", false_alarms), ("detection", detection_probability), ("wander", wander),
                     ("long record", long_record)):
        print(f"{name} ...", file=sys.stderr, flush=True)
        parts[name] = fn(args.quick)
    head = (f"# bench_pitch{suffix}\n\n{machine()}; {today()}; load average (1 min) at start {load:.2f}, at end "
            f"{os.getloadavg()[0]:.2f} (other jobs share the machine); total {time.perf_counter() - t0:.0f} s\n")
    text = head
    for name, rows in parts.items():
        text += f"\n## {name}\n\n" + markdown_table(rows) + "\n"
        write_csv(RESULTS / f"pitch_{name.replace(' ', '_')}{suffix}.csv", rows)
    write_text(RESULTS / f"pitch{suffix}.md", text)
    print(text)


if __name__ == "__main__":
    main()
