"""Pitch you can trust: the detector's false-alarm rate and detection probability, the
accuracy of the spectral and mean-phase estimators under a wandering speed, false verdicts on chain-free
records of twelve kinds, the verdict rate on chain signals with +-2 % speed wander against SNR, and the
end-to-end time of a 20 M-sample recording.

Run:  python benchmarks/bench_pitch.py [--quick] [--only PART ...] [--records N]

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

import numpy as np
import xarray as xr

from vibkit.diagnose.pitch import estimate_pitch
from vibkit.signal import link_pass_estimate
from vibkit.signal.detect import detect_link_pass

from _common import RESULTS, machine, markdown_table, support, today, write_csv, write_text

chain = support.chain  # the synthetic chain signals the tests use

BAND = (2.45, 6.125)


def false_alarms(quick):
    n_rec = 100 if quick else 10000
    rng = np.random.default_rng(11)
    pv = np.array([detect_link_pass(rng.standard_normal(3000), 100.0, band=BAND).p_value for _ in range(n_rec)])
    rows = []
    for p in (0.05, 0.01, 1e-3):
        k = int(np.sum(pv < p))
        rows.append(
            {
                "stated P_fa": p,
                "records": n_rec,
                "false alarms": k,
                "measured rate": k / n_rec,
                "binomial sd": float(np.sqrt(p * (1 - p) / n_rec)),
            }
        )
    return rows


def detection_probability(quick):
    trials = 10 if quick else 500
    rng = np.random.default_rng(12)
    rows = []
    for snr in (-21, -18, -15, -12, -9, -6):
        hits = 0
        for _ in range(trials):
            det = detect_link_pass(chain.noisy_family(3000, 100.0, 3.75, rng, snr), 100.0, band=BAND)
            hits += det.detected and abs(det.frequency_hz - 3.75) < 0.2
        rows.append(
            {
                "SNR per sample [dB]": snr,
                "record [s]": 30,
                "trials": trials,
                "P_fa": 1e-3,
                "detection probability": hits / trials,
            }
        )
    return rows


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
                    x, v, pitch = chain.wandering(duration, fs, period, 0.02, snr, kind, rng)
                    spec = link_pass_estimate(x, fs, band=(v / 0.2, v / 0.08))
                    es.append(abs(v / spec.fundamental_hz / pitch - 1))
                    t = np.arange(x.size) / fs
                    est = estimate_pitch(xr.Dataset({"x": ("time", x)}, coords={"time": t}), speed=v)
                    ep.append(abs(est.pitch_m / pitch - 1))
                    chosen.append(est.method == "mean-phase")
            rows.append(
                {
                    "record [s]": duration,
                    "wander period [s]": period,
                    "records": len(es),
                    "spectral max err [%]": 100 * max(es),
                    "spectral median err [%]": 100 * float(np.median(es)),
                    "vibkit pitch max err [%]": 100 * max(ep),
                    "vibkit pitch median err [%]": 100 * float(np.median(ep)),
                    "mean-phase chosen": f"{sum(chosen)}/{len(chosen)}",
                }
            )
    return rows


# ------------------------------------------------------------------- false verdicts

NOMINAL = 0.4 / 3.0
SPEED = 0.5
FV_FS = 100.0


def _coloured(n, rng, alpha):
    """Noise with a 1/f^alpha power spectrum (alpha 1: pink, 2: brown)."""
    spec = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n)
    f[0] = f[1]
    return np.fft.irfft(spec / f ** (alpha / 2), n)


def chain_free(kind, rng):
    """One chain-free record ``(x, fs)`` of a kind; durations 10, 20 or 40 s."""
    fs = 250.0 if kind == "elevator hum" else FV_FS
    n = int(fs * rng.choice([10.0, 20.0, 40.0]))
    t = np.arange(n) / fs
    noise = rng.standard_normal(n)
    lvl = 10 ** rng.uniform(-4, 0)
    if kind == "white noise":
        return noise, fs
    if kind == "pink noise":
        return _coloured(n, rng, 1.0), fs
    if kind == "brown noise":
        return np.cumsum(noise), fs
    if kind == "step":
        return np.where(t >= rng.uniform(0.1, 0.9) * t[-1], 1.0, 0.0) + lvl * noise, fs
    if kind == "impulses":
        x = lvl * noise
        x[rng.integers(0, n, rng.integers(1, 6))] += rng.uniform(0.5, 2.0)
        return x, fs
    if kind == "chirp":
        f1, f2 = rng.uniform(0.3, 5.0), rng.uniform(5.0, 45.0)
        return np.cos(2 * np.pi * (f1 * t + (f2 - f1) * t**2 / (2 * t[-1]))) + lvl * noise, fs
    if kind == "pure tone":
        f = np.exp(rng.uniform(np.log(0.3), np.log(45.0)))
        return np.cos(2 * np.pi * f * t + rng.uniform(0, 6.3)) + lvl * noise, fs
    if kind == "AM tone":
        fc, fm = np.exp(rng.uniform(np.log(0.5), np.log(45.0))), rng.uniform(0.1, 2.0)
        return (1 + rng.uniform(0.3, 1.0) * np.cos(2 * np.pi * fm * t)) * np.cos(2 * np.pi * fc * t) + lvl * noise, fs
    if kind == "quantised noise":
        step = rng.uniform(0.5, 2.0)
        return np.round(noise / step) * step, fs
    if kind == "clipped noise":
        c = rng.uniform(0.2, 1.5)
        return np.clip(noise, -c, c), fs
    if kind == "gait":
        f0 = rng.uniform(1.6, 2.2)
        w = _coloured(n, rng, 2.0)
        phi = 2 * np.pi * np.cumsum(f0 * (1 + 0.03 * (w - w.mean()) / max(1e-12, float(np.std(w))))) / fs
        amps = (1.0, 0.6, 0.4, 0.25, 0.15)
        x = sum(a * np.cos((k + 1) * phi + rng.uniform(0, 6.3)) for k, a in enumerate(amps))
        return x + 0.2 * noise, fs
    if kind == "elevator hum":
        # trapezoid speed profile (acceleration pulses), car sway at 1-2 Hz, 50/100 Hz motor hum
        a = np.zeros(n)
        t0 = rng.uniform(0.1, 0.3) * t[-1]
        t1 = rng.uniform(0.6, 0.8) * t[-1]
        a[(t > t0) & (t < t0 + 1.5)] = 1.0
        a[(t > t1) & (t < t1 + 1.5)] = -1.0
        sway = 0.1 * np.cos(2 * np.pi * rng.uniform(1.0, 2.0) * t)
        hum = 0.05 * np.cos(2 * np.pi * 50 * t) + 0.02 * np.cos(2 * np.pi * 100 * t + 1)
        return a + sway + hum + 0.02 * noise, fs
    raise ValueError(kind)


KINDS = (
    "white noise",
    "pink noise",
    "brown noise",
    "step",
    "impulses",
    "chirp",
    "pure tone",
    "AM tone",
    "quantised noise",
    "clipped noise",
    "gait",
    "elevator hum",
)


def false_verdicts(quick, n_records=None):
    """Chain-free records analysed as ``vibkit pitch --speed 0.5 --nominal-pitch 0.13333`` would."""
    import scipy.stats

    n_rec = n_records or (120 if quick else 12000)
    rng = np.random.default_rng(18)
    per = {k: [0, 0, 0, 0] for k in KINDS}  # records, verdicts, pitches (ok or inconclusive), too short
    for i in range(n_rec):
        kind = KINDS[i % len(KINDS)]
        x, fs = chain_free(kind, rng)
        rec = xr.Dataset({"x": ("time", x)}, coords={"time": np.arange(x.size) / fs})
        per[kind][0] += 1
        try:
            est = estimate_pitch(rec, speed=SPEED, nominal_pitch=NOMINAL)
        except ValueError:
            per[kind][3] += 1
            continue
        per[kind][1] += est.verdict not in (None, "inconclusive")
        per[kind][2] += est.has_link_pass
        if i % 500 == 0:
            print(f"  {i}/{n_rec}", file=sys.stderr, flush=True)
    rows = []
    tot = np.sum([v for v in per.values()], axis=0)
    for k, (n, v, p, e) in list(per.items()) + [("all", tuple(int(u) for u in tot))]:
        rows.append(
            {
                "kind": k,
                "records": n,
                "false verdicts": v,
                "rate": v / n,
                "95 % upper bound": float(scipy.stats.beta.ppf(0.95, v + 1, n - v)) if n else float("nan"),
                "pitch given (ok or inconclusive)": p,
                "refused as too short": e,
            }
        )
    return rows


def wander_power(quick):
    """Chain signals with +-2 % speed wander: how often vibkit gives a verdict (status ok) vs SNR."""
    trials = 4 if quick else 100
    rng = np.random.default_rng(19)
    rows = []
    for snr in (-15, -12, -9, -6, -3, 0, 10):
        found = verdict = 0
        errs = []
        for i in range(trials):
            x, v, pitch = chain.wandering(
                30.0,
                100.0,
                float(rng.choice([10.0, 60.0])),
                0.02,
                snr,
                "sine" if i % 2 else "walk",
                rng,
                pitch=NOMINAL * (1 + rng.uniform(0, 0.03)),
            )
            rec = xr.Dataset({"x": ("time", x)}, coords={"time": np.arange(x.size) / 100.0})
            est = estimate_pitch(rec, speed=v, nominal_pitch=NOMINAL)
            found += est.has_link_pass
            verdict += est.status == "ok"
            if est.has_link_pass:
                errs.append(abs(est.pitch_m / pitch - 1))
        rows.append(
            {
                "SNR per sample [dB]": snr,
                "record [s]": 30,
                "records": trials,
                "link pass found": found / trials,
                "verdict given (ok)": verdict / trials,
                "max pitch err when found [%]": 100 * max(errs) if errs else float("nan"),
            }
        )
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
    rows.append(
        {
            "analysis": "vibkit pitch (detect, decimate, spectral + mean-phase)",
            "samples": n,
            "wall [s]": wall,
            "peak RSS growth [MB]": rss1 - rss0,
            "rel. error of mean f": est.fundamental_hz / truth - 1,
            "method": est.method,
        }
    )
    t0 = time.perf_counter()
    spec = link_pass_estimate(x, fs, band=(2.5, 6.25))
    wall_b = time.perf_counter() - t0
    rss2 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rows.append(
        {
            "analysis": "baseline: link_pass_estimate at 2 kHz (spectral only)",
            "samples": n,
            "wall [s]": wall_b,
            "peak RSS growth [MB]": rss2 - rss1,
            "rel. error of mean f": spec.fundamental_hz / truth - 1,
            "method": "spectral",
        }
    )
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="fewer records, a 2 M-sample long record")
    p.add_argument(
        "--only",
        action="append",
        choices=("false alarms", "detection", "wander", "false verdicts", "wander power", "long record"),
        help="run only this part (repeatable)",
    )
    p.add_argument("--records", type=int, help="chain-free records for the false-verdict part (default 12000)")
    args = p.parse_args()
    suffix = "_quick" if args.quick else ""
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    parts = {}
    fns = (
        ("false alarms", false_alarms),
        ("detection", detection_probability),
        ("wander", wander),
        ("false verdicts", lambda q: false_verdicts(q, args.records)),
        ("wander power", wander_power),
        ("long record", long_record),
    )
    if args.only:
        fns = [(n, f) for n, f in fns if n in args.only]
        suffix += "_" + "_".join(n.replace(" ", "_") for n, _ in fns)
    for name, fn in fns:
        print(f"{name} ...", file=sys.stderr, flush=True)
        parts[name] = fn(args.quick)
    head = (
        f"# bench_pitch{suffix}\n\n{machine()}; {today()}; load average (1 min) at start {load:.2f}, at end "
        f"{os.getloadavg()[0]:.2f} (other jobs share the machine); total {time.perf_counter() - t0:.0f} s\n"
    )
    text = head
    for name, rows in parts.items():
        text += f"\n## {name}\n\n" + markdown_table(rows) + "\n"
        write_csv(RESULTS / f"pitch_{name.replace(' ', '_')}{'_quick' if args.quick else ''}.csv", rows)
    write_text(RESULTS / f"pitch{suffix}.md", text)
    print(text)


if __name__ == "__main__":
    main()
