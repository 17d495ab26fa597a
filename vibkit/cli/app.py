"""The ``vibkit`` command line: parses, calls the library, prints.  No physics in here.

Data go to stdout (a readable table, or JSON with ``--json`` carrying ``"schema": "vibkit.<command>/1"``),
messages to stderr.  Exit status: 0 success, 1 bad data or a failed run (one-line message, no
traceback), 2 usage error (argparse).
"""

from __future__ import annotations

import argparse
import errno
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


def _speed_uncertainty(text):
    """argparse type of --speed-uncertainty: m/s or a percentage; a bad value is a usage error (exit 2)."""
    try:
        _speed_sigma(text, 1.0)
    except CLIError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None
    return text


def _byte_size(text):
    from vibkit.runtime.budget import parse_bytes

    try:
        return parse_bytes(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _seconds_or_none(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if math.isnan(v) or v < 0:
        raise argparse.ArgumentTypeError(f"expected a number of seconds >= 0 (0: no limit), got {text!r}")
    return math.inf if v == 0 else v


def _check_output(out, inputs, force=False):
    """Refuse an unsafe -o before any work (see :mod:`vibkit.runtime.safe_output`)."""
    from vibkit.runtime.safe_output import check_output_path

    check_output_path(out, overwrite=force, inputs=[p for p in inputs if p])


# ---------------------------------------------------------------------------------------------- commands


def _cmd_simulate(a):
    import vibkit
    from vibkit.io import write_result

    _check_output(a.output, [a.scene], a.force)
    scene = vibkit.load_scene(a.scene)
    t0 = time.perf_counter()
    ds = vibkit.simulate(scene, duration=a.duration, progress=True, max_result_bytes=a.max_result_bytes,
                         max_wall_time=a.max_wall_time)
    wall = time.perf_counter() - t0
    path = write_result(ds, a.output, overwrite=a.force, inputs=[a.scene])
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

    tc = getattr(a, "time_column", None)
    if tc is not None:  # a 0-based index, 'none' (the file has no time column) or a name as the file writes it
        tc = int(tc) if tc.strip().isdigit() else False if tc.strip().lower() == "none" else tc
    return vibkit.read_recording(a.recording, sample_rate=getattr(a, "sample_rate", None), time_column=tc,
                                 time_unit=getattr(a, "time_unit", None),
                                 repair_time=bool(getattr(a, "repair_time", False)))


def _cmd_spectrum(a):
    from vibkit.diagnose.pitch import estimate_pitch, pick_channel

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
    from vibkit.diagnose.pitch import estimate_pitch

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
    from vibkit.diagnose.comparison import compare

    rec = _read(a)
    target = a.scene_or_result
    if not os.path.exists(target):
        raise CLIError(f"{target}: file not found (expected a scene .toml or a result file)")
    comp = compare(rec, target, channel=a.channel, n_harmonics=a.harmonics, band=a.band, duration=a.duration,
                   progress=True)
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
    from vibkit.diagnose.report import write_report

    _check_output(a.output, [a.recording, a.scene], a.force)
    sigma = _speed_sigma(a.speed_uncertainty, a.speed) if (a.speed_uncertainty and a.speed) else 0.0
    rep = write_report(a.recording, a.output, scene=a.scene, speed=a.speed, speed_sigma=sigma, channel=a.channel,
                       nominal_pitch=a.nominal_pitch, limits_percent=a.limits, sample_rate=a.sample_rate,
                       duration=a.duration, band=a.band, progress=True, overwrite=a.force)
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


def _vary(text):
    from vibkit.sweep.plan import parse_vary

    try:
        return parse_vary(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _cmd_sweep(a):
    import numpy as np

    import vibkit

    # a Zarr store is a folder, re-used to resume: only refuse one that is the scene itself (the
    # library refuses a folder that is not this sweep's store unless --force)
    if os.path.exists(a.output) and os.path.exists(a.scene) and os.path.samefile(a.output, a.scene):
        raise CLIError(f"output {a.output!r} is the scene file; refusing to overwrite it")
    vary = {}
    for key, spec in a.vary:
        if key in vary:
            raise CLIError(f"--vary {key} given twice")
        vary[key] = spec
    t0 = time.perf_counter()
    ds = vibkit.sweep(a.scene, vary, output=a.output, samples=a.samples, seed=a.seed, keep=a.keep or (),
                      settle=a.settle, duration=a.duration, scheduler=a.scheduler, n_workers=a.workers,
                      force=a.force, progress=not a.quiet, max_runs=a.max_runs)
    wall = time.perf_counter() - t0
    st = ds["status"]
    keys = [k.strip() for k in ds.attrs["varied_keys"].split(",")]
    meaning = dict(zip((int(v) for v in st.attrs["flag_values"]), st.attrs["flag_meanings"].split()))
    cols = {name: ds[name].values for name in ("status", "error", "link_pass_frequency", "delta_mean", "delta_ripple",
                                               "peak_link_tension", "wall_time")}
    runs = []
    for idx in np.ndindex(*st.shape):
        at = dict(zip(st.dims, idx))
        row = {"values": {k: ds[k].isel({d: at[d] for d in ds[k].dims}).item() for k in keys},
               "status": meaning.get(int(cols["status"][idx]), str(int(cols["status"][idx]))),
               "error": str(cols["error"][idx])}
        for name in ("link_pass_frequency", "delta_mean", "delta_ripple", "peak_link_tension", "wall_time"):
            row[name] = float(cols[name][idx])
        runs.append(row)
    complete = ds.attrs.get("runs_pending", 0) == 0 and ds.attrs.get("vibkit_sweep_state", "") != "running"
    summary = {"scene": a.scene, "output": os.fspath(a.output), "sweep": ds.attrs["sweep"],
               "dims": {k: int(v) for k, v in ds["status"].sizes.items()}, "runs": int(ds.attrs["runs"]),
               "ok": int(ds.attrs["runs_ok"]), "failed": int(ds.attrs["runs_failed"]),
               "invalid": int(ds.attrs["runs_invalid"]), "pending": int(ds.attrs.get("runs_pending", 0)),
               "computed": int(ds.attrs["runs_computed"]), "reused": int(ds.attrs["runs_reused"]),
               "complete": bool(complete), "seed": ds.attrs.get("seed"), "wall_time_s": wall,
               "units": {"link_pass_frequency": "Hz", "delta_mean": "m", "delta_ripple": "m",
                         "peak_link_tension": "N", "wall_time": "s"},
               "run_results": runs}
    if a.json:
        _print_json("sweep", summary)
    else:
        print(f"scene     {a.scene} ({ds.attrs['sweep']}: {', '.join(f'{k}={v}' for k, v in summary['dims'].items())})")
        print(f"output    {summary['output']}" + ("" if complete else " (incomplete: run the same command to resume)"))
        print(f"runs      {summary['runs']}: {summary['ok']} ok, {summary['failed']} failed, "
              f"{summary['invalid']} invalid"
              + (f", {summary['pending']} pending" if summary["pending"] else "")
              + f" ({summary['computed']} computed now, {summary['reused']} from the store)")
        print(f"wall time {wall:.1f} s")
        shown = runs[:40]
        print(_table([[*(f"{v:.6g}" if isinstance(v, float) else v for v in r["values"].values()), r["status"],
                       f"{r['link_pass_frequency']:.5f}", f"{1e3 * r['delta_mean']:.4f}",
                       f"{1e3 * r['delta_ripple']:.4f}",
                       f"{r['peak_link_tension']:.1f}", f"{r['wall_time']:.2f}"] for r in shown],
                     (*keys, "status", "link pass [Hz]", "delta [mm]", "ripple [mm]", "peak tension [N]", "wall [s]")))
        if len(runs) > len(shown):
            print(f"... {len(runs) - len(shown)} more runs in {summary['output']}")
        for r in runs:
            if r["error"]:
                _msg(f"run {', '.join(f'{k}={v}' for k, v in r['values'].items())}: {r['status']}: {r['error']}")
    return 0


def _weightings(text):
    """``Wk`` (every axis) or ``x=Wd,y=Wd,z=Wk`` -> {axis: name} (None: the defaults)."""
    if not text:
        return None
    from vibkit.signal.weighting import get_weighting

    out = {}
    for item in text.split(","):
        if "=" in item:
            k, v = (p.strip() for p in item.split("=", 1))
            if k.lower() not in ("x", "y", "z", "tangential"):
                raise CLIError(f"--weighting: axis {k!r} must be x, y, z or tangential (in {text!r})")
            out[k.lower()] = get_weighting(v).name
        else:
            name = get_weighting(item).name
            out.update({k: name for k in ("x", "y", "z", "tangential")})
    return out


def _ride_rows(rq):
    return [[a.axis, a.channel, a.weighting, f"{a.weighted.max:.4g}", f"{a.weighted.a95:.4g}", f"{a.weighted.rms:.4g}",
             f"{a.lowpass.max:.4g}", f"{a.lowpass.a95:.4g}"] for a in rq.axes]


def _cmd_ride(a):
    from vibkit.diagnose.ride import parse_channels, parse_segment, ride_quality_from_recording, simulate_ride

    segment = parse_segment(a.segment) if a.segment else None
    weightings = _weightings(a.weighting)
    if not os.path.exists(a.input):
        raise CLIError(f"{a.input}: file not found (expected a recording or a scene .toml)")
    is_scene = a.input.lower().endswith(".toml")
    if is_scene and a.channels:
        raise CLIError("--channels applies to a recording, not to a scene")
    if is_scene and a.scene:
        raise CLIError("--scene compares a recording with a scene; the input is already a scene")
    if is_scene:
        rq = simulate_ride(a.input, duration=a.duration, segment=segment, weightings=weightings,
                           progress=sys.stderr.isatty())
    else:
        rq = ride_quality_from_recording(a.input, channels=parse_channels(a.channels) if a.channels else None,
                                         segment=segment, weightings=weightings, sample_rate=a.sample_rate)
    sim = None
    if a.scene:
        sim = simulate_ride(a.scene, duration=a.duration, weightings=weightings, progress=sys.stderr.isatty())
    if a.json:
        d = rq.as_dict()
        if sim is not None:
            d["simulation"] = sim.as_dict()
        _print_json("ride", d)
    else:
        head = ("axis", "channel", "weighting", "max pk-pk", "A95", "r.m.s.", "10 Hz max pk-pk", "10 Hz A95")
        for r in (rq, sim):
            if r is None:
                continue
            seg = r.segment
            print(f"{r.source} ({r.kind}, {r.fs:.6g} Hz): ride {seg.start_s:.2f}-{seg.end_s:.2f} s "
                  f"({seg.duration_s:.2f} s, {seg.method})" +
                  (f", speed {r.speed_m_s:.3g} m/s" if r.speed_m_s else ""))
            print("step vibration [m/s^2]: weighted (ISO 2631-1) and 0.4-10 Hz unweighted")
            print(_table(_ride_rows(r), head))
            print()
        for r in (rq, sim):
            for n in ([] if r is None else r.notes + ([r.segment.note] if r.segment.note else [])):
                _msg(f"note: {n}")
    return 0


def _workers(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of workers, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected 0 (no Dask) or more workers, got {text!r}")
    return v


def _fleet_db(a, *, create=True):
    from vibkit.fleet.history import FleetDB

    return FleetDB(a.db, create=create)


def _fmt_measurement(m):
    return (f"#{m.id} unit {m.unit} {m.date_utc[:10]}: "
            f"pitch {1000 * m.pitch_m:.3f} +- {1000 * m.pitch_sigma_m:.3f} mm, "
            f"elongation {m.elongation_percent:+.3f} +- {m.elongation_sigma_percent:.3f} % "
            f"(SNR {'n/a' if m.snr_db is None else f'{m.snr_db:.0f} dB'})")


def _cmd_fleet_add(a):
    sigma = _speed_sigma(a.speed_uncertainty, a.speed) if a.speed_uncertainty else 0.0
    with _fleet_db(a) as db:
        m = db.add(a.recording, unit=a.unit, speed=a.speed, speed_sigma=sigma, date=a.date,
                   nominal_pitch=a.nominal_pitch, channel=a.channel)
        path = db.path
    if a.json:
        _print_json("fleet.add", {"database": path, "measurement": m.as_dict()})
    else:
        print(f"stored {_fmt_measurement(m)}")
        _msg(f"note: database {path}; date from {m.date_source}")
    for w in m.warnings:
        _msg(f"warning: {w}")
    return 0


def _cmd_fleet_scan(a):
    def failed(name, why):
        _msg(f"vibkit fleet scan: failed: {why if why.startswith(name) else f'{name}: {why}'}")

    with _fleet_db(a) as db:
        res = db.scan(a.directory, a.catalogue, scheduler=a.scheduler, n_workers=a.workers or None,
                      parallel=a.workers != 0, on_failure=failed, progress=sys.stderr.isatty())
        path = db.path
    for n in res.notes:
        _msg(f"note: {n}")
    if a.json:
        _print_json("fleet.scan", {"database": path, **res.as_dict()})
    else:
        print(f"added {len(res.added)}, skipped {len(res.skipped)} (already stored), failed {len(res.failed)}"
              f"  [database {path}]")
        for m in res.added:
            print(f"  added {_fmt_measurement(m)}")
    if not res.added and not res.skipped:
        raise CLIError(f"nothing added from {a.directory}: {len(res.failed)} file(s) failed"
                       if res.failed else f"{a.directory}: no recording found (suffixes .csv, .txt, .nc, .mseed ...)")
    return 0


def _fmt_forecast(f):
    if f.status == "reached":
        return "reached"
    if f.status == "forecast":
        if f.date_utc is None:
            return "after 9999"
        lo, hi = (f.earliest_utc or "?")[:7], (f.latest_utc or "after 9999")[:7]
        return f"{f.date_utc[:7]} ({lo}..{hi})"
    if f.status == "not before":
        return f"not before {f.earliest_utc[:7]}" if f.earliest_utc else "-"
    return "-"


def _cmd_fleet_status(a):
    with _fleet_db(a, create=False) as db:
        trends = db.status(limits_percent=a.limits, units=a.unit or None)
        path = db.path
    if a.unit and not trends:
        raise CLIError(f"{path}: no measurement of unit(s) {', '.join(a.unit)}")
    if a.json:
        _print_json("fleet.status", {"database": path, "limits_percent": list(a.limits),
                                     "units": [t.as_dict() for t in trends]})
        return 0
    if not trends:
        print(f"{path}: no measurement stored yet")
        return 0
    rows = []
    for t in trends:
        slope = "-" if t.slope_percent_per_year is None else \
            f"{t.slope_percent_per_year:+.3f} +- {t.slope_sigma_percent_per_year:.3f}"
        rows.append([t.rank, t.unit, t.n_measurements, t.latest_date_utc[:10],
                     f"{t.latest_elongation_percent:+.3f} +- {t.latest_elongation_sigma_percent:.3f}", t.latest_verdict,
                     slope] + [_fmt_forecast(f) for f in t.forecasts])
    print(_table(rows, ["rank", "unit", "n", "latest", "elongation [%]", "verdict", "trend [%/year]"]
                 + [f"{f.limit_percent:g} % on" for f in trends[0].forecasts]))
    _msg("note: forecast dates with their 2-sigma interval (year-month); 'not before' where the trend is not "
         "significantly positive")
    return 0


def _cmd_fleet_report(a):
    from vibkit.diagnose.report import write_fleet_report

    _check_output(a.output, [], a.force)
    with _fleet_db(a, create=False) as db:
        _check_output(a.output, [db.path], a.force)
        trends = db.status(limits_percent=a.limits)
        meas = db.measurements()
        path = db.path
    if not trends:
        raise CLIError(f"{path}: no measurement stored yet; nothing to report")
    rep = write_fleet_report(trends, meas, a.output, limits_percent=a.limits, database=path)
    if a.json:
        _print_json("fleet.report", {"output": rep.path, "database": path, "pages": [t for t, _ in rep.pages],
                                     "units": len(trends), "units_drawn": rep.summary["units_drawn"]})
    else:
        print(f"wrote {rep.path} (1 page, {rep.summary['units_drawn']} of {len(trends)} units drawn)")
    return 0


# ------------------------------------------------------------------------------------------------ parser

_EPILOG = {
    "simulate": "example:\n  vibkit simulate sim/leon.toml -o reports/leon.nc --duration 10",
    "spectrum": "example:\n  vibkit spectrum data/field/leon-tensioner.csv --band 2.5:6 --json",
    "pitch": "examples:\n  vibkit pitch data/field/leon-tensioner.csv --speed 0.49 --speed-uncertainty 0.1% "
             "--nominal-pitch 0.13333\n  vibkit pitch logger.txt --sample-rate 2050 --speed 0.52 --json",
    "compare": "example:\n  vibkit compare data/field/leon-tensioner.csv sim/leon.toml --duration 10",
    "report": "example:\n  vibkit report data/field/leon-tensioner.csv --scene sim/leon.toml -o reports/leon.pdf",
    "ride": "examples:\n  vibkit ride data/field/layouts/phyphox.csv --segment 0.5:3 --json\n  vibkit ride sim/las-palmas.toml --duration 15\n"
            "  vibkit ride step.csv --scene sim/las-palmas.toml --segment 3:25 --weighting x=Wd,y=Wd,z=Wk",
    "bench": "example:\n  vibkit bench --quick --only signal",
    "sweep": "examples:\n  vibkit sweep sim/thesis-forward.toml --vary chain.link_pitch=0.1333:0.1373:9 "
             "--vary effects.contact.stiffness=1e5,1e6,1e7 --duration 10 -o sweep.zarr\n"
             "  vibkit sweep sim/leon.toml --vary motion.speed=0.45:0.55 --samples 50 --seed 1 --keep delta -o mc.zarr\n"
             "re-running the same command resumes an interrupted sweep; xarray.open_zarr('sweep.zarr') reads it",
    "fleet": ("examples:\n  vibkit fleet add E07-2026-11-23.csv --unit E07 --speed 0.5 --nominal-pitch 0.13333\n"
              "  vibkit fleet scan visits/ --catalogue visits/units.csv --workers 2\n"
              "  vibkit fleet status --json\n  vibkit fleet report -o fleet.pdf\n"
              "database: --db PATH (or sqlite:///PATH), else $VIBKIT_FLEET_DB, else ./vibkit-fleet.sqlite\n"
              "catalogue columns: file (name or glob), unit, speed_m_s, date (ISO 8601; empty: the recording's "
              "start time),\n  nominal_pitch_m (empty: the unit's), optional speed_sigma_m_s, channel"),
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
            sp.add_argument("--channel", help="channel to analyse, named as the file writes it or as vibkit does "
                                                   "(default: the first that is not a sample counter)")
            sp.add_argument("--sample-rate", type=_positive, help="sample rate for files without time [Hz]")
        if rec and not sp.prog.endswith(" report"):  # report reads the file itself (vibkit.diagnose.report)
            sp.add_argument("--time-column", metavar="NAME|INDEX|none",
                            help="time column by name or 0-based index; 'none': the file has no time column")
            sp.add_argument("--time-unit", choices=("s", "ms", "us", "ns", "min", "h"),
                            help="unit of a numeric time column (overrides the header and the epoch guess)")
            sp.add_argument("--repair-time", action="store_true",
                            help="undo a clock set back at midnight or by a DST change, sort other backward "
                                 "rows and drop repeated stamps instead of refusing the file (in the history)")
        sp.add_argument("--json", action="store_true", help="JSON on stdout (with a schema version)")

    s = add("simulate", "simulate a scene and write the result (netCDF4/HDF5)")
    s.add_argument("scene", help="scene file (.toml)")
    s.add_argument("-o", "--output", required=True, help="result file to write (.nc); a new path unless --force")
    s.add_argument("--force", "--overwrite", dest="force", action="store_true",
                   help="replace an existing result file (never an input, a link, a device or a read-only file)")
    s.add_argument("--duration", type=_positive, help="override the scene's duration [s] (kinematics: [m])")
    s.add_argument("--max-result-bytes", type=_byte_size, metavar="SIZE",
                   help="refuse runs whose result would be larger, e.g. 500MB (default: the scene's "
                        "[solver] max_result_bytes, $VIBKIT_MAX_RESULT_BYTES or 2GiB; 0: no limit)")
    s.add_argument("--max-wall-time", type=_seconds_or_none, metavar="SECONDS",
                   help="stop a forward integration after this long (default: the scene's [solver] max_wall_time, "
                        "$VIBKIT_MAX_WALL_TIME or 600 s; 0: no limit)")
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
    s.add_argument("--speed-uncertainty", type=_speed_uncertainty,
                   help="speed standard deviation, in m/s or in %% (e.g. 0.1%%)")
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
    s.add_argument("-o", "--output", required=True, help="PDF to write; a new path unless --force")
    s.add_argument("--force", "--overwrite", dest="force", action="store_true",
                   help="replace an existing PDF (never an input, a link, a device or a read-only file)")
    s.add_argument("--speed", type=_positive, help="chain speed [m/s] (default: recording's or scene's)")
    s.add_argument("--speed-uncertainty", type=_speed_uncertainty, help="speed standard deviation, in m/s or in %%")
    s.add_argument("--nominal-pitch", type=_positive, help="nominal link pitch [m] (default: the scene's)")
    s.add_argument("--limits", type=_limits, default=(1.5, 2.0, 3.0), help="elongation limits [%%]")
    s.add_argument("--band", type=_band, help="link-pass search band LOW:HIGH [Hz]")
    s.add_argument("--duration", type=_positive, help="simulated time [s] (default: the scene's)")
    s.set_defaults(func=_cmd_report)

    s = add("sweep", "run a scene over a grid (or random draws) of its keys on Dask; results to Zarr")
    s.add_argument("scene", help="scene file (.toml)")
    s.add_argument("--vary", action="append", type=_vary, required=True, metavar="KEY=SPEC",
                   help="a dotted scene key and its values: A:B:N (linspace), a,b,c (list), A:B (a range, "
                        "with --samples); repeat for more keys")
    s.add_argument("-o", "--output", required=True, help="Zarr directory to write (re-run to resume)")
    s.add_argument("--samples", type=int, help="Monte Carlo: draw this many scenes (uniformly in each A:B)")
    s.add_argument("--seed", type=int, help="seed of the Monte Carlo draws (default 0)")
    s.add_argument("--keep", action="append", metavar="OUTPUT",
                   help="keep this output's full series (e.g. delta); repeat for more")
    s.add_argument("--settle", type=float, help="start-up left out of the summaries [s] (default: a quarter "
                                                "of a forward run)")
    s.add_argument("--duration", type=_positive, help="override every run's duration [s] (kinematics: [m])")
    s.add_argument("--scheduler", help="address of a running Dask scheduler (default: Dask's configuration, "
                                       "else a local cluster)")
    s.add_argument("--workers", type=int, help="worker processes of the local cluster (default: one per core)")
    s.add_argument("--max-runs", type=int, help="compute at most this many runs now (resume later)")
    s.add_argument("--force", action="store_true", help="discard a store at -o that holds a different sweep")
    s.add_argument("--quiet", action="store_true", help="no progress on stderr")
    s.add_argument("--json", action="store_true", help="JSON on stdout (with a schema version)")
    s.set_defaults(func=_cmd_sweep)
    s = add("ride", "ride quality of a step-riding accelerometer: ISO 2631-1 weighted max pk-pk, A95, r.m.s.")
    s.add_argument("input", metavar="RECORDING_OR_SCENE", help="recording file, or a scene .toml (simulated)")
    s.add_argument("--channels", help="recording channels for x,y,z (travel, lateral, vertical; - skips one), "
                   "or AXIS=NAME pairs (default: names ending in x, y, z); write --channels=-,-,az when x is skipped")
    s.add_argument("--segment", help="ride segment START:END [s] from the first sample (default: detected)")
    s.add_argument("--weighting", help="Wk, Wd ... for every axis, or x=Wd,y=Wd,z=Wk (the default)")
    s.add_argument("--scene", help="also simulate this scene's step and report it next to the recording")
    s.add_argument("--duration", type=_positive, help="simulated time [s] (default: the scene's)")
    s.add_argument("--sample-rate", type=_positive, help="sample rate for files without time [Hz]")
    s.add_argument("--json", action="store_true", help="JSON on stdout (with a schema version)")
    s.set_defaults(func=_cmd_ride)
    s = add("fleet", "measurement history of a fleet of escalators: add, scan, status, report")
    fsub = s.add_subparsers(dest="fleet_command", metavar="SUBCOMMAND", required=True)

    def fleet_sub(name, help_):
        sp = fsub.add_parser(name, help=help_, description=help_, epilog=_EPILOG["fleet"],
                             formatter_class=argparse.RawDescriptionHelpFormatter)
        sp.add_argument("--db", help="fleet database: a path or sqlite:///PATH (default $VIBKIT_FLEET_DB, "
                        "else ./vibkit-fleet.sqlite)")
        sp.add_argument("--json", action="store_true", help="JSON on stdout (with a schema version)")
        return sp

    f = fleet_sub("add", "analyse one recording and store its pitch and elongation")
    f.add_argument("recording", help="recording file (CSV/text, miniSEED ..., netCDF)")
    f.add_argument("--unit", required=True, help="escalator identifier")
    f.add_argument("--speed", type=_positive, required=True, help="chain speed measured on the steps [m/s]")
    f.add_argument("--speed-uncertainty", help="speed standard deviation, in m/s or in %% (e.g. 0.1%%)")
    f.add_argument("--date", help="measurement date, ISO 8601 (default: the recording's start time)")
    f.add_argument("--nominal-pitch", type=_positive, help="nominal link pitch [m] (required for a new unit)")
    f.add_argument("--channel", help="channel to analyse (default: the first)")
    f.set_defaults(func=_cmd_fleet_add)

    f = fleet_sub("scan", "add every recording of a folder that a catalogue describes, in parallel (Dask)")
    f.add_argument("directory", metavar="DIR", help="folder of recordings (searched recursively)")
    f.add_argument("--catalogue", required=True, help="CSV: file, unit, speed_m_s, date, nominal_pitch_m")
    f.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    f.add_argument("--workers", type=_workers, help="worker processes of the local cluster (default: one per "
                   "core; 0: analyse in this process)")
    f.set_defaults(func=_cmd_fleet_scan)

    f = fleet_sub("status", "per unit: latest elongation, trend [%/year] and limit forecasts, most urgent first")
    f.add_argument("--unit", action="append", help="only this unit (repeatable)")
    f.add_argument("--limits", type=_limits, default=(1.5, 2.0, 3.0),
                   help="elongation limits watch,plan,replace [%%] (default 1.5,2,3)")
    f.set_defaults(func=_cmd_fleet_status)

    f = fleet_sub("report", "one PDF page: elongation against date per unit, with the limits")
    f.add_argument("-o", "--output", required=True, help="PDF to write")
    f.add_argument("--force", action="store_true", help="replace an existing output file")
    f.add_argument("--limits", type=_limits, default=(1.5, 2.0, 3.0), help="elongation limits [%%]")
    f.set_defaults(func=_cmd_fleet_report)

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
    # parse first: --help and --version import nothing heavy and compile nothing
    args = _parser().parse_args(argv)
    from vibkit.runtime.safe_output import Interrupted, handle_termination

    try:
        with handle_termination():  # SIGTERM runs the same clean-up as Ctrl-C
            return int(args.func(args))
    except Interrupted as exc:
        _msg(f"vibkit {args.command}: interrupted (signal {exc.signum}); nothing was written")
        return 128 + exc.signum
    except KeyboardInterrupt:
        _msg(f"vibkit {args.command}: interrupted; nothing was written")
        return 130
    except Exception as exc:
        if not _is_user_error(exc):
            raise
        text = " ".join(str(exc).split()) or type(exc).__name__
        if isinstance(exc, OSError) and getattr(exc, "strerror", None):
            where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
            text = f"{where}{exc.strerror}" + (" (the disk is full; nothing was written)"
                                              if exc.errno == errno.ENOSPC else "")
        prefix = "\033[31merror\033[0m" if _color() else "error"
        _msg(f"vibkit {args.command}: {prefix}: {text}")
        return 1


def _is_user_error(exc) -> bool:
    """A bad input, a failed run or a refused output: reported in one line (exit 1), not a traceback."""
    if isinstance(exc, (ValueError, OSError, MemoryError)):
        return True
    integrate = sys.modules.get("vibkit.analyses.integrate")  # only if it was imported can it have raised
    return integrate is not None and isinstance(exc, integrate.IntegrationError)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
