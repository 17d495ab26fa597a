"""``vibkit compare``: a recording against a scene (simulated) or a result file, harmonic by harmonic."""

from __future__ import annotations

import os

from .options import add_command, add_json, add_recording, band, harmonics, positive, read_recording
from .output import CLIError, msg, print_json, table

EPILOG = "example:\n  vibkit compare data/field/leon-tensioner.csv sim/leon.toml --duration 10"


def add_parser(subparsers):
    s = add_command(
        subparsers,
        "compare",
        "compare a recording with a scene (simulated) or a result file, harmonic by harmonic",
        EPILOG,
    )
    add_recording(s)
    add_json(s)
    s.add_argument("scene_or_result", metavar="SCENE_OR_RESULT", help="scene .toml or result .nc")
    s.add_argument("--band", type=band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--harmonics", type=harmonics, default=5, help="harmonics compared (default 5)")
    s.add_argument("--duration", type=positive, help="simulated time when given a scene [s]")
    s.set_defaults(func=run)
    return s


def run(a):
    import vibkit
    from vibkit.diagnose.comparison import compare

    rec = read_recording(a)
    target = a.scene_or_result
    if not os.path.exists(target):
        raise CLIError(f"{target}: file not found (expected a scene .toml or a result file)")
    try:
        comp = compare(
            rec, target, channel=a.channel, n_harmonics=a.harmonics, band=a.band, duration=a.duration, progress=True
        )
    except ValueError as exc:  # a message that names neither file is about the simulation side
        text = " ".join(str(exc).split())
        if os.fspath(target) in text or os.fspath(a.recording) in text:
            raise
        raise CLIError(f"{target}: {text}") from None
    del vibkit
    if a.json:
        d = comp.as_dict()
        d.update(recording=a.recording, simulation=target)
        print_json("compare", d)
        return 0
    print(f"recording {a.recording} [{comp.channel}] vs simulation {target} [{comp.variable}]")
    print(f"link-pass {comp.fundamental_meas_hz:.5f} Hz recorded, {comp.fundamental_sim_hz:.5f} Hz simulated")
    print(
        f"pitch     {1000 * comp.pitch_meas_m:.3f} mm recorded, {1000 * comp.pitch_sim_m:.3f} mm simulated "
        f"(ratio {comp.pitch_ratio:.5f}): {'consistent' if comp.pitch_consistent else 'NOT consistent'}"
    )
    print(f"score     {comp.score:.3f}   log-spectral distance {comp.log_spectral_distance_db:.2f} dB")
    print()
    print(
        table(
            [
                [
                    h["order"],
                    f"{h['frequency_sim_hz']:.4f}",
                    f"{h['frequency_meas_hz']:.4f}",
                    f"{h['frequency_ratio']:.5f} +- {h['frequency_ratio_sigma']:.1e}",
                    f"{h['amplitude_diff_db']:+.2f} [{h['amplitude_diff_db_ci'][0]:+.2f}, {h['amplitude_diff_db_ci'][1]:+.2f}]",
                    ("sim " if h["detected_sim"] else "") + ("rec" if h["detected_meas"] else ""),
                ]
                for h in comp.harmonics
            ],
            ("order", "f sim [Hz]", "f rec [Hz]", "ratio rec/sim", "amplitude diff [dB]", "detected"),
        )
    )
    for n in comp.notes:
        msg(f"note: {n}")
    return 0
