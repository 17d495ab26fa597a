"""``vibkit spectrum``: link-pass fundamental and harmonic peak table of a recording."""

from __future__ import annotations

from .options import add_command, add_json, add_recording, band, read_recording
from .output import in_file, msg, print_json, table
from .pitch import not_found

EPILOG = "example:\n  vibkit spectrum data/field/leon-tensioner.csv --band 2.5:6 --json"


def add_parser(subparsers):
    s = add_command(subparsers, "spectrum", "link-pass fundamental and harmonic peak table of a recording", EPILOG)
    add_recording(s)
    add_json(s)
    s.add_argument("--band", type=band, help="search band of the link-pass LOW:HIGH [Hz] (default 2.5:6)")
    s.add_argument("--harmonics", type=int, default=5, help="harmonics listed (default 5)")
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.diagnose.pitch import estimate_pitch, pick_channel

    rec = read_recording(a)
    ch = pick_channel(rec, a.channel)
    search = a.band or (2.5, 6.0)
    try:
        est = estimate_pitch(rec, speed=1.0, channel=ch, band=search, n_harmonics=a.harmonics)
    except ValueError as exc:  # the analysis's words about the signal, with the file named
        raise in_file(a.recording, exc) from None
    units = str(rec[ch].attrs.get("units", "1"))
    if not est.detected:
        return not_found("spectrum", a, est, {"file": a.recording, "channel": ch, "units": units,
                                              "band_hz": list(search)})
    peaks = [{"order": h["order"], "frequency_hz": h["frequency_hz"], "amplitude": h["amplitude"],
              "units": units, "detected": h["detected"]} for h in est.harmonics]
    payload = {"status": est.status, "file": a.recording, "channel": ch, "units": units, "band_hz": list(search),
               "method": est.method, "method_reason": est.method_reason, "detection": est.detection,
               "invalid_samples": est.invalid_samples,
               "fundamental_hz": est.fundamental_hz, "fundamental_sigma_hz": est.fundamental_sigma_hz,
               "snr_db": est.snr_db, "peaks": peaks, "warnings": est.warnings}
    if a.json:
        print_json("spectrum", payload)
    else:
        print(f"{a.recording}: channel {ch} [{units}]")
        print(f"link-pass fundamental {est.fundamental_hz:.5f} +- {est.fundamental_sigma_hz:.2g} Hz "
              f"(search band {search[0]:g}-{search[1]:g} Hz)")
        print(table([[p["order"], f"{p['frequency_hz']:.4f}", f"{p['amplitude']:.4g}", "yes" if p["detected"] else "no"]
                     for p in peaks], ("order", "frequency [Hz]", f"amplitude [{units}]", "detected")))
        for w in est.warnings:
            msg(f"warning: {w}")
    return 0
