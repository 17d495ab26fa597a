"""``vibkit links``: which link of the chain is worn, by number, from a tensioner recording over two loops or more."""

from __future__ import annotations

import argparse
import math

from vibkit.diagnose.rounding import fmt_pm

from .options import (
    _LENGTH_UNITS,
    CHANNEL_LENGTH,
    _quantity,
    add_command,
    add_escalator,
    add_json,
    add_links,
    add_marker,
    add_recording,
    add_speed,
    band,
    escalator_profile,
    read_recording,
)
from .output import CLIError, in_file, msg, print_json, shown, table
from .pitch import require_speed
from .settings import run_settings

EPILOG = (
    "example:\n  vibkit links tensioner.nc --speed 0.5 --links 159 --scene sim/thesis-forward.toml\n"
    "exit status: 0 the links were scanned (flagged or not), 1 refused (fewer than two loops,\n"
    "  no link pass, bad input), 2 usage error,\n"
    "  3 inconclusive (without a scene, a pattern over many links)"
)


def probability(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a probability, got {text!r}") from None
    if not 0.0 < v < 1.0:
        raise argparse.ArgumentTypeError(f"expected a probability in (0, 1), got {text!r}")
    return v


#: the longest worn link docs/guide/links.md measured (benchmarks/bench_links.py: 0.1 to 3 mm) [m]; a bare
#: --min-excess above it is a number of mm given without its unit (0.05 is 50 mm), refused
BARE_EXCESS_MAX_M = 3e-3


def excess_length(text):
    """--min-excess: metres, or with a unit (``0.2mm``); 0 or more, below 50 mm.

    A bare number is metres: one above :data:`BARE_EXCESS_MAX_M` (``0.05``, the default typed as mm, is 50 mm;
    ``0.01`` is 10 mm) is refused with how it was read."""
    if text.strip().rstrip("m").rstrip("m") in ("0", "0.0"):  # 0, 0m, 0mm: no minimum
        return 0.0
    v, factor, _unit = _quantity(text, _LENGTH_UNITS, "an excess pitch", "0.2mm")
    m = v * (factor or 1.0)
    if factor is None and m > BARE_EXCESS_MAX_M:
        raise argparse.ArgumentTypeError(
            f"{text!r} is {m:g} m = {1e3 * m:.6g} mm (a bare number is metres; no worn link measured was longer "
            f"than {1e3 * BARE_EXCESS_MAX_M:g} mm): give the unit, e.g. {text.strip()}mm"
        )
    if not (math.isfinite(m) and 0 <= m < 0.05):
        raise argparse.ArgumentTypeError(f"expected an excess pitch from 0 to 50 mm (e.g. 0.2mm), got {text!r}")
    return m


def add_parser(subparsers):
    s = add_command(
        subparsers, "links", "which link of the chain is worn, by number, from a tensioner recording", EPILOG
    )
    add_recording(s, channel_default=CHANNEL_LENGTH)
    add_json(s)
    add_speed(s, "the --escalator profile's, else the speed the file states")
    add_links(s)
    add_escalator(s)
    s.add_argument(
        "--scene",
        help="forward scene of the escalator: gives the worn link's signature on the tensioner (one number per "
        "worn link, its excess pitch in mm); without it each link's own cycle is tested",
    )
    s.add_argument(
        "--direction",
        choices=("up", "down"),
        help="the way the steps travelled while recorded (the worn link's signature is simulated running that way; "
        "default: the --escalator profile's drive.direction, else the --scene's motor speed sign)",
    )
    add_marker(s)
    s.add_argument(
        "--false-alarm",
        type=probability,
        default=0.01,
        help="probability that a chain without a worn link gets any flag, over all its links (default 0.01)",
    )
    s.add_argument(
        "--min-excess",
        type=excess_length,
        help="with --scene: flag a link only when its excess pitch is at least this: 0.05mm, or m (a bare number, "
        f"at most {BARE_EXCESS_MAX_M:g}) (default 0.05 mm)",
    )
    s.add_argument("--band", type=band, help="link-pass search band LOW:HIGH [Hz] (default speed / 200-80 mm)")
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.diagnose.links import TooFewLoops, find_worn_links, profile_scene_file

    rec = read_recording(a)
    profile = escalator_profile(a)
    settings = run_settings(a, rec, profile)  # as `pitch` resolves them: a --links the profile contradicts
    speed = require_speed(a, settings).value
    n_links = settings.n_links
    if n_links is None:
        raise CLIError(
            f"{shown(a.recording)}: give --links N, the chain's number of links (or --escalator FILE with chain.n_links)"
        )
    scene = a.scene
    if scene is not None and not scene.strip():
        raise CLIError(
            f"--scene {scene!r}: expected the escalator's forward scene file (TOML); give its path, or leave --scene out"
        )
    if a.direction is not None and profile is not None and a.scene is None and a.direction != profile.direction:
        raise CLIError(
            f"--direction {a.direction}: the profile {profile.source} says drive.direction = {profile.direction}; "
            "correct the profile, or leave --direction out"
        )
    if scene is None and profile is not None:
        scene = profile_scene_file(profile)
    try:
        res = find_worn_links(
            rec,
            speed=speed,
            n_links=n_links,
            channel=a.channel,
            scene=scene,
            marker_s=a.marker,
            false_alarm=a.false_alarm,
            band=a.band,  # not the settings' profile band: the map's own, speed / 200-80 mm, unless given
            file=shown(a.recording),
            nominal_pitch=settings.nominal_pitch,
            direction=a.direction,
            profile=profile,
            **({} if a.min_excess is None else {"min_excess": a.min_excess}),
        )
    except TooFewLoops as exc:
        if a.json:
            print_json("links", {"file": shown(a.recording), "status": "too short", "reason": str(exc), "flagged": []})
        msg(f"vibkit links: {shown(a.recording)}: {exc}")
        return 1
    except ValueError as exc:
        if a.scene is None and profile is not None:  # the profile's scene is a temporary file: name the profile
            exc = ValueError(str(exc).replace(str(scene), f"of the profile {profile.source}"))
        raise in_file(a.recording, exc) from None
    code = 3 if res.status == "inconclusive" else 0
    if a.json:
        print_json("links", res.as_dict())
        return code
    if res.status == "inconclusive":
        msg(f"vibkit links: {shown(a.recording)}: inconclusive: {res.reason}")
        return code
    print(
        f"{shown(a.recording)}: channel {res.channel}, {res.loops} loops of {res.n_links} links at "
        f"{res.link_pass_hz:.4f} Hz link pass ({speed:g} m/s)"
    )
    print(f"method               {res.method}")
    if res.direction is not None:
        print(f"direction            {res.direction} (the signature simulated running {res.direction})")
    print(
        f"threshold            |t| > {res.threshold:.2f} (false alarm {res.false_alarm:g} per recording over "
        f"{res.n_links} links, {res.dof:.0f} degrees of freedom)"
    )
    link1 = f"marked at {res.marker_s:g} s" if res.marker_s is not None else "at the sensor at the start"
    print(f"link 1               the link {link1}; numbers in the order the links pass")
    print()
    if res.flagged:
        rows = []
        for f in res.flagged:
            ex = "-" if f["excess_pitch_mm"] is None else fmt_pm(f["excess_pitch_mm"], f["sigma_mm"], sign=True)
            link = " or ".join(str(k) for k in [f["link"], *f.get("alternatives", ())])
            rows.append([link, ex, f"{f['t']:.1f}", ",".join(str(i) for i in f["loops"]) or "-"])
        print(table(rows, ("link", "excess pitch [mm]", "|t|", "loops that show it")))
    else:
        print("no link flagged")
    for n in res.notes:
        msg(f"note: {n}")
    return 0
