"""Which flat rollers the knock test of ``vibkit ride`` finds, on the simulator.

``sim/thesis-forward.toml`` (no load, 0.5 m/s, 35 mm rollers), the accelerometer on step 20 (its middle
roller 59), 44 s simulated at 200 Hz: the step rides up the incline from about 31 s. Roller 59 round, or
worn flat over a chord of 1, 2, 3 or 5 mm (``roller_flat_by_roller``). On each simulated ride, white noise
of 5 or 20 mm/s^2 r.m.s. is added to the step's vertical acceleration (the noise of a logging
accelerometer and of a phone), and :func:`vibkit.diagnose.knock.ride_knock` tests it (the ride's ISO-weighted
vertical axis, the middle 70 % of the ride, false-alarm probability 1e-3), as the command does.

- detection: how often the test finds the knock, over 40 noise draws per flat and noise level, and
  how far the frequency it reads is from the roller's turn, v / (2 pi r);
- false alarms: the round roller, 500 noise draws per level (the stated probability is 1e-3;
  the table gives the binomial 95 % upper bound of what was seen).

Writes ``knock.md`` (``--quick``: 5 and 50 draws instead of 40 and 500, ``knock_quick.md``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time

import numpy as np
import scipy.stats

from _common import RESULTS, machine, markdown_table, today, write_text

SCENE = "sim/thesis-forward.toml"
FLATS_MM = (0.0, 1.0, 2.0, 3.0, 5.0)
NOISES = (0.005, 0.02)  # [m/s^2]
SPEED, RADIUS = 0.5, 0.035


def _ride(flat_mm):
    import vibkit
    from vibkit.diagnose.ride import ride_quality_from_simulation
    from vibkit.diagnose.ride_simulation import with_ride_outputs
    from vibkit.model.scene import load_scene, parse_scene

    text = load_scene(SCENE).text
    if flat_mm:
        text = text.replace("n_rollers = 159", f"n_rollers = 159\nroller_flat_by_roller = [[59, {flat_mm / 1e3}]]")
    ds = vibkit.simulate(with_ride_outputs(parse_scene(text, SCENE)), progress=False)
    return ride_quality_from_simulation(ds)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    from vibkit.diagnose.knock import ride_knock, step_rollers_of
    from vibkit.model.scene import load_scene

    draws, false_draws = (5, 50) if args.quick else (40, 500)
    rollers = step_rollers_of(scene=load_scene(SCENE))
    rng = np.random.default_rng(20261127)
    c0 = time.process_time()
    rows, seconds = [], []
    for flat in FLATS_MM:
        rq = _ride(flat)
        z = rq.weighted["z"]
        for noise in NOISES:
            n = false_draws if flat == 0 else draws
            found, errors = 0, []
            for _ in range(n):
                # noise on the raw axis: weighted with the same filter as the signal
                from vibkit.signal import frequency_weighting

                w = frequency_weighting(noise * rng.standard_normal(z.size), rq.fs, "Wk")
                t0 = time.process_time()
                res, _ = ride_knock(dataclasses.replace(rq, weighted={**rq.weighted, "z": z + w}), rollers)
                seconds.append(time.process_time() - t0)
                if res.detected:
                    found += 1
                    errors.append(res.frequency_hz / (SPEED / (2 * math.pi * RADIUS)) - 1)
            upper = scipy.stats.beta.ppf(0.975, found + 1, n - found) if found < n else 1.0
            rows.append(
                {
                    "flat_mm": flat,
                    "noise_m_s2": noise,
                    "draws": n,
                    "found": found,
                    "share": found / n,
                    "upper_95": upper if flat == 0 else float("nan"),
                    "frequency_error_max": max(map(abs, errors)) if errors else float("nan"),
                }
            )
            print(rows[-1], flush=True)
    cpu = time.process_time() - c0
    name = "knock_quick.md" if args.quick else "knock.md"
    md = (
        f"# bench_knock\n\n{machine()}; {today()}; CPU {cpu:.0f} s; one knock test {np.median(seconds):.2f} s "
        f"(median CPU)\n\n`{SCENE}` (0.5 m/s, 35 mm rollers), the accelerometer on step 20 (roller 59), 44 s at "
        f"200 Hz, the ride from about 31 s; roller 59 round (flat 0) or worn flat over the chord given; white "
        f"noise added to the vertical axis; the test of `vibkit ride` (false-alarm probability 1e-3). *share*: "
        f"the draws in which a knock was found (for the round roller: false alarms; *upper_95* their binomial "
        f"95 % upper bound); *frequency_error_max*: the largest relative distance of the knock's frequency "
        f"from the roller's turn v / (2 pi r).\n\n" + markdown_table(rows) + "\n"
    )
    write_text(RESULTS / name, md)
    print(md)


if __name__ == "__main__":
    main()
