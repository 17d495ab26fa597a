"""A phone on an escalator: how often `vibkit rides` finds a ride's link pass, how often it invents one, and
whether its stated sigma holds, on real phone noise with a line of known truth.

Run:  python benchmarks/bench_phone_rides.py [--quick] [--advio-root DIR]

Writes ``benchmarks/results/phone_rides{,_quick}.{md,csv,png}`` and ``phone_rides_real{,_quick}.csv`` (the real
rides' table).  With ``--advio-root DIR`` (or ``VIBKIT_ADVIO_ROOT``), the rides of the ADVIO sequences the project
does not hold (advio-08, advio-09: ``bench_advio_unseen.py``'s truth) join that table, measured only, never used to
draw the synthetic lines; without it the table holds the development rides alone.

The records are made of real phone data (the ADVIO walks in ``../shared/realworld``, CC BY-NC 4.0, read in
place): 10 s of walking (advio-02, a mall) before and after a still span cut from the rides-free sequences'
standing parts (an elevator ride in advio-07, standing in the mall in advio-01 and advio-05, in a metro station in
advio-11), into which a link-pass line is added on the accelerometer's and gyroscope's six axes.  The line's level is that of the real rides' independent check (SOURCES.md): its peak in an 8 s Welch
spectrum of the strongest axis over that axis' median of 1.5-10 Hz; each other axis carries the line at its weight's
share of that level over its *own* floor (``support.phone.add_line``: the accelerometer's and the gyroscope's floors
are 10-23 dB apart in their units).  The shares are those of a real ride: each record takes, at random, the pattern of
one of the eight development rides (SOURCES.md), measured on the same scale at the ride's link pass over the part
vibkit analysed (``support.phone.shares``: each axis' excess over its own floor over the strongest axis').  Earlier
tables drew the shares from a Dirichlet(0.7) law over the six axes, which put a line on one or two axes far more
often than a real ride does (the real rides carry it on three to five axes within 6 dB of the strongest: their
shares sum to 2.3-3.6, the Dirichlet draws' median 2.3 and a tenth under 1.6): the mean over the axes, which the
detector tests, got 1 dB less of the line than a real ride's at the same level, and a tenth of the records several
dB less.  The real rides' own levels, lengths and p-values are given in a table of their own.  The level over the floor at the line (+-1 Hz) is reported beside it.  The line is not a tone: its frequency
(3.3-4.5 Hz) wanders by a random walk of 0.3 % r.m.s. and steps by 1-2 % where passengers board (0-2 per
ride).  The truth for the sigma's coverage is the line's mean frequency over the span vibkit analysed.

The beds' slow acceleration (under 0.5 Hz: advio-07's lift car starting and stopping) is taken out, gravity kept,
so that a bed stands for a phone held still: ``vibkit rides`` refuses, without a barometer, a still span holding a
car's start or stop, and these records carry no barometer.

A ride's link pass is *found* when exactly one ride overlaps the still span and its frequency is within 1 % of
the truth (these records carry no barometer: the table measures the line's detection alone).  False rides: every
ride on the rides-free sequences (whole files, real, with their barometer) and on the same walk-stand-walk records
without a line, each record tested twice: without a barometer, and with the real barometer of its walk and its
still span (the relative altitude, joined where they meet), where a line that a lift's climb comes with is refused.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import signal

import vibkit
from vibkit.diagnose.rides import find_rides
from vibkit.signal.steadyline import normalised_spectrum, steady_line

from _common import RESULTS, machine, markdown_table, support, today, write_csv, write_text

REAL = Path(__file__).resolve().parents[1] / ".." / "shared" / "realworld"
#: still spans of the rides-free sequences (no line: vibkit's own verdict and SOURCES.md) [s]
BEDS = [("advio-07", 13.0, 87.0), ("advio-01", 1.0, 17.0), ("advio-05", 1.0, 14.0), ("advio-11", 186.5, 196.5)]
CONTROLS = ("advio-02", "advio-05", "advio-07", "advio-11", "advio-13")
NAMES = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")
#: the six vibration channels and the barometer's relative altitude [m]
READ = NAMES + ("altitude",)
LEVELS_DB = (4, 8, 12, 16, 20)
LENGTHS_S = (8, 15, 20, 30, 60)
#: the development rides (SOURCES.md; the sequence's own time) [s]
RIDES = {
    "advio-01": ((25, 44), (84, 101), (141, 158), (199, 214)),
    "advio-04": ((13, 28), (36, 52), (62, 78), (89, 110)),
}
#: the ride sequences the project does not hold (their truth: ``bench_advio_unseen.truth_rides``), with --advio-root
UNSEEN = ("advio-08", "advio-09")


def _uniform(ds, fs):
    t = ds["time"].values
    tu = np.arange(t[0], t[-1], 1 / fs)
    return tu, np.stack([np.interp(tu, t, ds[n].values) for n in READ])


def _without_car(bed, fs):
    """A still bed without a lift car's motion: the accelerometer's axes less their own slow part (under 0.5 Hz) about
    its median, gravity kept.  advio-07's bed stands in a moving lift, and ``vibkit rides`` refuses a record without a
    barometer whose still span holds a car's start or stop (0.78 m/s^2 there); the bed stands for a phone held still,
    so what it keeps is its noise over 0.5 Hz, where the walking band and the line are."""
    sos = signal.butter(2, 0.5, fs=fs, output="sos")
    out = bed.copy()
    acc = out[:3]
    out[:3] = acc - (signal.sosfiltfilt(sos, acc, axis=1) - np.median(acc, axis=1, keepdims=True))
    return out


def _real_rides(seq_dir, truth):
    """The rides ``truth`` ((start, end) [s]) of a real sequence on the benchmark's scale: one dict a ride with the
    still span's length, the part analysed, the link pass, every axis' level (:func:`support.phone.welch_level`) and
    the strongest axis' level over the floor at the line, the detector's level and p-value, and whether vibkit found
    the ride.  A ride vibkit did not find is measured over its still span less a second at each end, at the strongest
    frequency of the detector's statistic in the band, with the detector's first test (``parts=1``) as
    :func:`find_rides` runs it."""
    ds = vibkit.read_recording(seq_dir / "iphone")
    fs = float(ds.attrs["sample_rate_hz"])
    tu, x = _uniform(ds, fs)
    res = find_rides(ds)
    out = []
    for a, b in truth:
        hits = [r for r in res.rides if min(r.end_s, b) - max(r.start_s, a) > 0]
        if hits:
            r = hits[0]
            s0, s1, p, det = r.line_start_s, r.line_end_s, r.p_value, r.level_db
            length = r.end_s - r.start_s
            if r.link_pass_hz is not None:
                f, verdict = r.link_pass_hz, "found"
            else:  # two steady lines: the one nearest the other rides' link passes
                f = min(r.lines_hz, key=lambda v: abs(v - 3.85))
                verdict = "found, two lines, none told"
        else:
            t0, t1, why = max(res.still_spans, key=lambda v: min(v[1], b) - max(v[0], a))
            length, s0, s1 = t1 - t0, t0 + 1.0, t1 - 1.0
            sel = (tu >= s0) & (tu <= s1)
            seg = x[:6, sel] - x[:6, sel].mean(axis=1, keepdims=True)
            line = steady_line(seg, fs, band=res.band_hz, parts=1)
            fr, tstat = normalised_spectrum(seg, fs)
            band = (fr >= res.band_hz[0]) & (fr <= res.band_hz[1])
            f, p, det = float(fr[band][np.argmax(tstat[band])]), line.p_value, line.level_db
            verdict = "missed: " + why.removeprefix("no ride: ").split(": ", 1)[-1]
        sel = (tu >= s0) & (tu <= s1)
        levels = [support.phone.welch_level(x[c, sel], fs, f) for c in range(6)]
        k = int(np.argmax(levels))
        out.append(
            {
                "sequence": seq_dir.name,
                "ride": f"{a:.0f}-{b:.0f}",
                "still_s": length,
                "analysed_s": s1 - s0,
                "link_pass_hz": f,
                "level_db": levels[k],
                **{f"{nm}_db": lv for nm, lv in zip(NAMES, levels)},
                "local_level_db": support.phone.welch_level(x[k, sel], fs, f, local_hz=1.0),
                "detector_db": det,
                "p_value": p,
                "shares_sum": float(np.sum(support.phone.shares(levels))),
                "verdict": verdict,
            }
        )
    return out


def _record(rng, walk, bed, fs, length, level_db, barometer=False, patterns=None):
    """(Dataset, bed start [s], bed end [s], instantaneous frequency of the line or None, the line's level over the
    floor at the line on its strongest axis [dB] or None); ``barometer``: with the walk's and the bed's relative
    altitude, joined where they meet."""
    w = int(10 * fs)
    n = int(length * fs)
    i = rng.integers(0, walk.shape[1] - 2 * w)
    j = rng.integers(0, bed.shape[1] - n + 1)
    still = bed[:, j : j + n].copy()
    freq = local_db = None
    if level_db is not None:
        f0 = rng.uniform(3.3, 4.5)
        wander = np.cumsum(rng.normal(0, 1, n))
        wander = 0.003 * wander / max(np.std(wander), 1e-12)
        steps = np.zeros(n)
        for _ in range(rng.integers(0, 3)):
            steps[rng.integers(n // 4, n) :] += rng.choice([-1, 1]) * rng.uniform(0.01, 0.02)
        freq = f0 * (1 + wander - wander.mean() + steps)
        phase = 2 * np.pi * np.cumsum(freq) / fs + rng.uniform(0, 2 * np.pi)
        weights = patterns[rng.integers(len(patterns))]
        k = int(np.argmax(weights))
        local_db = level_db + support.phone.floor_at_line_db(still[k], fs, f0)
        still[:6] = support.phone.add_line(still[:6], fs, phase, weights, level_db, rng)
    before, after = walk[:, i : i + w].copy(), walk[:, i + w : i + 2 * w].copy()
    still[6] += before[6, -1] - still[6, 0]  # the altitude joined where the parts meet
    after[6] += still[6, -1] - after[6, 0]
    x = np.concatenate([before, still, after], axis=1)
    t = np.arange(x.shape[1]) / fs
    ds = xr.Dataset(
        {
            nm: (
                "time",
                x[c],
                {"units": "m/s^2" if c < 3 else "rad/s", "quantity": "acceleration" if c < 3 else "other"},
            )
            for c, nm in enumerate(NAMES)
        },
        coords={"time": t},
        attrs={"sample_rate_hz": fs, "source_file": "synthetic"},
    )
    if barometer:
        ds["altitude"] = ("time", x[6], {"units": "m", "native_rate_hz": 1.0})
    return ds, 10.0, 10.0 + length, freq, local_db


def _upper95(k, hours):
    """The 95 % upper bound of a Poisson rate [per hour] from ``k`` events in ``hours`` (chi-square, one-sided)."""
    from scipy import stats

    return float(stats.chi2.ppf(0.95, 2 * (k + 1)) / 2 / hours)


def _binom(k, n):
    p = k / n if n else float("nan")
    return p, math.sqrt(p * (1 - p) / n) if n else float("nan")


def main(quick=False, advio_root=None):
    reps = 4 if quick else 12
    cpu0 = time.process_time()
    real = [r for seq, truth in RIDES.items() for r in _real_rides(REAL / seq, truth)]
    held = len(real)
    patterns = [support.phone.shares([r[f"{nm}_db"] for nm in NAMES]) for r in real]
    if advio_root is not None:
        from bench_advio_unseen import truth_rides

        for seq in UNSEEN:
            truth = [(a, b) for a, b, *_ in truth_rides(Path(advio_root) / seq)[0]]
            real += _real_rides(Path(advio_root) / seq, truth)
    rng = np.random.default_rng(2026)
    # the shares' sum (the line's weight in the axes' mean, in units of the strongest axis') of the former draw
    dirichlet = rng.dirichlet(np.ones(6) * 0.7, 4000)
    dirichlet_sum = np.percentile(np.sum(dirichlet / dirichlet.max(axis=1, keepdims=True), axis=1), [10, 50, 90])
    walk_ds = vibkit.read_recording(REAL / "advio-02" / "iphone")
    fs = float(walk_ds.attrs["sample_rate_hz"])
    _, walk = _uniform(walk_ds, fs)
    beds = []
    for seq, a, b in BEDS:
        tu, x = _uniform(vibkit.read_recording(REAL / seq / "iphone"), fs)
        beds.append(_without_car(x[:, (tu >= a) & (tu < b)], fs))
    rows = []
    zs = []
    lengths = LENGTHS_S[:2] if quick else LENGTHS_S
    for length in lengths:
        usable = [b for b in beds if b.shape[1] >= length * fs]
        for level in LEVELS_DB:
            found, local = 0, []
            for r in range(reps):
                ds, t0, t1, freq, local_db = _record(
                    rng, walk, usable[r % len(usable)], fs, length, level, patterns=patterns
                )
                local.append(local_db)
                res = find_rides(ds)
                hits = [x for x in res.rides if x.end_s > t0 and x.start_s < t1]
                if len(hits) == 1:
                    h = hits[0]
                    a = int((h.line_start_s - t0) * fs)
                    b = int((h.line_end_s - t0) * fs)
                    truth = float(np.mean(freq[max(a, 0) : max(min(b, freq.size), a + 1)]))
                    if h.link_pass_hz is not None and abs(h.link_pass_hz / truth - 1) < 0.01:
                        found += 1
                        zs.append((h.link_pass_hz - truth) / h.link_pass_sigma_hz)
            p, s = _binom(found, reps)
            rows.append(
                {
                    "ride_s": length,
                    "level_db": level,
                    "local_level_db": float(np.median(local)),
                    "local_level_min_db": float(np.min(local)),
                    "local_level_max_db": float(np.max(local)),
                    "n": reps,
                    "found": found,
                    "p_found": p,
                    "sigma": s,
                }
            )
    # false rides: the rides-free sequences whole (real), and walk-stand-walk records without a line
    real_false, real_refused, real_hours = 0, 0, 0.0
    for seq in CONTROLS:
        ds = vibkit.read_recording(REAL / seq / "iphone")
        res = find_rides(ds)
        real_false += len(res.rides)
        real_refused += len(res.refused)
        real_hours += float(ds["time"][-1] - ds["time"][0]) / 3600
    syn_false, syn_baro, syn_refused, syn_hours, invented, refused = 0, 0, 0, 0.0, [], []
    for length in lengths:
        usable = [i for i, b in enumerate(beds) if b.shape[1] >= length * fs]
        for r in range(reps * 2):
            bed = usable[r % len(usable)]
            ds, *_ = _record(rng, walk, beds[bed], fs, length, None, barometer=True)
            found = find_rides(ds.drop_vars("altitude")).rides
            with_baro = find_rides(ds)
            syn_false += len(found)
            syn_baro += len(with_baro.rides)
            syn_refused += len(with_baro.refused)
            syn_hours += (length + 20) / 3600
            invented += [
                f"{x.link_pass_hz if x.link_pass_hz is not None else x.lines_hz[0]:.3f} Hz, {x.level_db:.1f} dB, p {x.p_value:.1g} ({length} s record on {BEDS[bed][0]})"
                for x in found
            ]
            refused += [
                f"{x['link_pass_hz']:.3f} Hz, the barometer's climb {x['vertical_speed_max_m_s']:.2f} m/s ({length} s "
                f"record on {BEDS[bed][0]})"
                for x in with_baro.refused
            ]
    cpu = time.process_time() - cpu0
    z = np.abs(np.asarray(zs))
    cov2, cov2_s = _binom(int(np.sum(z < 2)), z.size)
    cov3, _ = _binom(int(np.sum(z < 3)), z.size)
    suffix = "_quick" if quick else ""
    write_csv(RESULTS / f"phone_rides{suffix}.csv", rows)
    table = markdown_table(
        [
            {
                "ride [s]": length,
                **{
                    f"{lv} dB": f"{r['p_found']:.2f} +- {r['sigma']:.2f}"
                    for lv, r in zip(LEVELS_DB, [r for r in rows if r["ride_s"] == length])
                },
            }
            for length in lengths
        ]
    )
    local_table = markdown_table(
        [
            {
                "ride [s]": length,
                **{
                    f"{lv} dB": f"{r['local_level_db']:.1f} ({r['local_level_min_db']:.1f} to {r['local_level_max_db']:.1f})"
                    for lv, r in zip(LEVELS_DB, [r for r in rows if r["ride_s"] == length])
                },
            }
            for length in lengths
        ]
    )
    real_table = markdown_table(
        [
            {
                "ride [s]": f"{r['sequence']} {r['ride']}" + ("" if i < held else " (not held)"),
                "still span [s]": f"{r['still_s']:.1f}",
                "analysed [s]": f"{r['analysed_s']:.1f}",
                "line [Hz]": f"{r['link_pass_hz']:.4f}",
                "level [dB]": f"{r['level_db']:.1f}",
                "acc x, y, z; gyro x, y, z [dB]": ", ".join(f"{r[nm + '_db']:.1f}" for nm in NAMES),
                "shares' sum": f"{r['shares_sum']:.2f}",
                "at the line [dB]": f"{r['local_level_db']:.1f}",
                "detector [dB]": f"{r['detector_db']:.1f}",
                "p": f"{r['p_value']:.1g}",
                "vibkit": r["verdict"],
            }
            for i, r in enumerate(real)
        ]
    )
    write_csv(RESULTS / f"phone_rides_real{suffix}.csv", real)
    dev = real[:held]
    shares_held = f"{min(r['shares_sum'] for r in dev):.2f}-{max(r['shares_sum'] for r in dev):.2f}"
    dirichlet_note = " / ".join(f"{v:.2f}" for v in dirichlet_sum)
    levels_held = f"{min(r['level_db'] for r in dev):.1f}-{max(r['level_db'] for r in dev):.1f}"
    still_held = f"{min(r['still_s'] for r in dev):.0f}-{max(r['still_s'] for r in dev):.0f}"
    unseen_note = (
        " and, with `--advio-root`, of the ADVIO sequences the project does not hold (their truth:\n"
        "`bench_advio_unseen.py`; regenerable only where that data is)"
        if advio_root is not None
        else ""
    )
    text = f"""# A phone on an escalator: rides found, rides invented, sigma coverage

`python benchmarks/bench_phone_rides.py{" --quick" if quick else ""}`, {today()}, {machine()}; {cpu:.0f} CPU-s.
Real phone noise (ADVIO walks and standing parts, CC BY-NC 4.0) with a line of known truth added; see the
script's docstring.  {reps} records a cell; +- is the binomial standard error.

## Probability that the ride's link pass is found (within 1 % of the truth, one ride)

Level: the line's peak in an 8 s Welch spectrum of its strongest axis over that axis' median of 1.5-10 Hz (the
development rides: {levels_held} dB, below); the other axes carry it at a real ride's shares of that level over their
own floors.  Default band 2.9-9 Hz (no profile), false-alarm bound 0.001 per still span.

{table}

The same records' level over the floor *at the line* (the strongest axis' 8 s Welch median within +-1 Hz of the
line, what the detector's running median sees): the median of the cell (its least to its largest).  A phone's
handling noise rises toward 3-5 Hz, so a line stands less over the floor at it than over the 1.5-10 Hz median.

{local_table}

## The real rides on the same scale

Each ride of the development sequences{unseen_note}: the still span vibkit found, the part it analysed, its link pass,
the strongest axis' level as above (8 s Welch over the analysed part, over the axis' median of 1.5-10 Hz), every
axis' level on that scale, the shares' sum (each axis' excess over the strongest's, summed: the line's weight in the
axes' mean), the strongest axis' level over the floor at the line (+-1 Hz), and the detector's level (the axes' mean
at the record's full resolution) and p-value.  A ride vibkit missed is measured over its still span less a second
at each end, at the detector's strongest frequency, with the test that refused it.

{real_table}

The synthetic records above take their shares from the eight development rides' patterns (their sums
{shares_held}); the Dirichlet(0.7) draw of earlier tables gives sums of {dirichlet_note} (10th / 50th / 90th
percentile).  SOURCES.md's "8-24 dB" spans every axis of every ride; on this table's scale (the strongest axis) the
development rides stand at {levels_held} dB, over still spans of {still_held} s.

## Rides invented

| records | hours | rides found | rate [per hour] | lines refused (a lift's climb) |
|---|---|---|---|---|
| the five rides-free ADVIO sequences, whole (walking, stairs, an elevator, a metro station, an office), with their barometer | {real_hours:.3f} | {real_false} | {real_false / real_hours:.1f} (95 % upper bound {_upper95(real_false, real_hours):.0f}) | {real_refused} |
| walk, still span without a line, walk ({reps * 2} per length), no barometer | {syn_hours:.3f} | {syn_false} | {syn_false / syn_hours:.1f} (95 % upper bound {_upper95(syn_false, syn_hours):.0f}) | - |
| the same records with their real barometer | {syn_hours:.3f} | {syn_baro} | {syn_baro / syn_hours:.1f} (95 % upper bound {_upper95(syn_baro, syn_hours):.0f}) | {syn_refused} |

Rides found where no line was added, without a barometer: {"; ".join(invented) or "none"}.
Lines refused with the barometer: {"; ".join(refused) or "none"}.

The still beds are few (four standing parts, 11-74 s): the synthetic rows reuse them at random offsets, so they
are not independent draws of the world's standing; the real rows are all the rides-free data there is here.

## Coverage of the stated sigma

Of the {z.size} link passes found: {cov2:.2f} +- {cov2_s:.2f} within 2 sigma of the truth (target >= 0.9),
{cov3:.2f} within 3 sigma.
"""
    write_text(RESULTS / f"phone_rides{suffix}.md", text)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        for length in lengths:
            rr = [r for r in rows if r["ride_s"] == length]
            ax.errorbar(
                [r["level_db"] for r in rr],
                [r["p_found"] for r in rr],
                yerr=[r["sigma"] for r in rr],
                marker="o",
                capsize=3,
                label=f"{length} s ride",
            )
        ax.scatter(
            [r["level_db"] for r in real],
            [1.0 if r["verdict"].startswith("found") else 0.0 for r in real],
            marker="x",
            color="k",
            zorder=3,
            label="real rides (found 1, missed 0)",
        )
        ax.set_xlabel("line level over the floor [dB] (8 s Welch, strongest axis)")
        ax.set_ylabel("P(link pass found)")
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
        ax.legend()
        ax.set_title("vibkit rides on real phone noise with a known line")
        fig.tight_layout()
        path = RESULTS / f"phone_rides{suffix}.png"
        tmp = path.with_suffix(".tmp.png")
        fig.savefig(tmp, dpi=110)
        tmp.replace(path)
    except ImportError:
        pass
    print(text)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer records (a smoke run)")
    ap.add_argument(
        "--advio-root",
        type=Path,
        default=os.environ.get("VIBKIT_ADVIO_ROOT") or None,
        help="folder of the ADVIO sequences the project does not hold (advio-08, advio-09): their rides join the real "
        "rides' table (CC BY-NC 4.0: keep the data out of this repository); default: $VIBKIT_ADVIO_ROOT, else none",
    )
    args = ap.parse_args()
    main(args.quick, args.advio_root)
