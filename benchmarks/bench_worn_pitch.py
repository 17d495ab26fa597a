"""The chain's mean elongation from a tensioner recording of a chain with one worn link: how often a verdict is
given, and how often the stated sigma covers the true link-pass frequency, with and without the number of links.

Run:  python benchmarks/bench_worn_pitch.py [--quick]

Writes ``benchmarks/results/worn_pitch{,_quick}.{md,csv}``.

A worn link changes the tensioner's signal once a loop; without the number of links the parts check of
:func:`vibkit.diagnose.pitch.estimate_pitch` reads that as a wander of the frequency and withholds the verdict.
With it (``n_links``, ``vibkit pitch --links``) the parts are taken at the same places of every loop.  The
recordings: ``sim/thesis-forward.toml`` (no load, 0.5 m/s) with link 40 longer by the excess (exact closure), and
the healthy chain, simulated once each for five loops after one loop and 5 s of settling (bench_links's base
runs); each recording is a base run cut to 2, 3 or 5 loops from a random start within the first loop, with its
own white noise (1.5 um, the Leon tensioner recording's level) and, in a second set, a slow speed wander of
0.05 % (sinusoid, period 60-300 s: a chain under speed control); a third set has a wander of 0.3 %, more than
a chain under speed control holds, which must still get no verdict.  The truth is the sprocket's mesh frequency over
the recording (teeth passed over its span, the wander's time warp included).  The speed is given as 0.5 m/s
+- 0.05 %.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text
from bench_links import SCENE, SPEED, WORN, variant

FS = 200.0
NOISE = 1.5e-6  # the Leon tensioner recording's noise [m]
NOMINAL = 0.13333  # the scene's link pitch [m]


def base_run(scene, excess, loops=5):
    """Time, tensioner displacement and the sprocket's links passed (teeth x turns) after the settling."""
    import vibkit

    n, pitch = scene.chain.n_rollers, scene.chain.link_pitch
    settle = n * pitch / SPEED + 5.0
    duration = settle + (loops + 1.2) * n * pitch / SPEED
    sc = variant(scene, excess=excess)
    ds = vibkit.simulate(sc, duration=duration, progress=False)
    t = ds.time.values
    keep = t >= settle
    links = (
        scene.sprocket.teeth * np.abs(ds.sprocket_angle.values[keep] - ds.sprocket_angle.values[keep][0]) / (2 * np.pi)
    )
    return t[keep] - t[keep][0], ds.delta.values[keep], links


def recording(base, loops, n, wander, rng):
    """One recording cut from a base run: ``(time, displacement, true link-pass frequency)``."""
    t, x, links = base
    loop_s = n * NOMINAL / SPEED
    start = rng.uniform(0.0, loop_s)
    span = (loops + 0.05) * loop_s
    tr = np.arange(0.0, span, 1.0 / FS)
    period, ph = rng.uniform(60.0, 300.0), rng.uniform(0.0, 2 * np.pi)
    # the chain's own time runs at 1 + w(t): the signal at time tr is the base run at tau(tr)
    tau = start + tr + wander * period / (2 * np.pi) * (np.sin(2 * np.pi * tr / period + ph) - np.sin(ph))
    y = np.interp(tau, t, x) + rng.normal(0.0, NOISE, tr.size)
    passed = np.interp(tau[-1], t, links) - np.interp(tau[0], t, links)
    return tr, y, passed / (tr[-1] - tr[0])


def estimate(tr, y, n_links):
    import xarray as xr

    from vibkit.diagnose.pitch import estimate_pitch

    rec = xr.Dataset({"delta": ("time", y, {"units": "m"})}, coords={"time": tr})
    return estimate_pitch(rec, speed=SPEED, speed_sigma=5e-4 * SPEED, nominal_pitch=NOMINAL, n_links=n_links)


def rows_for(label, base, n, loops_list, wander, trials, rng):
    rows = []
    for loops in loops_list:
        counts = {None: [0, 0, 0, 0], n: [0, 0, 0, 0]}  # verdict, inconclusive, within 2 sigma, within 3 sigma
        sig = {None: [], n: []}
        for _ in range(trials):
            tr, y, f_true = recording(base, loops, n, wander, rng)
            for links in (None, n):
                e = estimate(tr, y, links)
                c = counts[links]
                c[0] += e.status == "ok"
                c[1] += e.status == "inconclusive"
                z = abs(e.fundamental_hz - f_true) / e.fundamental_sigma_hz
                c[2] += z <= 2
                c[3] += z <= 3
                sig[links].append(e.fundamental_sigma_hz / e.fundamental_hz)
        for links in (None, n):
            c = counts[links]
            rows.append(
                {
                    "chain": label,
                    "wander [%]": 100 * wander,
                    "loops": loops,
                    "links given": "yes" if links else "no",
                    "recordings": trials,
                    "verdict": c[0] / trials,
                    "inconclusive": c[1] / trials,
                    "truth within 2 sigma": c[2] / trials,
                    "within 3 sigma": c[3] / trials,
                    "median sigma [%]": f"{100 * np.median(sig[links]):.2g}",
                }
            )
            print(rows[-1], flush=True)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="two chains, 3 loops, few recordings")
    a = p.parse_args()
    from vibkit.model.scene import load_scene

    scene = load_scene(SCENE)
    n = scene.chain.n_rollers
    rng = np.random.default_rng(14)
    t0 = time.process_time()
    chains = {"healthy": None, "0.3 mm": 0.3e-3, "1 mm": 1e-3, "3 mm": 3e-3}
    if a.quick:
        chains = {"healthy": None, "1 mm": 1e-3}
    loops_list = [3] if a.quick else [2, 3, 5]
    trials = 4 if a.quick else 20
    c0 = time.process_time()
    bases = {label: base_run(scene, ex) for label, ex in chains.items()}
    sim_cpu = time.process_time() - c0
    rows = []
    for wander in (0.0, 5e-4):
        for label, base in bases.items():
            rows += rows_for(label, base, n, loops_list, wander, trials, rng)
    # a wander of 0.3 %, more than a chain under speed control holds: still no verdict with the links given
    for label in ("healthy", "1 mm"):
        rows += rows_for(label, bases[label], n, [3], 3e-3, trials, rng)
    suffix = "_quick" if a.quick else ""
    write_csv(RESULTS / f"worn_pitch{suffix}.csv", rows)
    text = (
        f"# bench_worn_pitch{suffix}\n\n{machine()}; {today()}; CPU {time.process_time() - t0:.0f} s "
        f"(simulations {sim_cpu:.0f} s)\n\n"
        f"Tensioner displacement of `{SCENE}` ({SPEED} m/s, {n} links), healthy or link {WORN} longer by the "
        f"excess; white noise {1e6 * NOISE:g} um; speed wander 0, 0.05 % or 0.3 % (sinusoid, period 60-300 s; "
        f"0.3 %: more than a chain under speed control, no verdict expected); each "
        f"recording cut from a random place of the loop; speed given as {SPEED} m/s +- 0.05 %; "
        f"`estimate_pitch` (`vibkit pitch`) without and with the number of links.\n\n"
        + markdown_table(rows)
        + "\n\n*verdict*: status ok (an elongation verdict given); *inconclusive*: no verdict (here: the frequency "
        "wanders between parts of the record); *truth within k sigma*: |f - f_true| <= k x the stated sigma of "
        "the link-pass frequency, f_true the sprocket's mesh frequency over the recording (a Gaussian sigma "
        "covers 0.954 and 0.997); *median sigma*: the stated sigma relative to the frequency.\n"
    )
    write_text(RESULTS / f"worn_pitch{suffix}.md", text)
    print(text)


if __name__ == "__main__":
    main()
