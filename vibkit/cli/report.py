"""``vibkit report``: the multi-page PDF diagnostic report of a recording."""

from __future__ import annotations

import dataclasses

from vibkit.diagnose.rounding import fmt_pm, fmt_value
from vibkit.runtime.frozen_imports import import_frozen
from vibkit.runtime.report_options import ReportOptions

from .options import (
    CHANNEL_EVERY,
    _profile_of,
    add_command,
    add_escalator,
    add_force_overwrite,
    add_json,
    add_limits,
    add_marker,
    add_nominal_pitch,
    add_recording,
    add_speed,
    add_speed_uncertainty,
    band,
    positive,
    reader_options,
    segment_of,
    speed_sigma,
)
from .output import check_output, is_stdout, msg, output_path, print_json, table

#: what ``run`` imports once its arguments are checked: where the process is the command's, imported with the
#: collector paused and then frozen (:func:`vibkit.runtime.frozen_imports.import_frozen`); matplotlib's PDF backend is
#: what the pages are saved with
LIBRARY = ("vibkit.diagnose.report", "matplotlib.pyplot", "matplotlib.backends.backend_pdf")

EPILOG = (
    "example:\n  vibkit report data/field/leon-tensioner.csv --scene sim/leon.toml --date 2020-02-14 \\\n"
    "      -o out/leon.pdf"
)


def add_parser(subparsers):
    s = add_command(subparsers, "report", "write the multi-page PDF diagnostic report of a recording", EPILOG)
    add_recording(s, channel_default=CHANNEL_EVERY)
    add_json(s)
    add_escalator(s)
    _add_declared(s, "scene")
    s.add_argument("-o", "--output", required=True, help="PDF to write; a new path unless --force; '-': stdout")
    add_force_overwrite(s, "PDF")
    add_speed(
        s,
        "the --escalator profile's, else the recording's, else the scene's",
        "chain speed measured on the steps, the one speed of every page",
    )
    add_speed_uncertainty(s)
    add_marker(s)
    add_nominal_pitch(s, "the --escalator profile's, else the scene's")
    add_limits(s)
    for name in ("band", "duration", "date"):
        _add_declared(s, name)
    s.set_defaults(func=run)
    return s


def _add_declared(s, name):
    """The flag of option ``name`` that the report declares itself (its field's ``help``; the others are flags every
    command shares, :mod:`vibkit.cli.options`)."""
    meta = {f.name: f.metadata for f in dataclasses.fields(ReportOptions)}[name]
    s.add_argument(meta["flag"], type=_PARSE[meta["parse"]], help=meta["help"])


#: how a flag the report declares is read (ReportOptions' ``parse``): None, the text as given
_PARSE = {"band": band, "positive": positive, None: None}


def options_of(a, profile) -> ReportOptions:
    """The report's options from the parsed flags: each option that has a flag (``flag`` of its field), as
    ``_FROM_FLAG`` reads it where it is not the flag's value as parsed; the reader's flags as ``read_options``."""
    given = {}
    for f in dataclasses.fields(ReportOptions):
        flag = f.metadata["flag"]
        if flag is not None and flag != "--sample-rate":  # the sample rate reaches the reader with its other flags
            read = _FROM_FLAG.get(f.name)
            given[f.name] = read(a, profile) if read else getattr(a, flag.lstrip("-").replace("-", "_"))
    return ReportOptions(**given, read_options=reader_options(a), progress=True)


def _speed_sigma(a, profile):
    text = a.speed_uncertainty
    return None if text is None else text if text.strip().endswith("%") else speed_sigma(text, 1.0)


#: the options that a flag gives other than as its parsed value
_FROM_FLAG = {
    "scene": lambda a, profile: a.scene if a.scene or profile is None else profile.scene("forward", a.duration),
    "speed_sigma": _speed_sigma,
    "profile": lambda a, profile: profile,
    "segment": lambda a, profile: segment_of(a),
}


#: summary keys whose value is rounded to their sigma's two significant digits
_SIGMA_OF = {
    "link_pass_hz": "fundamental_sigma_hz",
    "pitch_m": "pitch_sigma_m",
    "elongation_percent": "elongation_sigma_percent",
    "speed_m_s": "speed_sigma_m_s",
}


def _shown(key, value, summary):
    """A summary value as the table prints it: to its sigma when it has one, else 6 significant digits."""
    if value is None:
        return "not stated"
    if key == "flagged_links_detail":
        return "; ".join(_flag_text(f) for f in value) or "none"
    if isinstance(value, (list, tuple)):
        return ", ".join(str(v) for v in value) or "none"
    if not isinstance(value, float):
        return value
    if key == "score":
        return f"{value:.3f}"  # a similarity between 0 and 1: 2.4e-38 is 0.000
    if "sigma" in key:
        return f"{value:#.2g}"  # two significant digits (0.00010, not 0.0001), the rule of every +-
    if key in ("rms", "peak_to_peak") and summary.get("units"):
        return f"{value:.3g} {summary['units']}"  # of the channel, in its units
    sigma = summary.get(_SIGMA_OF.get(key, ""))
    if sigma:
        return fmt_value(value, sigma)
    # without a sigma (a speed whose uncertainty is not stated) as `pitch` prints them: 0.01 % and 0.01 mm
    return {"elongation_percent": f"{value:+.2f}", "pitch_m": f"{value:.5f}"}.get(key, f"{value:.6g}")


def _flag_text(f):
    """One flagged link as the table prints it: ``210 (or 28): +0.7907 +- 0.0084 mm, loops 1,2,3``."""
    link = str(f["link"]) + (f" (or {', '.join(map(str, f['alternatives']))})" if f.get("alternatives") else "")
    excess = (
        ""
        if f.get("excess_pitch_mm") is None
        else ": " + fmt_pm(f["excess_pitch_mm"], f.get("sigma_mm"), "mm", sign=True)
    )
    loops = f.get("loops") or []
    return link + excess + (f", loops {','.join(map(str, loops))}" if loops else "")


def run(a):
    check_output(a.output, [a.recording, a.scene], a.force, json_flag=a.json)
    with output_path(a.output, ".pdf") as target:  # '-o -': written to a temporary file, then to stdout
        return _run(a, target)


def _run(a, target):
    if getattr(a, "own_process", False):
        import_frozen(LIBRARY)
    from vibkit.diagnose.report import write_report

    profile = _profile_of(a)
    if a.date is not None:  # before the recording is read: the date validator every command shares
        from vibkit.runtime.dates import parse_iso_date

        parse_iso_date(a.date, "--date")
    opts = options_of(a, profile)
    rep = write_report(a.recording, target, overwrite=a.force, **opts.as_dict())
    if a.json:
        print_json(
            "report",
            {
                "output": a.output if is_stdout(a.output) else rep.path,
                "pages": [t for t, _ in rep.pages],
                "summary": rep.summary,
            },
        )
    else:
        msg(f"vibkit report: wrote {'<stdout>' if is_stdout(a.output) else rep.path} ({len(rep.pages)} pages)")
        print(table([[k, _shown(k, v, rep.summary)] for k, v in rep.summary.items()]))
    return 0
