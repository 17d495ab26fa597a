"""``vibkit compare``: a recording against a scene (simulated) or a result file, harmonic by harmonic."""

from __future__ import annotations

import os

from vibkit.diagnose.rounding import fmt_pm

from .options import (
    CHANNEL_EVERY,
    _profile_of,
    add_command,
    add_escalator,
    add_json,
    add_recording,
    add_speed,
    add_speed_uncertainty,
    band,
    harmonics,
    positive,
    read_recording,
)
from .output import CLIError, msg, print_json, shown, table
from .settings import run_settings

EPILOG = "example:\n  vibkit compare data/field/leon-tensioner.csv sim/leon.toml --duration 10"


def add_parser(subparsers):
    s = add_command(
        subparsers,
        "compare",
        "compare a recording with a scene (simulated) or a result file, harmonic by harmonic",
        EPILOG,
    )
    add_recording(s, channel_default=CHANNEL_EVERY)  # the decision of pitch and report (estimate_channels)
    add_json(s)
    add_escalator(s)
    s.add_argument(
        "scene_or_result",
        metavar="SCENE_OR_RESULT",
        nargs="?",
        help="scene .toml or result .nc (default with --escalator: the scene built from the profile)",
    )
    s.add_argument("--band", type=band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--harmonics", type=harmonics, default=5, help="harmonics compared (default 5)")
    s.add_argument("--duration", type=positive, help="simulated time when given a scene [s]")
    add_speed(
        s,
        "the --escalator profile's, else the speed the file states, else the scene's nominal speed (then the "
        "pitch is not judged)",
        "the recording's chain speed, measured on the steps",
    )
    add_speed_uncertainty(s)
    s.set_defaults(func=run)
    return s


def _name(target):
    """A scene or result as the output names it: its path, or the scene built from a profile."""
    return target if isinstance(target, str) else f"{target.name} ({target.source})"


def run(a):
    import vibkit
    from vibkit.diagnose.comparison import NothingToCompare, amplitude_diff_text, compare

    rec = read_recording(a)
    target = a.scene_or_result
    profile = _profile_of(a)
    if target is None:
        if profile is None:
            raise CLIError("give SCENE_OR_RESULT (a scene .toml or a result file), or --escalator FILE")
        target = profile.scene("forward", a.duration)  # the unit's own scene, in memory
    elif not os.path.exists(target):
        from vibkit.scenes import find

        if find(target) is None:
            raise CLIError(
                f"{target}: file not found (expected a scene .toml, a shipped scene's name or a result file)"
            )
    sp = run_settings(a, rec, profile, notes=False).speed  # the compare's band is its own (both sides' speeds)
    try:
        comp = compare(
            rec,
            target,
            channel=a.channel,
            n_harmonics=a.harmonics,
            band=a.band,
            duration=a.duration,
            progress=True,
            speed=sp.value,
            speed_sigma=sp.sigma,
            profile=profile,
        )
    except NothingToCompare as exc:  # the recording's side
        raise CLIError(f"{shown(a.recording)}: {' '.join(str(exc).split())}") from None
    except ValueError as exc:  # a message that names neither file is about the simulation side
        text = " ".join(str(exc).split())
        if _name(target) in text or os.fspath(a.recording) in text:
            raise
        raise CLIError(f"{_name(target)}: {text}") from None
    del vibkit
    if a.json:
        d = comp.as_dict()
        d.update(recording=shown(a.recording), simulation=_name(target))
        print_json("compare", d)
        return 0
    print(f"recording {shown(a.recording)} [{comp.channel}] vs simulation {_name(target)} [{comp.variable}]")
    print(f"link-pass {comp.link_pass_meas_hz:.5f} Hz recorded, {comp.link_pass_sim_hz:.5f} Hz simulated")
    print(
        f"speed     {sp.text if sp.value is not None else f'{comp.speed_meas_m_s:.4g} m/s (the scene' + chr(39) + 's, assumed)'}"
    )
    if sp.value is None:  # the recording taken at the scene's speed: a ratio of link passes, not of pitches
        print(
            f"pitch     not judged: the recording's speed is not known (give --speed); at the scene's speed its "
            f"link pass gives {1000 * comp.pitch_meas_m:.2f} mm, the simulation {1000 * comp.pitch_sim_m:.2f} mm "
            f"(link-pass ratio simulated/recorded {comp.pitch_ratio:.4g})"
        )
    else:
        print(
            f"pitch     {1000 * comp.pitch_meas_m:.2f} mm recorded, {1000 * comp.pitch_sim_m:.2f} mm simulated "
            f"(pitch ratio recorded/simulated {fmt_pm(comp.pitch_ratio, comp.pitch_ratio_sigma)}): "
            f"{'consistent' if comp.pitch_consistent else 'NOT consistent'}"
        )
    print(
        f"score     {comp.score:.3f} (0-1: the harmonics' agreement, frequency within 1 %, amplitude within 3 dB)   "
        f"log-spectral distance {comp.log_spectral_distance_db:.2f} dB"
    )
    print()
    print(
        table(
            [
                [
                    h["order"],
                    f"{h['frequency_sim_hz']:.4f}",
                    f"{h['frequency_meas_hz']:.4f}",
                    fmt_pm(h["frequency_ratio"], h["frequency_ratio_sigma"]),
                    amplitude_diff_text(h),
                    ("sim " if h["detected_sim"] else "") + ("rec" if h["detected_meas"] else ""),
                ]
                for h in comp.harmonics
            ],
            ("order", "f sim [Hz]", "f rec [Hz]", "f rec / f sim", "amplitude diff [dB]", "detected"),
        )
    )
    for n in comp.notes:
        msg(f"note: {n}")
    return 0
