"""``vibkit ride``: ride quality of a step-riding accelerometer (ISO 2631-1), recorded or simulated."""

from __future__ import annotations

import dataclasses
import os
import re
import sys

from vibkit.diagnose.rounding import fmt_pm

from .options import (
    add_command,
    add_escalator,
    add_json,
    add_recording,
    add_speed,
    escalator_profile,
    positive,
    reader_options,
    segment_of,
)
from .output import STDIO, CLIError, msg, print_json, table
from .settings import run_settings

EPILOG = (
    "examples:\n  vibkit ride data/field/layouts/phyphox.csv --segment 0.5:3 --json\n"
    "  vibkit ride sim/las-palmas.toml --duration 15\n"
    "  vibkit ride step.csv --scene sim/las-palmas.toml --segment 3:25 --weighting x=Wd,y=Wd,z=Wk"
)


def add_parser(subparsers):
    s = add_command(
        subparsers,
        "ride",
        "ride quality of a step-riding accelerometer: ISO 2631-1 weighted max pk-pk, A95, r.m.s.",
        EPILOG,
    )
    s.add_argument("input", metavar="RECORDING_OR_SCENE", help="recording file, or a scene .toml (simulated)")
    s.add_argument(
        "--channels",
        help="recording channels for x,y,z (travel, lateral, vertical; - skips one), "
        "or AXIS=NAME pairs (default: names ending in x, y, z); write --channels=-,-,az when x is skipped",
    )
    add_speed(s, "the --escalator profile's, else the speed the file states")
    s.add_argument(
        "--weighting",
        type=_weightings,
        help="Wk, Wd ... for every axis, three for x,y,z (Wd,Wd,Wk), or x=Wd,y=Wd,z=Wk (the default)",
    )
    s.add_argument("--scene", help="also simulate this scene's step and report it next to the recording")
    s.add_argument("--duration", type=positive, help="simulated time [s] (default: the scene's)")
    add_recording(
        s,
        positional=False,
        channel=False,
        segment_help="ride segment START:END [s] of the recording, in its own time (as its time column reads): the "
        "ride quality over it (default: detected); outside the recording: an error",
    )
    add_json(s)
    add_escalator(s)
    s.set_defaults(func=run)
    return s


def _weightings(text):
    """``Wk`` (every axis), ``Wd,Wd,Wk`` (x, y, z) or ``x=Wd,y=Wd,z=Wk`` -> {axis: name} (None: the defaults);
    a bad value is a usage error (exit 2)."""
    import argparse

    from vibkit.diagnose.ride import parse_weightings

    try:
        return parse_weightings(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(re.sub(r"^--weighting ", "", str(exc))) from None


def _carried_scene(path):
    """The scene a vibkit result file carries in its attributes (``scene``: its TOML text), or None."""
    if not str(path).lower().endswith((".nc", ".nc4", ".h5")) or not os.path.isfile(path):
        return None
    import xarray as xr

    from vibkit.model.scene import SceneError, parse_scene

    try:
        with xr.open_dataset(path) as ds:
            text, source = ds.attrs.get("scene"), ds.attrs.get("scene_source", "")
    except (OSError, ValueError):
        return None
    if not text:
        return None
    try:
        return parse_scene(str(text), f"{source or 'the scene'} (carried by {path})")
    except (SceneError, ValueError, OSError):
        return None


def _knocks(a, is_scene, rq, sim):
    """The knock test of each ride (recording or scene, then --scene's simulation): a dict each (JSON)."""
    from vibkit.diagnose.knock import ride_knock, step_rollers_of
    from vibkit.model.scene import load_scene

    out = []
    profile = escalator_profile(a)
    for r, scene in ((rq, a.input if is_scene else None), (sim, a.scene)):
        if r is None:
            out.append(None)
            continue
        if scene:
            rollers = step_rollers_of(scene=load_scene(scene))
        elif profile is not None or r is not rq:
            rollers = step_rollers_of(profile=profile)
        else:  # a vibkit result file carries its scene
            rollers = step_rollers_of(scene=_carried_scene(a.input))
        res, note = ride_knock(r, rollers)
        d = {"checked": False, "reason": note} if res is None else {"checked": True, **res.as_dict(), "reason": note}
        if rollers is not None:
            d["roller_radius_m"], d["roller_radius_source"] = rollers[0], rollers[3]
        out.append(d)
    return out


def _speed_words(r, sp, rq):
    """A ride's speed as every command prints it: the run's speed with its sigma (``0.74850 +- 0.00075 m/s``), or
    to five digits where it states none (a simulation's counted speed)."""

    if r is rq and sp is not None and sp.value is not None and sp.sigma:
        return fmt_pm(sp.value, sp.sigma, "m/s")
    return f"{r.speed_m_s:.5g} m/s"


def _level_walk(profile) -> bool:
    """Whether the --escalator profile is a level moving walk (no incline: the whole record is the ride)."""
    return bool(getattr(profile, "is_walk", False)) and not profile.incline_deg


def run(a):
    from vibkit.diagnose.ride import parse_channels, ride_quality_from_recording
    from vibkit.diagnose.ride_simulation import simulate_ride

    segment = segment_of(a)
    weightings = a.weighting  # {axis: name}, or None: the defaults
    if a.input != STDIO and not os.path.exists(a.input):  # '-': a recording on stdin
        from vibkit.scenes import find

        shipped = find(a.input)  # a shipped scene's name
        if shipped is None:
            raise CLIError(f"{a.input}: file not found (expected a recording or a scene .toml)")
        a.input = str(shipped)
    is_scene = a.input.lower().endswith(".toml")
    sp = None
    if is_scene and a.channels:
        raise CLIError("--channels applies to a recording, not to a scene")
    if is_scene and a.scene:
        raise CLIError("--scene compares a recording with a scene; the input is already a scene")
    if is_scene:
        rq = simulate_ride(
            a.input, duration=a.duration, segment=segment, weightings=weightings, progress=sys.stderr.isatty()
        )
    else:
        rq = ride_quality_from_recording(
            a.input,
            channels=parse_channels(a.channels) if a.channels else None,
            segment=segment,
            weightings=weightings,
            read_options=reader_options(a),
            level_walk=_level_walk(escalator_profile(a)),
        )
        # --speed, else the escalator profile's: the run's one speed replaces the file's
        sp = run_settings(a, None, escalator_profile(a), notes=False).speed
        if sp.value is not None:
            rq = dataclasses.replace(rq, speed_m_s=sp.value)
    sim = None
    if a.scene:
        sim = simulate_ride(a.scene, duration=a.duration, weightings=weightings, progress=sys.stderr.isatty())
    knocks = _knocks(a, is_scene, rq, sim)
    if a.json:
        d = rq.as_dict()
        d["roller_knock"] = knocks[0]
        if sim is not None:
            d["simulation"] = sim.as_dict()
            d["simulation"]["roller_knock"] = knocks[1]
        print_json("ride", d)
    else:
        head = ("axis", "channel", "weighting", "max pk-pk", "A95", "r.m.s.", "10 Hz max pk-pk", "10 Hz A95")
        for r in (rq, sim):
            if r is None:
                continue
            seg = r.segment
            print(
                f"{r.source} ({r.kind}, {r.fs:.6g} Hz): ride {seg.start_s:.2f}-{seg.end_s:.2f} s "
                f"({seg.duration_s:.2f} s, {seg.method})"
                + (f", speed {_speed_words(r, sp, rq)}" if r.speed_m_s else "")
            )
            print("step vibration [m/s^2]: weighted (ISO 2631-1) and 0.4-10 Hz unweighted")
            print(table(r.table_rows(), head))
            k = knocks[0 if r is rq else 1]
            print(f"roller knock: {k['reason']}")
            print()
        for r in (rq, sim):
            for n in [] if r is None else r.notes + ([r.segment.note] if r.segment.note else []):
                msg(f"note: {n}")
    return 0
