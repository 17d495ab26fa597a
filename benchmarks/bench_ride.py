"""Benchmark of the ride-quality path: ISO 2631-1 weighting filters and the ride metrics.

Run:  python benchmarks/bench_ride.py [--quick]

Writes (atomically) benchmarks/results/ride.{md,csv} (``ride_quick.*`` with --quick).

* ``frequency_weighting`` (oversampled to 4096 Hz where the record is slower, then decimated)
  against the strongest plain baseline, ``scipy.signal.sosfilt`` of the same four second-order
  sections at the record's own rate (what a bilinear-only design would cost, and be 0.1 dB wrong
  near Nyquist at low rates);
* the whole ride-quality computation (:func:`vibkit.diagnose.ride.ride_quality`: both weightings, the 10 Hz
  channel, half-cycle peak-to-peak, A95, r.m.s.) on a 10-minute, 3-axis, 2 kHz record, and the
  peak-to-peak step alone.

Best of several repeats, one process, one core; the machine's 1-minute load average is recorded
(other jobs share it).
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np
import scipy.signal

from vibkit.diagnose.ride import ride_quality
from vibkit.signal import frequency_weighting, frequency_weighting_sos, peak_to_peak
from vibkit.signal.weighting import oversampling_factor

from _common import RESULTS, best_of, machine, markdown_table, today, write_csv, write_text


def record(fs, seconds, seed=0):
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    t = np.arange(n) / fs
    base = 0.05 * rng.standard_normal((3, n)) + 0.1 * np.sin(2 * np.pi * 7.8 * t)
    base[2] += 9.80665
    return base


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1-minute records, fewer repeats; writes ride_quick.*")
    a = ap.parse_args(argv)
    minutes = 0.2 if a.quick else 10.0
    repeat = 1 if a.quick else 5
    load = os.getloadavg()[0]
    rows = []
    for fs in (200.0, 500.0, 2000.0, 5000.0):
        x = record(fs, 60.0 * minutes)[2]
        sos = frequency_weighting_sos("Wk", fs)
        frequency_weighting(x[: int(fs)], fs, "Wk")  # warm-up
        tw = best_of(lambda: frequency_weighting(x, fs, "Wk"), repeat=repeat)
        tb = best_of(lambda: scipy.signal.sosfilt(sos, x), repeat=repeat)
        rows.append(
            {
                "case": f"Wk weighting, {minutes:g} min at {fs:g} Hz (internal x{oversampling_factor(fs)})",
                "samples": x.size,
                "vibkit [ms]": 1e3 * tw,
                "sosfilt same order [ms]": 1e3 * tb,
                "ratio": tw / tb,
            }
        )
    fs = 2000.0
    x3 = record(fs, 60.0 * minutes, seed=1)
    sig = {"x": x3[0], "y": x3[1], "z": x3[2]}
    seg = (5.0, 60.0 * minutes - 5.0)
    tr = best_of(lambda: ride_quality(sig, fs, segment=seg), repeat=repeat)
    sos_k = frequency_weighting_sos("Wk", fs)
    tb = best_of(lambda: scipy.signal.sosfilt(sos_k, x3, axis=-1), repeat=repeat)
    rows.append(
        {
            "case": f"ride_quality, 3 axes, {minutes:g} min at 2 kHz (weightings, 10 Hz channel, pk-pk, A95)",
            "samples": x3.size,
            "vibkit [ms]": 1e3 * tr,
            "sosfilt same order [ms]": 1e3 * tb,
            "ratio": tr / tb,
        }
    )
    y = frequency_weighting(x3[2] - 9.80665, fs, "Wk")
    tp = best_of(lambda: peak_to_peak(y, fs), repeat=repeat)
    rows.append(
        {
            "case": f"peak_to_peak alone, one axis, {minutes:g} min at 2 kHz",
            "samples": y.size,
            "vibkit [ms]": 1e3 * tp,
            "sosfilt same order [ms]": float("nan"),
            "ratio": float("nan"),
        }
    )
    suffix = "_quick" if a.quick else ""
    head = (
        f"# Ride-quality benchmark\n\n{machine()}; {today()}; numpy {np.__version__}, scipy {scipy.__version__}; "
        f"1-minute load average {load:.2f} at the start (the machine is shared).\n"
        "Best of several repeats; 'sosfilt same order' is scipy.signal.sosfilt of the same four sections "
        "at the record's rate (for the ride_quality row: of one weighting on all three axes).\n\n"
    )
    write_text(RESULTS / f"ride{suffix}.md", head + markdown_table(rows) + "\n")
    write_csv(RESULTS / f"ride{suffix}.csv", [dict(r, load_avg_1min=load) for r in rows])
    print(markdown_table(rows))
    print(f"wrote {RESULTS / f'ride{suffix}.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
