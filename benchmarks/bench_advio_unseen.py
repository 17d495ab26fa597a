"""`vibkit rides` on phone walks it was not developed on: the ADVIO sequences the project does not hold, as a
stranger runs it (the sequence's folder, no options), against a truth made without vibkit.

Run:  python benchmarks/bench_advio_unseen.py --root DIR

Without ``--root`` the folder in the environment variable ``VIBKIT_ADVIO_ROOT`` is read; without either (``make
bench`` on a clone without the data) the script says so and writes nothing, leaving the committed table.

``DIR`` holds ADVIO sequence folders ``advio-NN/`` (``iphone/accelerometer.csv``, ``gyro.csv``, ``barometer.csv``,
``ground-truth/fixpoints.csv``): the data set from Zenodo (DOI 10.5281/zenodo.1320825), or the copy in the public
repository ethan-jiang-1/deep-speed-constrained-ins (folder ``data_ds/``).  The data's licence is CC BY-NC 4.0: keep
it out of this repository and say so beside any copy.  Writes ``benchmarks/results/advio_unseen.{md,csv}``; the
table is regenerable only where the data is.

The truth is made from the files with numpy alone, never from vibkit:

* a **ride** is a still span (the walking band, 0.5-3 Hz of ``|a|``, under 0.4 m/s^2 r.m.s. over 2 s, for 6 s or
  more) during which the barometer's relative altitude climbs or falls steadily (4 s slopes of 0.08-0.45 m/s, one
  sign, over 6 s or more: faster is a lift) and across which the fix points' floor number changes;
* its **independent link pass** is the tests' estimate (``tests/diagnose/test_rides.py``): the ride less 2 s at each
  end, each accelerometer axis Hann-windowed, zero-padded 16 times, the three periodograms summed, the peak in
  3-5 Hz; its **level** the peak of the three axes' periodograms each over its running median (+-1 Hz), averaged,
  over their median in the same band (a line stands out of about 7-8 dB of noise maxima).

A ride is *found* when one of vibkit's rides starts and ends within 3 s of it; its link pass *agrees* when within
0.5 % of the independent estimate and within 3 sigma (vibkit's sigma combined with 0.01 Hz for the estimate's own,
as the tests do).  Every vibkit ride that matches no truth ride is *invented*.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import re
import time
from pathlib import Path

import numpy as np

from vibkit.cli import main as vibkit_main

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

#: the ADVIO README's table: venue, and what it lists (stairs, escalator, elevator, vehicles)
README = {
    1: ("mall", "escalator"),
    2: ("mall", "-"),
    3: ("mall", "-"),
    4: ("mall", "escalator"),
    5: ("mall", "stairs"),
    6: ("mall", "-"),
    7: ("mall", "elevator"),
    8: ("mall", "escalator"),
    9: ("mall", "escalator"),
    10: ("mall", "-"),
    11: ("metro", "vehicles"),
    12: ("metro", "vehicles"),
    13: ("office", "stairs"),
    14: ("office", "stairs, elevator"),
    15: ("office", "-"),
    16: ("office", "stairs"),
    17: ("office", "stairs"),
    18: ("office", "stairs, elevator"),
    19: ("office", "stairs"),
    20: ("outdoor", "vehicles"),
    21: ("outdoor", "vehicles"),
    22: ("outdoor (urban)", "vehicles"),
    23: ("outdoor (urban)", "vehicles"),
}
#: the sequences the project holds in ../shared/realworld (its development data)
HELD = {1, 2, 4, 5, 7, 11, 13}
#: the mall's escalators' profile as a field engineer would guess it (133.33 mm at the rated 0.5 m/s)
PROFILE = ["--nominal-pitch", "133.33mm", "--speed", "0.5"]


def _load(path):
    return np.loadtxt(path, delimiter=",", ndmin=2)


def _runs(mask, t, min_s):
    """(start, end) [s] of the runs of ``mask`` lasting ``min_s`` or more."""
    out, i = [], 0
    while i < mask.size:
        if mask[i]:
            j = i
            while j < mask.size and mask[j]:
                j += 1
            if t[j - 1] - t[i] >= min_s:
                out.append((float(t[i]), float(t[j - 1])))
            i = j
        else:
            i += 1
    return out


def still_spans(acc):
    """Still spans: the walking band (0.5-3 Hz of |a|) under 0.4 m/s^2 r.m.s. over 2 s, for 6 s or more."""
    t = acc[:, 0]
    fs = 1 / np.median(np.diff(t))
    tu = np.arange(t[0], t[-1], 1 / fs)
    m = np.sqrt(sum(np.interp(tu, t, acc[:, k]) ** 2 for k in (1, 2, 3)))
    spec = np.fft.rfft(m - m.mean())
    f = np.fft.rfftfreq(m.size, 1 / fs)
    spec[(f < 0.5) | (f > 3)] = 0
    band = np.fft.irfft(spec, m.size)
    n = int(2 * fs)
    rms = np.sqrt(np.convolve(band**2, np.ones(n) / n, mode="same"))
    return _runs(rms < 0.4, tu, 6.0)


def climbs(baro):
    """Steady barometric climbs: 4 s slopes of the relative altitude of 0.08-0.45 m/s, one sign, over 6 s or more
    ((start, end, median vertical speed))."""
    t, z = baro[:, 0], baro[:, 2]
    tg = np.arange(t[0], t[-1], 0.5)
    zg = np.interp(tg, t, z)
    v = np.array([np.polyfit(tg[i : i + 9], zg[i : i + 9], 1)[0] for i in range(max(tg.size - 8, 0))])
    tc = tg[: v.size] + 2.0
    out = []
    for sign in (1, -1):
        for a, b in _runs((sign * v > 0.08), tc, 6.0):
            sel = (tc >= a) & (tc <= b)
            if np.max(np.abs(v[sel])) <= 0.45:
                out.append((a - 2.0, b + 2.0, float(np.median(v[sel]))))
    return out


def floor_changes(fix):
    """(last fix point's time before, first after) where the floor number (last column) changes."""
    out, prev = [], None
    for t, floor in zip(fix[:, 0], fix[:, -1]):
        if np.isnan(floor):
            continue
        if prev is not None and floor != prev[1]:
            out.append((float(prev[0]), float(t)))
        prev = (t, floor)
    return out


def truth_rides(seq_dir):
    acc = _load(seq_dir / "iphone" / "accelerometer.csv")
    baro = _load(seq_dir / "iphone" / "barometer.csv")
    fix_path = seq_dir / "ground-truth" / "fixpoints.csv"
    changes = floor_changes(np.genfromtxt(fix_path, delimiter=",", ndmin=2)) if fix_path.is_file() else []
    rides = []
    for a, b in still_spans(acc):
        for c0, c1, v in climbs(baro):
            overlap = min(b, c1) - max(a, c0)
            if overlap >= 0.5 * (b - a) and any(f0 <= b and f1 >= a for f0, f1 in changes):
                # the ride: the still span within the climb (its 4 s windows' middles: a person may stand at the
                # landing before stepping on)
                rides.append((max(a, c0 + 2.0), min(b, c1 - 2.0), "up" if v > 0 else "down", v))
                break
    return rides, acc


def independent_line(acc, t0, t1):
    """(the tests' independent link pass [Hz], the line's level [dB]) of the ride t0..t1 (see the module's notes)."""
    from scipy.ndimage import median_filter

    fs = 1 / np.median(np.diff(acc[:, 0]))
    tt = np.arange(t0 + 2, t1 - 2, 1 / fs)
    nfft = 16 * 2 ** int(np.ceil(np.log2(tt.size)))
    f = np.fft.rfftfreq(nfft, 1 / fs)
    total, norm = 0, 0
    for k in (1, 2, 3):
        x = np.interp(tt, acc[:, 0], acc[:, k])
        p = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size), nfft)) ** 2
        total = total + p
        norm = norm + p / median_filter(p, size=int(2.0 / f[1]) | 1, mode="nearest")
    sel = np.flatnonzero((f > 3) & (f < 5))
    peak = float(f[sel[np.argmax(total[sel])]])
    level = 10 * np.log10(np.max(norm[sel]) / np.median(norm[sel]))
    return peak, float(level)


def _vibkit(args):
    """(exit status, stdout, stderr) of ``vibkit ARGS`` run in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = vibkit_main(args)
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else 1
        except Exception as exc:  # a traceback is a finding: say it in the table
            rc, err = 99, io.StringIO(f"traceback: {type(exc).__name__}: {exc}")
    return rc, out.getvalue(), err.getvalue()


def _told(r):
    """A ride's link pass as the table shows it, or its two steady lines where vibkit gives none."""
    if r["link_pass_hz"] is None:
        return "not told: " + " or ".join(f"{f:.4f}" for f in r["lines_hz"])
    return f"{r['link_pass_hz']:.4f} +- {r['link_pass_sigma_hz']:.4f}"


def _agrees(f, s, truth):
    return abs(f / truth - 1) < 0.005 and abs(f - truth) < 3 * np.hypot(s, 0.01)


def check(seq_dir):
    n = int(re.sub(r"\D", "", seq_dir.name) or 0)
    venue, listed = README.get(n, ("?", "?"))
    base = {"sequence": seq_dir.name, "held": "yes" if n in HELD else "no", "venue": venue, "readme": listed}
    rc, out, err = _vibkit(["rides", str(seq_dir), "--json"])
    if rc != 0:
        return [{**base, "verdict": f"vibkit rides exit {rc}: {err.strip()[:160]}"}], 0, 0, []
    found = json.loads(out)
    truth, acc = truth_rides(seq_dir)
    rc_p, out_p, _ = _vibkit(["rides", str(seq_dir), "--json", *PROFILE]) if truth else (1, "", "")
    with_profile = json.loads(out_p)["rides"] if rc_p == 0 else []
    rows, used = [], set()
    for t0, t1, direction, vz in truth:
        f_ind, level = independent_line(acc, t0, t1)
        row = {
            **base,
            "truth ride [s]": f"{t0:.1f}-{t1:.1f} {direction} ({vz:+.2f} m/s)",
            "independent [Hz]": f"{f_ind:.4f} ({level:.1f} dB)",
            "_level": level,
        }
        overlap = [min(r["end_s"], t1) - max(r["start_s"], t0) for r in found["rides"]]
        match = [k for k, o in enumerate(overlap) if o > 0.5 * (t1 - t0)]
        rc_s, out_s, _ = _vibkit(["spectrum", str(seq_dir), "--segment", f"{t0:.1f}:{t1:.1f}", "--json"])
        spec = json.loads(out_s) if out_s.strip() else {}
        fs_, ss_ = spec.get("fundamental_hz"), spec.get("fundamental_sigma_hz")
        row["spectrum --segment [Hz]"] = (
            f"{fs_:.4f} +- {ss_:.4f} ({'agrees' if _agrees(fs_, ss_, f_ind) else 'DISAGREES'})"
            if fs_ is not None
            else f"none ({spec.get('status', f'exit {rc_s}')})"
        )
        prof = [r for r in with_profile if min(r["end_s"], t1) - max(r["start_s"], t0) > 0.5 * (t1 - t0)]
        row["with 133.33 mm, 0.5 m/s [Hz]"] = _told(prof[0]) if prof else "no ride"
        row["_profile_agrees"] = (
            bool(prof)
            and prof[0]["link_pass_hz"] is not None
            and _agrees(prof[0]["link_pass_hz"], prof[0]["link_pass_sigma_hz"], f_ind)
        )
        if match:
            r = found["rides"][match[0]]
            used.add(match[0])
            f, s = r["link_pass_hz"], r["link_pass_sigma_hz"]
            row["vibkit ride [s]"] = f"{r['start_s']:.1f}-{r['end_s']:.1f} {r['direction']}"
            row["link pass [Hz]"] = _told(r)
            off = max(abs(r["start_s"] - t0), abs(r["end_s"] - t1))
            if f is None:
                near = any(abs(x / f_ind - 1) < 0.005 for x in r["lines_hz"])
                row["verdict"] = (
                    "found, two steady lines, no link pass given; "
                    + ("one of them the independent line" if near else "NEITHER the independent line")
                    + (f"; BOUNDS OFF by {off:.1f} s" if off > 3.0 else "")
                )
            elif off > 3.0:
                row["verdict"] = (
                    f"BOUNDS OFF by {off:.1f} s; link pass {'agrees' if _agrees(f, s, f_ind) else 'disagrees'}"
                )
            elif _agrees(f, s, f_ind):
                row["verdict"] = f"found, agrees ({100 * (f / f_ind - 1):+.2f} %)"
            else:
                row["verdict"] = f"found, link pass DISAGREES ({100 * (f / f_ind - 1):+.2f} %)"
        else:
            row["vibkit ride [s]"] = row["link pass [Hz]"] = "-"
            why = [s["verdict"] for s in found["still_spans"] if min(s["end_s"], t1) > max(s["start_s"], t0)]
            why = why[0].replace(" that the false-alarm bound requires", " needed") if why else "no still span there"
            row["verdict"] = "MISSED: " + why
        rows.append(row)
    for k, r in enumerate(found["rides"]):
        if k not in used:
            rows.append(
                {
                    **base,
                    "vibkit ride [s]": f"{r['start_s']:.1f}-{r['end_s']:.1f} {r['direction']}",
                    "link pass [Hz]": _told(r),
                    "verdict": "INVENTED (no truth ride)",
                }
            )
    refused = [f"{r['start_s']:.0f}-{r['end_s']:.0f} s ({r['link_pass_hz']:.3f} Hz)" for r in found["refused"]]
    if not rows:
        rows.append({**base, "verdict": "no ride, none found"})
    if refused:
        rows[-1]["verdict"] += "; refused: " + ", ".join(refused)
    invented = sum("INVENTED" in r["verdict"] for r in rows)
    # the independent level's noise: 12 s windows of standing in a sequence without a ride, stepped by 6 s
    noise = []
    if not truth:
        for a, b in still_spans(acc):
            noise += [independent_line(acc, t, t + 12.0)[1] for t in np.arange(a, b - 12.0 + 1e-9, 6.0)]
    return rows, len(truth), invented, noise


COLUMNS = (
    "sequence",
    "held",
    "venue",
    "readme",
    "truth ride [s]",
    "vibkit ride [s]",
    "link pass [Hz]",
    "independent [Hz]",
    "spectrum --segment [Hz]",
    "with 133.33 mm, 0.5 m/s [Hz]",
    "verdict",
)


def main(root: Path) -> None:
    seqs = sorted(p for p in root.iterdir() if p.is_dir() and re.fullmatch(r"advio-\d+", p.name))
    if not seqs:
        raise SystemExit(f"{root}: no advio-NN folders; expected ADVIO's sequence folders (see the script's notes)")
    cpu0 = time.process_time()
    rows, n_truth, n_invented, noise = [], 0, 0, []
    for seq in seqs:
        r, nt, ni, nz = check(seq)
        rows += r
        n_truth += nt
        n_invented += ni
        noise += nz
    nz = np.asarray(noise) if noise else np.array([np.nan])
    for row in rows:
        if row["verdict"].startswith("MISSED") and row["_level"] <= np.max(nz):
            row["verdict"] += "; the independent spectrum shows no line either (its level within the noise)"
    with_profile = sum(bool(row.get("_profile_agrees")) for row in rows)
    rows = [{c: row.get(c, "") for c in COLUMNS} for row in rows]
    cpu = time.process_time() - cpu0
    found = sum(r["verdict"].startswith("found") for r in rows)
    overlapping = sum(r["verdict"].startswith("BOUNDS OFF") for r in rows)
    agree = sum(r["verdict"].startswith("found, agrees") for r in rows)
    text = f"""# `vibkit rides` on phone walks it was not developed on (ADVIO)

`python benchmarks/bench_advio_unseen.py --root {root.name}/`, {today()}, {machine()}; {cpu:.0f} CPU-s.
{len(seqs)} sequences ({sum(int(s.name[6:]) not in HELD for s in seqs)} not held by the project). Data: ADVIO (Cortes et al., ECCV 2018), CC BY-NC 4.0, not in this repository. vibkit run as a stranger
runs it: `vibkit rides advio-NN --json` (the sequence's folder, no options); `vibkit spectrum advio-NN --segment
START:END --json` on each truth ride; and once more with the mall's guessed profile (`{" ".join(PROFILE)}`).
The truth (barometer, walking band, fix points' floors) and the independent link pass are made with numpy alone
(the script's notes).

Truth rides {n_truth}; found {found} (start and end within 3 s; {overlapping} more with a bound further off); link pass within 0.5 % and 3 sigma of the
independent estimate {agree} (with the profile {with_profile}); invented rides {n_invented}.  The independent level's noise (12 s windows of standing
in the sequences without a ride, {len(noise)} of them): median {np.median(nz):.1f} dB, largest {np.max(nz):.1f} dB;
a truth ride whose level is within that holds no line the independent spectrum can show.

{markdown_table(rows)}
"""
    write_text(RESULTS / "advio_unseen.md", text)
    write_csv(RESULTS / "advio_unseen.csv", rows)
    print(text)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", type=Path, help="folder holding ADVIO's advio-NN/ sequence folders")
    ap.add_argument("--quick", action="store_true", help="the same run (it takes under a minute)")
    args = ap.parse_args()
    root = args.root or (Path(os.environ["VIBKIT_ADVIO_ROOT"]) if os.environ.get("VIBKIT_ADVIO_ROOT") else None)
    if root is None:
        print("skipped: no ADVIO data (give --root DIR or VIBKIT_ADVIO_ROOT); the committed table is left as it is")
    elif not root.is_dir():
        raise SystemExit(f"--root {root}: no such folder; expected one holding ADVIO's advio-NN/ sequence folders")
    else:
        main(root)
