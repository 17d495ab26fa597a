"""`vibkit rides` and `vibkit spectrum` on real phone exports from apps and phones vibkit was not developed on, run as
a stranger runs them (the export as it comes, no options), and on the ADVIO rides written in those apps' layouts.

Run:  python benchmarks/bench_phone_exports.py --root DIR [--advio DIR]

``DIR`` holds copies of the public exports listed in :data:`EXPORTS` (each from a public GitHub repository, at the
commit named; most state no licence, so they stay out of this repository), under the relative names given there.
Without ``--root`` (or ``VIBKIT_PHONE_EXPORTS_ROOT``) the script says so and writes nothing, leaving the committed
table.  ``--advio`` names the folder of the ADVIO sequences (default: ``../shared/realworld`` beside the clone where
it exists; CC BY-NC 4.0, never in this repository): its ride walks (advio-01 up, advio-04 down) and two rides-free
walks (advio-02 walking, advio-07 a lift) are written in each app's layout (:data:`LAYOUTS`) and run the same way.
Writes ``benchmarks/results/phone_exports.{md,csv}`` and ``phone_exports_layouts.csv``.

No escalator ride is among the public exports found (a search of public repositories for phone recordings of
escalators found none with data); the rides are ADVIO's, in the other apps' layouts: Sensor Logger's accelerometer
has gravity removed and writes gravity beside it, phyphox writes one sensor per export in the phone's language.
The gravity removed from ADVIO's accelerometer is its 2 s running mean (what the phone's gravity estimate follows).

A ride is *found* when one of vibkit's rides starts and ends within 3 s of one listed in the data's ``SOURCES.md``;
its link pass *agrees* when within 0.5 % and 3 sigma of the independent estimate of ``bench_advio_unseen.py`` (numpy
alone, on the accelerometer as ADVIO wrote it).  Every other ride is *invented*.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
from scipy import ndimage

import vibkit

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text
from bench_advio_unseen import _agrees, _vibkit, independent_line

#: (relative path under --root, app and layout, phone, what was recorded, source repository @ commit: path, licence)
EXPORTS = (
    (
        "sensorlogger_pdr/inhand-20-steps-Cxh",
        "Sensor Logger 1.31 (iOS), folder, Accelerometer.csv gravity removed, Gravity.csv, Barometer.csv",
        "iPhone 12",
        "20 steps, phone in the hand",
        "AZyfen/PDR @34a2a1f: data/walking/inhand-20-steps-Cxh/",
        "none stated",
    ),
    (
        "sensorlogger_pdr/texting-30-steps-Zyf",
        "Sensor Logger 1.27 (Android), folder, gravity removed, Gravity.csv",
        "Xiaomi 22041211AC",
        "30 steps, texting",
        "AZyfen/PDR @34a2a1f: data/walking/texting-30-steps-Zyf/",
        "none stated",
    ),
    (
        "sensorlogger_pdr/inhand-28-steps-Ido",
        "Sensor Logger (iOS, 2021: 'time,z,y,x'), folder, gravity removed, Gravity.csv, Barometer.csv",
        "iPhone",
        "28 steps, phone in the hand",
        "AZyfen/PDR @34a2a1f: data/walking/inhand-28-steps-Ido/",
        "none stated",
    ),
    (
        "sensorlogger_pdr/inpocket-27-steps-Matan",
        "Sensor Logger (Android, 2021: 'time,z,y,x'), folder, gravity removed, Gravity.csv, Barometer.csv",
        "Samsung SM-N960F",
        "27 steps, phone in a trouser pocket",
        "AZyfen/PDR @34a2a1f: data/walking/inpocket-27-steps-Matan/",
        "none stated",
    ),
    (
        "sensorlogger_pdr/z-calibration-M",
        "Sensor Logger (Android, 2021: 'time,z,y,x'), folder, gravity removed, Gravity.csv, Barometer.csv",
        "Samsung SM-N960F",
        "74 s lying still (a calibration)",
        "AZyfen/PDR @34a2a1f: data/calibration/z-calibration-M/",
        "none stated",
    ),
    (
        "phyphox_adtngrha",
        "phyphox, folder of Accelerometer.csv (with g), Gyroscope.csv (deg/s), Linear Acceleration.csv",
        "not stated",
        "60 s, moving (not stated)",
        "adtngrha/Dataset-Phypox- @fa60c4b: Accelerometer.csv, Gyroscope.csv, Linear Acceleration.csv",
        "none stated",
    ),
    (
        "phyphox_adtngrha_xls.xls",
        "phyphox, Excel export (.xls)",
        "not stated",
        "the same experiment",
        "adtngrha/Dataset-Phypox- @fa60c4b: My Experiment adit 2023-04-16 18-40-30.xls",
        "none stated",
    ),
    (
        "phyphox_elevador/Acceleration without g 2023-05-29 16-53-06.zip",
        "phyphox 1.1.11, zip of 'Acceleration without g' (Raw Data.csv, meta/)",
        "iPhone XS (iPhone11,2)",
        "22 s in a lift",
        "KN1GHTR1DER/Elevador @2b337a4: Acceleration without g 2023-05-29 16-53-06.zip",
        "none stated",
    ),
    (
        "phyphox_elev45/Raw Data.csv",
        "phyphox, 'Acceleration with g' Raw Data.csv, 414 Hz",
        "not stated (Android rate)",
        "35 s in a lift",
        "SuaTia32145241/G_elev_predio_45 @000d688: Raw Data.csv",
        "none stated",
    ),
    (
        "sciencejournal_elevator/skyscrapper_up.csv",
        "Google Science Journal (relative_time ms, a row per sensor update)",
        "Android",
        "38 s in a skyscraper's lift, phone on its floor",
        "PabRod/elevator-tool @e5b24c6: data/skyscrapper_up.csv",
        "Apache-2.0",
    ),
    (
        "androsensor_mobility/Sensor_record.csv",
        "AndroSensor (33 columns, 'Time since start in ms', 2 Hz)",
        "Android",
        "31 min outdoors (walking, cycling)",
        "MMaricevic64/analiza_mobilnosti @ee2262b: Sensor_record.csv",
        "none stated",
    ),
)

#: ADVIO's rides (SOURCES.md): sequence -> [(start, end)] [s, the file's own time]
RIDES = {
    "advio-01": [(25, 44), (84, 101), (141, 158), (199, 214)],
    "advio-04": [(13, 28), (36, 52), (62, 78), (89, 110)],
}
SEQUENCES = ("advio-01", "advio-04", "advio-02", "advio-07")


def _gravity(t, acc):
    fs = 1 / np.median(np.diff(t))
    return ndimage.uniform_filter1d(acc, int(round(2.0 * fs)), axis=0, mode="nearest")


def _rows(cols, fmt="%.9f", sep=",", dec="."):
    lines = []
    for row in zip(*cols):
        cells = [c if isinstance(c, str) else (fmt % c) for c in row]
        lines.append(sep.join(x.replace(".", dec) if dec != "." else x for x in cells))
    return "\n".join(lines) + "\n"


def _ns(t):
    return [str(1_700_000_000_000_000_000 + int(round(v * 1e9))) for v in t]


def _sensor_logger(out, seq_dir, elapsed):
    """Sensor Logger's folder: Accelerometer.csv with gravity removed, Gravity.csv, Gyroscope.csv, Barometer.csv, in
    its layout of 2024 ('time,seconds_elapsed,z,y,x', iOS) or of 2021 ('time,z,y,x', Android)."""
    a, g, p = (
        np.loadtxt(seq_dir / "iphone" / f"{n}.csv", delimiter=",") for n in ("accelerometer", "gyro", "barometer")
    )
    grav = _gravity(a[:, 0], a[:, 1:4])
    out.mkdir(parents=True)

    def put(name, t, xyz):
        head = "time,seconds_elapsed,z,y,x" if elapsed else "time,z,y,x"
        cols = [_ns(t)] + ([t] if elapsed else []) + [xyz[:, 2], xyz[:, 1], xyz[:, 0]]
        (out / name).write_text(head + "\n" + _rows(cols))

    put("Accelerometer.csv", a[:, 0], a[:, 1:4] - grav)
    put("Gravity.csv", a[:, 0], grav)
    put("Gyroscope.csv", g[:, 0], g[:, 1:4])
    head = "time,seconds_elapsed,relativeAltitude,pressure" if elapsed else "time,relativeAltitude,pressure"
    cols = [_ns(p[:, 0])] + ([p[:, 0]] if elapsed else []) + [p[:, 2], 10 * p[:, 1]]
    (out / "Barometer.csv").write_text(head + "\n" + _rows(cols))
    platform = "ios" if elapsed else "android"
    (out / "Metadata.csv").write_text(
        f"version,device name,recording time,platform\n2,phone,2024-01-01_10-00-00,{platform}\n"
    )
    return out


def _phyphox(out, seq_dir, linear):
    """phyphox's zip of one sensor: 'Beschleunigung mit g' in German (Rohdaten.csv, semicolons, decimal comma), or
    'Linear Acceleration' in English (gravity removed)."""
    a = np.loadtxt(seq_dir / "iphone" / "accelerometer.csv", delimiter=",")
    xyz = a[:, 1:4] - (_gravity(a[:, 0], a[:, 1:4]) if linear else 0.0)
    cols = [a[:, 0], xyz[:, 0], xyz[:, 1], xyz[:, 2], np.linalg.norm(xyz, axis=1)]
    if linear:
        name, sep, dec = "Raw Data.csv", ",", "."
        head = ["Time (s)"] + [f"Linear Acceleration {c} (m/s^2)" for c in "xyz"] + ["Absolute acceleration (m/s^2)"]
    else:
        name, sep, dec = "Rohdaten.csv", ";", ","
        head = ["Zeit (s)"] + [f"Beschleunigung {c} (m/s^2)" for c in "xyz"] + ["Absolute Beschleunigung (m/s^2)"]
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w") as zf:
        zf.writestr(name, sep.join(f'"{h}"' for h in head) + "\n" + _rows(cols, "%.9E", sep, dec))
        zf.writestr("meta/device.csv", f'"property"{sep}"value"\n"deviceModel"{sep}"iPhone"\n')
    return out


#: name -> (what, writer(out, seq_dir) -> the path to give vibkit)
LAYOUTS = {
    "ADVIO as it comes": ("iphone/ folder (accelerometer with g, gyro, barometer)", None),
    "Sensor Logger (iOS)": (
        "folder, 'time,seconds_elapsed,z,y,x', Accelerometer.csv gravity removed + Gravity.csv",
        lambda out, d: _sensor_logger(out / "sl-ios", d, True),
    ),
    "Sensor Logger (Android, 2021)": (
        "folder, 'time,z,y,x', gravity removed + Gravity.csv",
        lambda out, d: _sensor_logger(out / "sl-android", d, False),
    ),
    "phyphox, German": (
        "zip: Rohdaten.csv, 'Zeit (s)';'Beschleunigung x (m/s^2)', decimal comma; accelerometer only",
        lambda out, d: _phyphox(out / "Beschleunigung mit g.zip", d, False),
    ),
    "phyphox, Linear Acceleration": (
        "zip: Raw Data.csv, gravity removed; accelerometer only",
        lambda out, d: _phyphox(out / "Linear Acceleration.zip", d, True),
    ),
}


def _read_notes(path):
    """(channels, rate, duration, the reader's notes that a stranger needs) of the export, or the refusal."""
    try:
        ds = vibkit.read_recording(path)
    except Exception as exc:  # RecordingError: the one-line refusal is the finding
        return None, f"refused: {str(exc).split(': ', 1)[-1][:200]}"
    hist = str(ds.attrs.get("history", ""))
    keys = ("gravity removed", "added back", "no units", "Sensor Logger export", "joined onto", "repeats", "sparse")
    notes = [h.split(": ", 1)[-1][:110] for h in hist.splitlines() if any(k in h for k in keys)]
    chans = [v for v in ds.data_vars if v != "segment"]
    dur = float(ds["time"].values[-1] - ds["time"].values[0])
    return ds, f"{len(chans)} channels ({', '.join(chans[:7])}{' ...' if len(chans) > 7 else ''}), " + (
        f"{float(ds.attrs.get('sample_rate_hz', 0)):.4g} Hz, {dur:.0f} s"
        + ("; " + "; ".join(notes[:3]) if notes else "")
    )


def _rides_verdict(path):
    """What ``vibkit rides PATH --json`` says: its rides and still spans' verdicts, or its refusal."""
    rc, out, err = _vibkit(["rides", str(path), "--json"])
    if rc != 0:
        return f"exit {rc}: " + (err.strip().splitlines()[-1].split("error: ", 1)[-1][:200] if err.strip() else "")
    found = json.loads(out)
    spans = found["still_spans"]
    text = f"{len(found['rides'])} ride(s) in {len(spans)} still span(s) of >= 6 s"
    for s in spans[:2]:
        text += f"; {s['start_s']:.0f}-{s['end_s']:.0f} s: {s['verdict'][:150]}"
    return text


def _spectrum_verdict(path):
    """What ``vibkit spectrum PATH --json`` says: the link pass, or why none."""
    rc, out, err = _vibkit(["spectrum", str(path), "--json"])
    if rc != 0 and not out.strip():
        return f"exit {rc}: " + (err.strip().splitlines()[-1].split("error: ", 1)[-1][:160] if err.strip() else "")
    data = json.loads(out)
    if data.get("fundamental_hz"):
        return f"link pass {data['fundamental_hz']:.4f} Hz"
    return f"{data.get('status', '?')}: {str(data.get('reason', ''))[:120]}"


def _verdict(read, rides, spectrum):
    """None of the real exports holds an escalator: right is no ride and no link pass, or a one-line refusal."""
    if read.startswith("refused"):
        return "refused in one line"
    if read.startswith("not under"):
        return "-"
    wrong = []
    if rides.startswith("exit"):
        wrong.append("rides fails")
    elif not rides.startswith("0 ride"):
        wrong.append("a ride invented")
    if spectrum.startswith("exit"):
        wrong.append("spectrum fails")
    elif spectrum.startswith("link pass"):
        wrong.append("spectrum gives a link pass")
    return "WRONG: " + ", ".join(wrong) if wrong else "right: no ride, no link pass"


def real_exports(root):
    rows = []
    for rel, app, phone, what, source, licence in EXPORTS:
        path = root / rel
        if not path.exists():
            read, rides, spectrum = "not under --root", "-", "-"
        else:
            _, read = _read_notes(path)
            refused = read.startswith("refused")
            rides = "-" if refused else _rides_verdict(path)
            spectrum = "-" if refused else _spectrum_verdict(path)
        rows.append(
            {
                "export": rel,
                "verdict": _verdict(read, rides, spectrum),
                "app and layout": app,
                "phone": phone,
                "recorded": what,
                "read": read,
                "vibkit rides": rides,
                "vibkit spectrum": spectrum,
                "source": source,
                "licence": licence,
            }
        )
    return rows


def _tally_real(rows):
    n = {v: sum(r["verdict"].startswith(v) for r in rows) for v in ("right", "refused", "WRONG")}
    return f"Right {n['right']}, refused in one line {n['refused']}, wrong {n['WRONG']} (the verdict column says how)."


def advio_layouts(advio):
    rows, tally, off = [], {}, []
    with tempfile.TemporaryDirectory() as tmp:
        for seq in SEQUENCES:
            seq_dir = advio / seq
            if not seq_dir.is_dir():
                continue
            acc = np.loadtxt(seq_dir / "iphone" / "accelerometer.csv", delimiter=",")
            truth = RIDES.get(seq, [])
            indep = [independent_line(acc, a, b)[0] for a, b in truth]
            for name, (what, writer) in LAYOUTS.items():
                path = (
                    seq_dir / "iphone" if writer is None else writer(Path(tmp) / seq / name.replace(" ", "_"), seq_dir)
                )
                rc, out, err = _vibkit(["rides", str(path), "--json"])
                rides = json.loads(out)["rides"] if rc == 0 else []
                found, agree, used = 0, 0, set()
                for (a, b), f_ind in zip(truth, indep):
                    for i, r in enumerate(rides):
                        if i not in used and abs(r["start_s"] - a) <= 3 and abs(r["end_s"] - b) <= 3:
                            used.add(i)
                            found += 1
                            f, sf = r["link_pass_hz"], r["link_pass_sigma_hz"]
                            if f is not None and _agrees(f, sf, f_ind):
                                agree += 1
                            else:
                                off.append(
                                    f"{seq} {a}-{b} s, {name}: "
                                    + (f"{f:.4f} +- {sf:.4f} Hz" if f is not None else "no link pass")
                                    + f" against {f_ind:.4f} Hz"
                                    + (f" ({100 * (f / f_ind - 1):+.2f} %)" if f is not None else "")
                                )
                            break
                invented = len(rides) - len(used)
                t = tally.setdefault(name, [0, 0, 0, 0])
                t[0] += len(truth)
                t[1] += found
                t[2] += agree
                t[3] += invented
                rows.append(
                    {
                        "sequence": seq,
                        "layout": name,
                        "written as": what,
                        "truth rides": len(truth),
                        "found": found,
                        "link pass agrees": agree,
                        "invented": invented,
                        "vibkit's rides [s]": (", ".join(f"{r['start_s']:.0f}-{r['end_s']:.0f}" for r in rides) or "-")
                        if rc == 0
                        else f"exit {rc}: {err.strip()[-160:]}",
                    }
                )
    return rows, tally, off


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", type=Path, help="folder holding the public exports under EXPORTS' relative names")
    ap.add_argument("--advio", type=Path, help="folder of ADVIO's advio-NN/ sequences (default ../shared/realworld)")
    ap.add_argument("--quick", action="store_true", help="the same run")
    args = ap.parse_args(argv)
    env = os.environ.get("VIBKIT_PHONE_EXPORTS_ROOT")
    root = args.root or (Path(env) if env else None)
    if root is None or not root.is_dir():
        print("bench_phone_exports: no --root (the public exports are not in this repository): table left as it is")
        return 0
    advio = args.advio or Path(__file__).resolve().parents[1].parent / "shared" / "realworld"
    t0 = time.process_time()
    real = real_exports(root)
    layout_rows, tally, off = advio_layouts(advio) if advio.is_dir() else ([], {}, [])
    cpu = time.process_time() - t0
    summary = [
        f"{name}: {t[1]} of {t[0]} rides found, {t[2]} link passes agree, {t[3]} invented" for name, t in tally.items()
    ]
    text = "\n".join(
        [
            "# Phone exports from other apps and phones, as a stranger runs vibkit on them",
            "",
            f"`python benchmarks/bench_phone_exports.py --root exports/ --advio realworld/`, {today()}, {machine()}; "
            f"{cpu:.0f} CPU-s. The script's notes say what is run and how a ride is judged.",
            "",
            "## Real exports (public repositories; none holds an escalator ride)",
            "",
            "Each read as it comes (`vibkit rides EXPORT --json`, `vibkit spectrum EXPORT --json`, no options). None",
            "of them holds an escalator: the right answer is no ride and no link pass, or a one-line refusal that says",
            "what to do. " + _tally_real(real),
            "",
            markdown_table(real),
            "",
            "## ADVIO's rides written in the other apps' layouts",
            "",
            "advio-01 (4 rides up) and advio-04 (4 down), advio-02 (walking) and advio-07 (a lift): "
            + ("; ".join(summary) if summary else "not run (no --advio folder)")
            + ".",
            "",
            markdown_table(layout_rows) if layout_rows else "",
            "",
            "Found rides whose link pass is off the independent estimate by more than 0.5 % or 3 sigma: "
            + ("; ".join(off) if off else "none")
            + ".",
            "",
        ]
    )
    write_text(RESULTS / "phone_exports.md", text)
    write_csv(RESULTS / "phone_exports.csv", real)
    if layout_rows:
        write_csv(RESULTS / "phone_exports_layouts.csv", layout_rows)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
