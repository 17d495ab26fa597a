"""The ``vibkit`` command line: parses, calls the library, prints.  No physics in here.

Data go to stdout (a readable table, or JSON with ``--json`` carrying ``"schema": "vibkit.<command>/1"``),
messages to stderr.  Exit status: 0 success, 1 bad data or a failed run (one-line message, no
traceback), 2 usage error (argparse).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["main"]

SCHEMA_VERSION = 1


class CLIError(ValueError):
    """A problem with the command's inputs, reported in one line (exit 1)."""


def _schema(cmd):
    return f"vibkit.{cmd}/{SCHEMA_VERSION}"


def _color():
    return sys.stderr.isatty() and "NO_COLOR" not in os.environ and os.environ.get("TERM", "") != "dumb"


def _msg(text):
    print(text, file=sys.stderr)


def _jsonable(o):
    import numpy as np

    if isinstance(o, dict):
        return {str(k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return _jsonable(o.tolist())
    if isinstance(o, (np.floating, float)):
        v = float(o)
        return v if math.isfinite(v) else None
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.bool_,)):
        return bool(o)
    return o


def _print_json(cmd, payload):
    d = {"schema": _schema(cmd)}
    d.update(_jsonable(payload))
    print(json.dumps(d, indent=2, sort_keys=False, allow_nan=False))


def _table(rows, header=None):
    rows = [[str(c) for c in r] for r in rows]
    if header:
        rows = [list(header)] + rows
    if not rows:
        return ""
    w = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)).rstrip() for r in rows]
    if header:
        lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines)


def _band(text):
    try:
        lo, hi = (float(v) for v in text.replace(",", ":").split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LOW:HIGH in Hz (e.g. 2.5:6), got {text!r}") from None
    if not 0 < lo < hi:
        raise argparse.ArgumentTypeError(f"expected 0 < LOW < HIGH, got {text!r}")
    return (lo, hi)


def _limits(text):
    try:
        vals = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three percentages like 1.5,2,3, got {text!r}") from None
    if len(vals) != 3 or not 0 < vals[0] < vals[1] < vals[2]:
        raise argparse.ArgumentTypeError(f"expected three increasing positive percentages, got {text!r}")
    return vals


def _positive(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _teeth(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of sprocket teeth, got {text!r}") from None
    if v < 3:
        raise argparse.ArgumentTypeError(f"a sprocket has at least 3 teeth, got {text!r}")
    return v


def _speed_sigma(text, speed):
    t = text.strip()
    try:
        if t.endswith("%"):
            v = float(t[:-1]) / 100.0 * speed
        else:
            v = float(t)
    except ValueError:
        raise CLIError(f"--speed-uncertainty: expected m/s or a percentage like 0.1%, got {text!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise CLIError(f"--speed-uncertainty must be >= 0, got {text!r}")
    return v


def _check_output(out, inputs):
    out = os.fspath(out)
    for p in inputs:
        if p and os.path.exists(out) and os.path.exists(p) and os.path.samefile(out, p):
            raise CLIError(f"output {out!r} is an input file; refusing to overwrite it")


# ---------------------------------------------------------------------------------------------- commands


def _cmd_simulate(a):
    import vibkit
    from vibkit.io import write_result

    _check_output(a.output, [a.scene])
    scene = vibkit.load_scene(a.scene)
    t0 = time.perf_counter()
    ds = vibkit.simulate(scene, duration=a.duration, progress=sys.stderr.isatty())
    wall = time.perf_counter() - t0
    path = write_result(ds, a.output)
    resid = float(ds["closure_residual"].max()) if "closure_residual" in ds else \
        float(ds.attrs.get("closure_residual_max", float("nan")))
    summary = {"scene": scene.name, "analysis": scene.analysis, "output": os.fspath(path),
               "dims": {k: int(v) for k, v in ds.sizes.items()},
               "variables": {str(k): {"dims": list(v.dims), "units": v.attrs.get("units", "")}
                             for k, v in ds.data_vars.items()},
               "closure_residual_max_m": resid, "wall_time_s": wall}
    if a.json:
        _print_json("simulate", summary)
    else:
        print(f"scene     {scene.name} ({scene.analysis})")
        print(f"output    {summary['output']}")
        print(f"dims      {', '.join(f'{k}={v}' for k, v in summary['dims'].items())}")
        print(f"closure   max residual {resid:.3g} m")
        print(f"wall time {wall:.2f} s")
        print(_table([[k, ",".join(v["dims"]), v["units"]] for k, v in summary["variables"].items()],
                     ("variable", "dims", "units")))
    return 0


def _read(a):
    import vibkit

    return vibkit.read_recording(a.recording, sample_rate=getattr(a, "sample_rate", None))


def _cmd_spectrum(a):
    from vibkit.pitch import estimate_pitch, pick_channel

    rec = _read(a)
    ch = pick_channel(rec, a.channel)
    band = a.band or (2.5, 6.0)
    est = estimate_pitch(rec, speed=1.0, channel=ch, band=band, n_harmonics=a.harmonics)
    units = str(rec[ch].attrs.get("units", "1"))
    if not est.detected:
        return _not_found("spectrum", a, est, {"file": a.recording, "channel": ch, "units": units,
                                               "band_hz": list(band)})
    peaks = [{"order": h["order"], "frequency_hz": h["frequency_hz"], "amplitude": h["amplitude"],
              "units": units, "detected": h["detected"]} for h in est.harmonics]
    payload = {"status": est.status, "file": a.recording, "channel": ch, "units": units, "band_hz": list(band),
               "method": est.method, "method_reason": est.method_reason, "detection": est.detection,
               "invalid_samples": est.invalid_samples,
               "fundamental_hz": est.fundamental_hz, "fundamental_sigma_hz": est.fundamental_sigma_hz,
               "snr_db": est.snr_db, "peaks": peaks, "warnings": est.warnings}
    if a.json:
        _print_json("spectrum", payload)
    else:
        print(f"{a.recording}: channel {ch} [{units}]")
        print(f"link-pass fundamental {est.fundamental_hz:.5f} +- {est.fundamental_sigma_hz:.2g} Hz "
              f"(search band {band[0]:g}-{band[1]:g} Hz)")
        print(_table([[p["order"], f"{p['frequency_hz']:.4f}", f"{p['amplitude']:.4g}", "yes" if p["detected"] else "no"]
                      for p in peaks], ("order", "frequency [Hz]", f"amplitude [{units}]", "detected")))
        for w in est.warnings:
            _msg(f"warning: {w}")
    return 0


def _cmd_pitch(a):
    from vibkit.pitch import estimate_pitch

    rec = _read(a)
    sigma = _speed_sigma(a.speed_uncertainty, a.speed) if a.speed_uncertainty else 0.0
    est = estimate_pitch(rec, speed=a.speed, speed_sigma=sigma, channel=a.channel, band=a.band,
                         nominal_pitch=a.nominal_pitch, limits_percent=a.limits, teeth=a.teeth)
    if not est.detected:
        return _not_found("pitch", a, est, {"file": a.recording})
    if a.json:
        d = est.as_dict()
        d["file"] = a.recording
        _print_json("pitch", d)
        return 0
    print(f"{a.recording}: channel {est.channel}, speed {est.speed_m_s:g} +- {est.speed_sigma_m_s:.2g} m/s")
    print(f"link-pass frequency  {est.fundamental_hz:.5f} +- {est.fundamental_sigma_hz:.2g} Hz "
          f"({len(est.per_burst)} burst(s))")
    print(f"method               {est.method}")
    print(f"link pitch           {1000 * est.pitch_m:.3f} +- {1000 * est.pitch_sigma_m:.3f} mm")
    if est.nominal_pitch_m is not None:
        print(f"elongation           {est.elongation_percent:+.2f} +- {est.elongation_sigma_percent:.2f} % "
              f"of {1000 * est.nominal_pitch_m:.2f} mm -> {est.verdict} "
              f"(limits {' / '.join(f'{v:g}' for v in est.limits_percent)} %)")
    print()
    print(_table([[h.name, f"{h.frequency_hz:.4f}", "n/a" if math.isnan(h.snr_db) else f"{h.snr_db:.0f}",
                   f"{1000 * h.implied_pitch_m:.2f}", f"{1000 * h.nearest_catalogue_m:.2f} ({h.deviation_percent:+.1f} %)",
                   "<-" if h.chosen else "", h.reason] for h in est.hypotheses],
                 ("hypothesis", "link pass [Hz]", "SNR [dB]", "pitch [mm]", "catalogue [mm]", "", "why")))
    print()
    print(_table([[h["order"], f"{h['frequency_hz']:.4f}", f"{h['amplitude']:.4g}", "yes" if h["detected"] else "no"]
                  for h in est.harmonics], ("order", "frequency [Hz]", f"amplitude [{est.extra['units']}]", "detected")))
    for w in est.warnings:
        _msg(f"warning: {w}")
    for n in est.notes:
        _msg(f"note: {n}")
    _msg(f"note: method {est.method}: {est.method_reason}")
    return 0


def _not_found(cmd, a, est, extra):
    """No link-pass family in the band: say so (JSON with the status, no number), exit 1."""
    if a.json:
        d = est.as_dict()
        d.update(extra)
        _print_json(cmd, d)
    else:
        print(f"{a.recording}: channel {est.channel}: no link-pass found")
    band = est.band_hz
    _msg(f"vibkit {cmd}: no link-pass found in {band[0]:.4g}-{band[1]:.4g} Hz: {est.detection.get('reason', '')}")
    for w in est.warnings[1:]:
        _msg(f"warning: {w}")
    return 1


def _cmd_compare(a):
    import vibkit
    from vibkit.comparison import compare

    rec = _read(a)
    target = a.scene_or_result
    if not os.path.exists(target):
        raise CLIError(f"{target}: file not found (expected a scene .toml or a result file)")
    comp = compare(rec, target, channel=a.channel, n_harmonics=a.harmonics, band=a.band, duration=a.duration,
                   progress=sys.stderr.isatty())
    del vibkit
    if a.json:
        d = comp.as_dict()
        d.update(recording=a.recording, simulation=target)
        _print_json("compare", d)
        return 0
    print(f"recording {a.recording} [{comp.channel}] vs simulation {target} [{comp.variable}]")
    print(f"link-pass {comp.fundamental_meas_hz:.5f} Hz recorded, {comp.fundamental_sim_hz:.5f} Hz simulated")
    print(f"pitch     {1000 * comp.pitch_meas_m:.3f} mm recorded, {1000 * comp.pitch_sim_m:.3f} mm simulated "
          f"(ratio {comp.pitch_ratio:.5f}): {'consistent' if comp.pitch_consistent else 'NOT consistent'}")
    print(f"score     {comp.score:.3f}   log-spectral distance {comp.log_spectral_distance_db:.2f} dB")
    print()
    print(_table([[h["order"], f"{h['frequency_sim_hz']:.4f}", f"{h['frequency_meas_hz']:.4f}",
                   f"{h['frequency_ratio']:.5f} +- {h['frequency_ratio_sigma']:.1e}",
                   f"{h['amplitude_diff_db']:+.2f} [{h['amplitude_diff_db_ci'][0]:+.2f}, {h['amplitude_diff_db_ci'][1]:+.2f}]",
                   ("sim " if h["detected_sim"] else "") + ("rec" if h["detected_meas"] else "")]
                  for h in comp.harmonics],
                 ("order", "f sim [Hz]", "f rec [Hz]", "ratio rec/sim", "amplitude diff [dB]", "detected")))
    for n in comp.notes:
        _msg(f"note: {n}")
    return 0


def _cmd_report(a):
    from vibkit.report import write_report

    _check_output(a.output, [a.recording, a.scene])
    sigma = _speed_sigma(a.speed_uncertainty, a.speed) if (a.speed_uncertainty and a.speed) else 0.0
    rep = write_report(a.recording, a.output, scene=a.scene, speed=a.speed, speed_sigma=sigma, channel=a.channel,
                       nominal_pitch=a.nominal_pitch, limits_percent=a.limits, sample_rate=a.sample_rate,
                       duration=a.duration, band=a.band, progress=sys.stderr.isatty())
    if a.json:
        _print_json("report", {"output": rep.path, "pages": [t for t, _ in rep.pages], "summary": rep.summary})
    else:
        print(f"wrote {rep.path} ({len(rep.pages)} pages)")
        print(_table([[k, f"{v:.6g}" if isinstance(v, float) else v] for k, v in rep.summary.items()]))
    return 0


def _repo_root():
    return Path(__file__).resolve().parent.parent


def _cmd_bench(a):
    root = Path(a.root) if a.root else _repo_root()
    bdir = root / "benchmarks"
    if not bdir.is_dir():
        raise CLIError(f"{bdir}: no benchmarks folder (give --root, the repository holding benchmarks/)")
    scripts = sorted(bdir.glob("bench_*.py"))
    if (bdir / "work_precision.py").exists():
        scripts.append(bdir / "work_precision.py")
    if a.only:
        scripts = [s for s in scripts if a.only in s.stem]
        if not scripts:
            raise CLIError(f"--only {a.only!r} matches no script in {bdir}")
    if not scripts:
        raise CLIError(f"{bdir}: no bench_*.py script")
    rows = []
    failed = 0
    for i, s in enumerate(scripts, 1):
        _msg(f"[{i}/{len(scripts)}] {s.name} ...")
        cmd = [sys.executable, str(s)] + (["--quick"] if a.quick else [])
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.perf_counter() - t0
        ok = proc.returncode == 0
        failed += not ok
        last = (proc.stdout.strip().splitlines() or [""])[-1][:100]
        rows.append({"script": s.name, "returncode": proc.returncode, "wall_time_s": wall, "last_line": last})
        _msg(f"    {'ok' if ok else 'FAILED'} in {wall:.1f} s")
    if a.json:
        _print_json("bench", {"root": str(root), "quick": bool(a.quick), "results": rows})
    else:
        print(_table([[r["script"], "ok" if r["returncode"] == 0 else f"failed ({r['returncode']})",
                       f"{r['wall_time_s']:.1f}", r["last_line"]] for r in rows],
                     ("script", "status", "wall [s]", "last line")))
    if failed:
        raise CLIError(f"{failed} of {len(rows)} benchmark script(s) failed")
    return 0


# ------------------------------------------------------------------------------------------------ parser

_EPILOG = {
    "simulate": "example:\n  vibkit simulate sim/leon.toml -o reports/leon.nc --duration 10",
    "spectrum": "example:\n  vibkit spectrum data/field/leon-tensioner.csv --band 2.5:6 --json",
    "pitch": "examples:\n  vibkit pitch data/field/leon-tensioner.csv --speed 0.49 --speed-uncertainty 0.1% "
             "--nominal-pitch 0.13333\n  vibkit pitch logger.txt --sample-rate 2050 --speed 0.52 --json",
    "compare": "example:\n  vibkit compare data/field/leon-tensioner.csv sim/leon.toml --duration 10",
    "report": "example:\n  vibkit report data/field/leon-tensioner.csv --scene sim/leon.toml -o reports/leon.pdf",
    "bench": "example:\n  vibkit bench --quick --only signal",
}


def _parser():
    import vibkit

    p = argparse.ArgumentParser(prog="vibkit", description="Escalator drive-chain vibration: simulate, analyse, "
                                "compare, report.", formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="run 'vibkit COMMAND --help' for each command's options and an example")
    p.add_argument("--version", action="version", version=f"vibkit {vibkit.__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(name, help_):
        return sub.add_parser(name, help=help_, description=help_, epilog=_EPILOG[name],
                              formatter_class=argparse.RawDescriptionHelpFormatter)

    def common(sp, *, rec=True):
        if rec:
            sp.add_argument("recording", help="recording file (CSV/text, miniSEED ..., netCDF)")
            sp.add_argument("--channel", help="channel to analyse (default: the first)")
            sp.add_argument("--sample-rate", type=_positive, help="sample rate for files without time [Hz]")
        sp.add_argument("--json", action="store_true", help="JSON on stdout (with a schema version)")

    s = add("simulate", "simulate a scene and write the result (netCDF4/HDF5)")
    s.add_argument("scene", help="scene file (.toml)")
    s.add_argument("-o", "--output", required=True, help="result file to write (.nc)")
    s.add_argument("--duration", type=_positive, help="override the scene's duration [s] (kinematics: [m])")
    common(s, rec=False)
    s.set_defaults(func=_cmd_simulate)

    s = add("spectrum", "link-pass fundamental and harmonic peak table of a recording")
    common(s)
    s.add_argument("--band", type=_band, help="search band of the link-pass LOW:HIGH [Hz] (default 2.5:6)")
    s.add_argument("--harmonics", type=int, default=5, help="harmonics listed (default 5)")
    s.set_defaults(func=_cmd_spectrum)

    s = add("pitch", "link pitch from a recording's link-pass frequency and the chain speed")
    common(s)
    s.add_argument("--speed", type=_positive, required=True, help="chain speed measured on the steps [m/s]")
    s.add_argument("--speed-uncertainty", help="speed standard deviation, in m/s or in %% (e.g. 0.1%%)")
    s.add_argument("--nominal-pitch", type=_positive, help="nominal link pitch [m]: gives elongation and verdict")
    s.add_argument("--limits", type=_limits, default=(1.5, 2.0, 3.0),
                   help="elongation limits watch,plan,replace [%%] (default 1.5,2,3)")
    s.add_argument("--band", type=_band, help="search band LOW:HIGH [Hz] (default speed / 80-200 mm)")
    s.add_argument("--teeth", type=_teeth, default=28, help="sprocket teeth, for the shaft hypothesis (default 28)")
    s.set_defaults(func=_cmd_pitch)

    s = add("compare", "compare a recording with a scene (simulated) or a result file, harmonic by harmonic")
    common(s)
    s.add_argument("scene_or_result", metavar="SCENE_OR_RESULT", help="scene .toml or result .nc")
    s.add_argument("--band", type=_band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--harmonics", type=int, default=5, help="harmonics compared (default 5)")
    s.add_argument("--duration", type=_positive, help="simulated time when given a scene [s]")
    s.set_defaults(func=_cmd_compare)

    s = add("report", "write the multi-page PDF diagnostic report of a recording")
    common(s)
    s.add_argument("--scene", help="scene describing the escalator and sensor (simulated and compared)")
    s.add_argument("-o", "--output", required=True, help="PDF to write")
    s.add_argument("--speed", type=_positive, help="chain speed [m/s] (default: recording's or scene's)")
    s.add_argument("--speed-uncertainty", help="speed standard deviation, in m/s or in %%")
    s.add_argument("--nominal-pitch", type=_positive, help="nominal link pitch [m] (default: the scene's)")
    s.add_argument("--limits", type=_limits, default=(1.5, 2.0, 3.0), help="elongation limits [%%]")
    s.add_argument("--band", type=_band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--duration", type=_positive, help="simulated time [s] (default: the scene's)")
    s.set_defaults(func=_cmd_report)

    s = add("bench", "run the repository's benchmark scripts (benchmarks/bench_*.py)")
    s.add_argument("--quick", action="store_true", help="pass --quick to every script")
    s.add_argument("--only", help="run only scripts whose name contains this")
    s.add_argument("--root", help="repository root holding benchmarks/ (default: next to the vibkit package)")
    s.add_argument("--json", action="store_true", help="JSON on stdout")
    s.set_defaults(func=_cmd_bench)
    return p


def main(argv=None) -> int:
    """Run the command line; returns the exit status (argparse usage errors raise SystemExit(2)).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).
    """
    from vibkit.integrate import IntegrationError
    from vibkit.io import RecordingError
    from vibkit.scene import SceneError

    args = _parser().parse_args(argv)
    try:
        return int(args.func(args))
    except (SceneError, RecordingError, IntegrationError, ValueError, OSError) as exc:
        text = " ".join(str(exc).split()) or type(exc).__name__
        prefix = "\033[31merror\033[0m" if _color() else "error"
        _msg(f"vibkit {args.command}: {prefix}: {text}")
        return 1
    except KeyboardInterrupt:
        _msg("vibkit: interrupted")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
