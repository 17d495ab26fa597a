"""``vibkit pitch``: link pitch (and elongation) from a recording's link-pass frequency and the chain speed."""

from __future__ import annotations

import math
import textwrap

from .options import (add_command, add_json, add_limits, add_recording, band, positive, read_recording,
                      speed_sigma, speed_uncertainty, teeth)
from .output import msg, print_json, table

EPILOG = ("examples:\n  vibkit pitch data/field/leon-tensioner.csv --speed 0.49 --speed-uncertainty 0.1% \\\n"
          "      --nominal-pitch 0.13333\n  vibkit pitch logger.txt --sample-rate 2050 --speed 0.52 --json")


def add_parser(subparsers):
    s = add_command(subparsers, "pitch", "link pitch from a recording's link-pass frequency and the chain speed",
                    EPILOG)
    add_recording(s)
    add_json(s)
    s.add_argument("--speed", type=positive, required=True, help="chain speed measured on the steps [m/s]")
    s.add_argument("--speed-uncertainty", type=speed_uncertainty,
                   help="speed standard deviation, in m/s or in %% (e.g. 0.1%%)")
    s.add_argument("--nominal-pitch", type=positive, help="nominal link pitch [m]: gives elongation and verdict")
    add_limits(s)
    s.add_argument("--band", type=band, help="search band LOW:HIGH [Hz] (default speed / 80-200 mm)")
    s.add_argument("--teeth", type=teeth, default=28, help="sprocket teeth, for the shaft hypothesis (default 28)")
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.diagnose.pitch import estimate_pitch

    rec = read_recording(a)
    sigma = speed_sigma(a.speed_uncertainty, a.speed) if a.speed_uncertainty else 0.0
    est = estimate_pitch(rec, speed=a.speed, speed_sigma=sigma, channel=a.channel, band=a.band,
                         nominal_pitch=a.nominal_pitch, limits_percent=a.limits, teeth=a.teeth)
    if not est.detected:
        return not_found("pitch", a, est, {"file": a.recording})
    if a.json:
        d = est.as_dict()
        d["file"] = a.recording
        print_json("pitch", d)
        return 0
    print(f"{a.recording}: channel {est.channel}, speed {est.speed_m_s:g} +- {est.speed_sigma_m_s:.2g} m/s")
    print(f"link-pass frequency  {est.fundamental_hz:.5f} +- {est.fundamental_sigma_hz:.2g} Hz "
          f"({len(est.per_burst)} burst(s))")
    print(f"method               {est.method}")
    print(f"link pitch           {1000 * est.pitch_m:.3f} +- {1000 * est.pitch_sigma_m:.3f} mm")
    if est.nominal_pitch_m is not None:
        print(f"elongation           {est.elongation_percent:+.2f} +- {est.elongation_sigma_percent:.2f} % "
              f"of {1000 * est.nominal_pitch_m:.2f} mm -> {est.verdict}\n"
              f"                     (limits {' / '.join(f'{v:g}' for v in est.limits_percent)} %)")
    print()
    print(table([[h.name, f"{h.frequency_hz:.4f}", "n/a" if math.isnan(h.snr_db) else f"{h.snr_db:.0f}",
                  f"{1000 * h.implied_pitch_m:.2f}", f"{1000 * h.nearest_catalogue_m:.2f} ({h.deviation_percent:+.1f} %)",
                  "<-" if h.chosen else ""] for h in est.hypotheses],
                ("hypothesis", "link pass [Hz]", "SNR [dB]", "pitch [mm]", "catalogue [mm]", "")))
    for h in est.hypotheses:  # the reasons under the table: it stays within 100 columns
        print(textwrap.fill(f"{h.name}: {h.reason}", 100, subsequent_indent="    "))
    print()
    print(table([[h["order"], f"{h['frequency_hz']:.4f}", f"{h['amplitude']:.4g}", "yes" if h["detected"] else "no"]
                 for h in est.harmonics], ("order", "frequency [Hz]", f"amplitude [{est.extra['units']}]", "detected")))
    for w in est.warnings:
        msg(textwrap.fill(f"warning: {w}", 100, subsequent_indent="  "))
    for n in est.notes + [f"method {est.method}: {est.method_reason}"]:
        msg(textwrap.fill(f"note: {n}", 100, subsequent_indent="  "))
    return 0


def not_found(cmd, a, est, extra):
    """No link-pass family in the band: say so (JSON with the status, no number), exit 1."""
    if a.json:
        d = est.as_dict()
        d.update(extra)
        print_json(cmd, d)
    else:
        print(f"{a.recording}: channel {est.channel}: no link-pass found")
    band = est.band_hz
    msg(f"vibkit {cmd}: no link-pass found in {band[0]:.4g}-{band[1]:.4g} Hz: {est.detection.get('reason', '')}")
    for w in est.warnings[1:]:
        msg(f"warning: {w}")
    return 1
