"""The steady-line detector's null: its stated false-alarm bound against a Monte Carlo of Gaussian noise, and the
thresholds it requires, with the floor's error integrated exactly (the law of a running median's order statistic)
and, as before, as a Gaussian.

Run:  python benchmarks/bench_steadyline_null.py [--quick]

Writes ``benchmarks/results/steadyline_null{,_quick}.{md,csv}``.  Seeded: the same numbers on every run.

* **Thresholds**: the level [dB over the floor] at which :func:`vibkit.signal.steadyline.steady_line` declares a
  line at ``p_fa = 1e-3`` over 2.9-9 Hz (the rides' default band) at 100 Hz, for the strongest single channel of six
  and for the channels' mean (six independent channels; two sensors of three strongly coherent axes each).  "old":
  the floor's relative error integrated as a Gaussian of sd ``1 / (ln 2 sqrt(2 T))``; "new": its exact law
  (:func:`~vibkit.signal.steadyline._tail_floored`).
* **One channel's band maximum**: white Gaussian noise, the normalised periodogram's maximum over 2-45 Hz (many
  independent frequencies, to reach the tail): how often it exceeds 12, 13, 14 dB, against the bound the detector
  states for it (``GRID_FACTOR M`` times the per-frequency tail) and the old one.  Where the bound is under the
  measured rate by more than its binomial error the bound is not one.
* **The channels' mean's band maximum**: the same for the mean of six channels (independent; two coherent
  sensors), where the old bound (the floors' error averaged over the channels' full effective number, no grid
  factor) is under the measured rate at 6.5-7 dB on independent channels.
* **The detector's own p-value** on six-channel Gaussian noise (independent; two coherent sensors): the fraction of
  records with ``p <= alpha`` must stay under ``alpha``.
* **The channels' mean's tail at the detector's own level** (``--deep``, written to ``steadyline_null_deep.{md,csv}``:
  about 150 CPU-s): the rate at which one independent frequency (an unpadded bin of 2-45 Hz) of the six channels'
  mean exceeds the threshold that ``p_fa = 1e-3`` over 2.9-9 Hz asks of an 11 s record, where the stated per-frequency
  tail is a few in a million, against that stated tail; with no union bound and no grid factor in it, this is where
  the floors' law of the mean alone is exact or not.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from vibkit.signal import steadyline as sl

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

FS = 100.0
BAND = (2.9, 9.0)
P_FA = 1e-3
SEED = 20261207


def _old_tail(s, eig, floor_sd):
    """The previous rule: the floor's relative error ``d ~ N(0, floor_sd**2)`` integrated by Gauss-Hermite."""
    x, w = np.polynomial.hermite_e.hermegauss(24)
    d = np.clip(floor_sd * x, -0.9, None)
    lam, wt = sl._mixture(eig)
    ss = s * (1.0 + d)
    p = np.exp(-ss[:, None] / lam[None, :]) @ wt
    p = np.clip(np.maximum(p, np.exp(-ss / lam[0])), 0.0, 1.0)
    return float(p @ (w / w.sum()))


def _old_sd(duration, eig):
    eig = np.asarray(eig, dtype=float)
    c_eff = float(np.sum(eig) ** 2 / np.sum(eig**2))
    return 1.0 / (math.log(2.0) * math.sqrt(max(2.0 * duration, 4.0)) * math.sqrt(max(c_eff, 1.0)))


def _bisect(tail, p):
    lo, hi = 0.0, 10.0
    while tail(hi) > p:
        hi *= 2
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if tail(mid) > p else (lo, mid)
    return hi


def _db(v):
    return round(10.0 * math.log10(v), 2)


#: two sensors of three axes each, the axes of one coherent at 0.6: the coherence matrix's eigenvalues
_SENSORS = np.linalg.eigvalsh(np.kron(np.eye(2), np.full((3, 3), 0.6)) + 0.4 * np.eye(6))


def thresholds(durations):
    rows = []
    for dur in durations:
        n = int(round(dur * FS))
        half = sl._floor_half(n, FS, 4, 1.0)
        m_old = (BAND[1] - BAND[0]) * dur
        m_new = sl.GRID_FACTOR * m_old
        row = {"analysed_s": dur}
        # the strongest single channel of six: at most 6 M tail per search, half of p_fa (Bonferroni)
        one = [1.0]
        row["one_of_6_old_db"] = _db(_bisect(lambda s: _old_tail(s, one, _old_sd(dur, one)), P_FA / (2 * 6 * m_old)))
        h1 = sl._floor_law(half, one)
        row["one_of_6_new_db"] = _db(_bisect(lambda s: sl._tail_floored(s, one, h1), P_FA / (2 * 6 * m_new)))
        for name, eig in (("mean_indep", np.ones(6)), ("mean_2_sensors", _SENSORS)):
            sd = _old_sd(dur, eig)
            row[f"{name}_old_db"] = _db(_bisect(lambda s: _old_tail(s, eig, sd), P_FA / (2 * m_old)) / 6)
            h = sl._floor_law(half, eig)
            row[f"{name}_new_db"] = _db(_bisect(lambda s: sl._tail_floored(s, eig, h), P_FA / (2 * m_new)) / 6)
        rows.append(row)
    return rows


def band_maximum(rng, durations, records, levels_db=(12, 13, 14), lo=2.0, hi=45.0):
    rows = []
    for dur in durations:
        n = int(round(dur * FS))
        maxima = []
        for _ in range(records // 500):
            _, _, _, r = sl._spectra(rng.standard_normal((500, n)), FS, 4, 1.0)
            f = np.fft.rfftfreq(2 * (r.shape[1] - 1), 1.0 / FS)
            maxima.append(r[:, (f >= lo) & (f <= hi)].max(axis=1))
        mx = np.concatenate(maxima)
        half = sl._floor_half(n, FS, 4, 1.0)
        m = (hi - lo) * dur
        for d in levels_db:
            s = 10.0 ** (d / 10.0)
            k = int(np.sum(mx > s))
            rate = k / mx.size
            rows.append(
                {
                    "record_s": dur,
                    "level_db": d,
                    "records": mx.size,
                    "measured": rate,
                    "binomial_err": math.sqrt(max(rate * (1 - rate), 1.0 / mx.size) / mx.size),
                    "bound_new": min(1.0, sl.GRID_FACTOR * m * sl._tail_floored(s, [1.0], sl._floor_law(half, [1.0]))),
                    "bound_old": min(1.0, m * _old_tail(s, [1.0], _old_sd(dur, [1.0]))),
                }
            )
    return rows


def mean_maximum(rng, durations, records, lo=2.0, hi=45.0):
    """The channels' mean over 2-45 Hz (six independent channels; two coherent sensors): how often its maximum
    exceeds a level, against the bound stated for it and the old one."""
    rows = []
    mix = np.linalg.cholesky(np.kron(np.eye(2), np.full((3, 3), 0.6)) + 0.4 * np.eye(6))
    for dur in durations:
        n = int(round(dur * FS))
        half = sl._floor_half(n, FS, 4, 1.0)
        m = (hi - lo) * dur
        for name, a, eig, levels in (
            ("6 independent", np.eye(6), np.ones(6), (6.0, 6.5, 7.0)),
            ("2 coherent sensors", mix, _SENSORS, (7.5, 8.0, 8.5)),
        ):
            maxima = []
            for _ in range(records // 500):
                x = np.einsum("ij,bjn->bin", a, rng.standard_normal((500, 6, n))).reshape(3000, n)
                f, _, _, r = sl._spectra(x, FS, 4, 1.0)
                t = r.reshape(500, 6, -1).mean(axis=1)
                maxima.append(t[:, (f >= lo) & (f <= hi)].max(axis=1))
            mx = np.concatenate(maxima)
            h = sl._floor_law(half, eig)
            for d in levels:
                s = 10.0 ** (d / 10.0)
                rate = float(np.mean(mx > s))
                rows.append(
                    {
                        "record_s": dur,
                        "channels": name,
                        "level_db": d,
                        "records": mx.size,
                        "measured": rate,
                        "binomial_err": math.sqrt(max(rate * (1 - rate), 1.0 / mx.size) / mx.size),
                        "bound_new": min(1.0, sl.GRID_FACTOR * m * sl._tail_floored(6 * s, eig, h)),
                        "bound_old": min(1.0, m * _old_tail(6 * s, eig, _old_sd(dur, eig))),
                    }
                )
    return rows


def detector_p(rng, durations, records):
    rows = []
    mix = np.linalg.cholesky(np.kron(np.eye(2), np.full((3, 3), 0.6)) + 0.4 * np.eye(6))
    for dur in durations:
        n = int(round(dur * FS))
        for name, a in (("6 independent", np.eye(6)), ("2 coherent sensors", mix)):
            p = np.array(
                [
                    sl.steady_line(a @ rng.standard_normal((6, n)), FS, band=BAND, parts=1).p_value
                    for _ in range(records)
                ]
            )
            row = {"record_s": dur, "channels": name, "records": records}
            for al in (1e-1, 1e-2, 1e-3):
                row[f"frac_p_le_{al:g}"] = float(np.mean(p <= al))
            row["binomial_err_1e-2"] = math.sqrt(1e-2 * (1 - 1e-2) / records)
            rows.append(row)
    return rows


def mean_tail_deep(rng, records, dur=11.0, lo=2.0, hi=45.0):
    """The six channels' mean at single unpadded bins: how often it exceeds the threshold the detector asks at
    ``p_fa`` over :data:`BAND` (and 0.5 dB under it), against the per-frequency tail :func:`sl._tail_floored` states."""
    rows = []
    n = int(round(dur * FS))
    half = sl._floor_half(n, FS, 4, 1.0)
    m = sl.GRID_FACTOR * (BAND[1] - BAND[0]) * dur
    mix = np.linalg.cholesky(np.kron(np.eye(2), np.full((3, 3), 0.6)) + 0.4 * np.eye(6))
    for name, a, eig in (("6 independent", np.eye(6), np.ones(6)), ("2 coherent sensors", mix, _SENSORS)):
        h = sl._floor_law(half, eig)
        level = sl._level_for(P_FA / (2.0 * m), eig, h)
        sums = [level * 10.0 ** (-0.05), level]
        count, bins = np.zeros(2), 0
        for _ in range(records // 200):
            x = np.einsum("ij,bjn->bin", a, rng.standard_normal((200, 6, n))).reshape(1200, n)
            f, _, _, r = sl._spectra(x, FS, 4, 1.0)
            step = max((2 * (r.shape[1] - 1)) // n, 1)
            t = r.reshape(200, 6, -1).sum(axis=1)[:, ::step]
            fc = f[::step]
            t = t[:, (fc >= lo) & (fc <= hi)]
            bins += t.size
            count += [np.sum(t > v) for v in sums]
        for v, k in zip(sums, count):
            rows.append(
                {
                    "record_s": dur,
                    "channels": name,
                    "level_db": _db(v / 6),
                    "bins": bins,
                    "exceeded": int(k),
                    "measured": k / bins,
                    "stated": sl._tail_floored(v, eig, h),
                }
            )
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer records (a smoke run)")
    ap.add_argument("--deep", action="store_true", help="only the channels' mean's tail at the detector's own level")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(SEED)
    if args.deep:
        c0 = time.process_time()
        rows = mean_tail_deep(rng, 2000 if args.quick else 20000)
        cpu = time.process_time() - c0
        tag = "_quick" if args.quick else ""
        write_csv(RESULTS / f"steadyline_null_deep{tag}.csv", rows)
        text = (
            "# The steady-line detector's null: the channels' mean at its own level\n\n"
            f"`python benchmarks/bench_steadyline_null.py --deep{' --quick' if args.quick else ''}`; {machine()}; "
            f"{today()}; {cpu:.0f} CPU-s; seed {SEED}.  Fs {FS:g} Hz; an 11 s record; the threshold is the one "
            f"`p_fa = {P_FA:g}` over {BAND[0]:g}-{BAND[1]:g} Hz asks of the mean (and 0.5 dB under it).  One row a "
            "level: how often a single independent frequency (an unpadded bin of 2-45 Hz) of the six channels' mean "
            "exceeds it in Gaussian noise, against the per-frequency tail the detector states (no union bound, no "
            "grid factor).  A count of k events has a Poisson error of about sqrt(k).\n\n" + markdown_table(rows) + "\n"
        )
        write_text(RESULTS / f"steadyline_null_deep{tag}.md", text)
        print(text)
        return
    c0 = time.process_time()
    thr = thresholds((8, 10, 12, 15, 20, 30, 60))
    bm = band_maximum(rng, (8, 11, 15, 20, 30), 2000 if args.quick else 10000)
    mm = mean_maximum(rng, (11, 20), 1000 if args.quick else 5000)
    dp = detector_p(rng, (11, 20), 100 if args.quick else 300)
    cpu = time.process_time() - c0
    tag = "_quick" if args.quick else ""
    write_csv(RESULTS / f"steadyline_null{tag}.csv", [dict(table="thresholds", **r) for r in thr])
    text = (
        "# The steady-line detector's null\n\n"
        f"`python benchmarks/bench_steadyline_null.py{' --quick' if args.quick else ''}`; {machine()}; {today()}; "
        f"{cpu:.0f} CPU-s; seed {SEED}.  Fs {FS:g} Hz, band {BAND[0]:g}-{BAND[1]:g} Hz, p_fa {P_FA:g}.\n\n"
        "## Thresholds [dB over the floor], old (the floor's error as a Gaussian) and new (its exact law)\n\n"
        + markdown_table(thr)
        + "\n\n## One channel's band maximum (2-45 Hz) on white Gaussian noise: measured rate against the bounds\n\n"
        + markdown_table(bm)
        + "\n\n## The channels' mean's band maximum (2-45 Hz) on Gaussian noise: measured rate against the bounds\n\n"
        + markdown_table(mm)
        + "\n\n## The detector's p-value on six-channel Gaussian noise: the fraction of records with p <= alpha\n\n"
        + markdown_table(dp)
        + "\n"
    )
    write_text(RESULTS / f"steadyline_null{tag}.md", text)
    print(text)


if __name__ == "__main__":
    main()
