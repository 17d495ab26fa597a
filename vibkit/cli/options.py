"""Option types, validators and the option groups that several commands share.

A bad option value is a usage error (argparse, exit 2), except where a command checks it later.
Each shared option is defined here once; a command adds the groups it takes.
"""

from __future__ import annotations

import argparse
import math
import re

from vibkit.diagnose.decision import DEFAULT_LIMITS_PERCENT
from vibkit.runtime.budget import parse_bytes
from vibkit.runtime.reader_options import READER_OPTIONS, option

from .output import CLIError, msg

JSON_HELP = "JSON on stdout (with a schema version)"
DEFAULT_LIMITS = DEFAULT_LIMITS_PERCENT  # the one default (vibkit.diagnose.decision)

# ------------------------------------------------------------------------------------------ types


def band(text):
    try:
        lo, hi = (float(v) for v in text.replace(",", ":").split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LOW:HIGH in Hz (e.g. 2.5:6), got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise argparse.ArgumentTypeError(f"expected finite 0 < LOW < HIGH in Hz, got {text!r}")
    return (lo, hi)


#: sample rates a recording may be given [Hz]: a chain's link pass (a few Hz) needs more than 1 Hz,
#: no accelerometer logger writes more than 10 MHz
SAMPLE_RATE_RANGE_HZ = (1.0, 1e7)


def sample_rate(text):
    """--sample-rate: a number of Hz within :data:`SAMPLE_RATE_RANGE_HZ` (1e308 would overflow every filter)."""
    lo, hi = SAMPLE_RATE_RANGE_HZ
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a sample rate in Hz such as 200, got {text!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise argparse.ArgumentTypeError(f"expected a sample rate of {lo:g} Hz to {hi:g} Hz, got {text!r}")
    return v


def harmonics(text):
    """--harmonics: a whole number of harmonics, 1 to 50."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of harmonics such as 5, got {text!r}") from None
    if not 1 <= v <= 50:
        raise argparse.ArgumentTypeError(f"expected 1 to 50 harmonics, got {text!r}")
    return v


def limits(text):
    try:
        vals = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three percentages like 1.5,2,3, got {text!r}") from None
    if len(vals) != 3 or not 0 < vals[0] < vals[1] < vals[2]:
        raise argparse.ArgumentTypeError(f"expected three increasing positive percentages, got {text!r}")
    return vals


def positive(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


_LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254, '"': 0.0254}
_SPEED_UNITS = {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "m/min": 1 / 60, "ft/min": 0.3048 / 60, "fpm": 0.3048 / 60}
#: a chain pitch given as a bare number must lie here [m]; a speed here [m/s] (escalators and moving walks)
PITCH_RANGE_M = (0.02, 0.5)
SPEED_RANGE_M_S = (0.05, 3.0)


def _quantity(text, units, what, example):
    t = str(text).strip().replace(" ", "")
    for u in sorted(units, key=len, reverse=True):
        if t.lower().endswith(u):
            num, factor, unit = t[: -len(u)], units[u], u
            break
    else:
        num, factor, unit = t, None, None
    try:
        v = float(num)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what} like {example}, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        noun = what.split(" ", 1)[1] if what.startswith(("a ", "an ")) else what  # "a chain speed": no "a a"
        raise argparse.ArgumentTypeError(f"expected a positive {noun}, got {text!r}")
    return v, factor, unit


def pitch_length(text):
    """--nominal-pitch: metres, or with a unit (``133.33mm``, ``13.333cm``, ``0.13333m``, ``5.25in``).

    A bare number outside 0.02-0.5 m is a usage error that says what was probably meant
    (``133.33`` -> ``133.33mm``)."""
    v, factor, unit = _quantity(text, _LENGTH_UNITS, "a link pitch", "0.13333 (m) or 133.33mm")
    m = v * (factor or 1.0)
    lo, hi = PITCH_RANGE_M
    if not lo <= m <= hi:
        hint = ""
        if factor is None and lo <= v * 1e-3 <= hi:
            hint = f"; did you mean {text.strip()}mm ({v * 1e-3:.6g} m)?"
        elif factor is None and lo <= v * 1e-2 <= hi:
            hint = f"; did you mean {text.strip()}cm ({v * 1e-2:.6g} m)?"
        raise argparse.ArgumentTypeError(
            f"{text!r} is {m:g} m, not a step-chain pitch ({lo:g}-{hi:g} m){hint} "
            "(a bare number is in metres; write the unit: 133.33mm)"
        )
    return m


def chain_speed(text):
    """--speed: m/s, or with a unit (``0.49m/s``, ``49cm/s``, ``29.4m/min``, ``96.5ft/min``).

    A bare number outside 0.05-3 m/s is a usage error that says what was probably meant
    (``49`` -> ``49cm/s``)."""
    v, factor, unit = _quantity(text, _SPEED_UNITS, "a chain speed", "0.49 (m/s) or 49cm/s")
    ms = v * (factor or 1.0)
    lo, hi = SPEED_RANGE_M_S
    if not lo <= ms <= hi:
        hint = ""
        for u in ("cm/s", "m/min", "ft/min", "mm/s"):
            if factor is None and lo <= v * _SPEED_UNITS[u] <= 1.0:
                hint = f"; did you mean {text.strip()}{u} ({v * _SPEED_UNITS[u]:.4g} m/s)?"
                break
        raise argparse.ArgumentTypeError(
            f"{text!r} is {ms:g} m/s, not an escalator or moving-walk speed "
            f"({lo:g}-{hi:g} m/s){hint} (a bare number is in m/s; write the unit: 49cm/s)"
        )
    return ms


def _whole_number(text, noun, least, at_least):
    """An argparse type: ``text`` as an integer of at least ``least``, else an error naming ``noun`` (the count's
    name) or ``at_least`` (what has at least ``least``)."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of {noun}, got {text!r}") from None
    if v < least:
        raise argparse.ArgumentTypeError(f"{at_least}, got {text!r}")
    return v


def teeth(text):
    return _whole_number(text, "sprocket teeth", 3, "a sprocket has at least 3 teeth")


#: the largest speed uncertainty taken, as a fraction of the speed (the fleet's stated range)
SPEED_SIGMA_MAX_FRACTION = 0.2


def speed_sigma(text, speed):
    """--speed-uncertainty (m/s, or a percentage of ``speed``) -> m/s; a bad value is a CLIError (exit 1)."""
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
    if t.endswith("%") and v > SPEED_SIGMA_MAX_FRACTION * speed:
        # a speed known to worse than a fifth gives no pitch worth the name (and 1e308% no number at all)
        raise CLIError(
            f"--speed-uncertainty {text} is more than {100 * SPEED_SIGMA_MAX_FRACTION:g} % of the speed; expected "
            f"0-{100 * SPEED_SIGMA_MAX_FRACTION:g} % (a step timing is good to a few %), e.g. 0.5%"
        )
    if not t.endswith("%") and v >= 0.1 * speed:
        # a bare number is m/s: 5 is 5 m/s, ten times an escalator's speed; no tachometer is that bad
        raise CLIError(
            f"--speed-uncertainty {text} is {v:g} m/s, {100 * v / speed:.3g} % of the speed {speed:g} m/s: a bare "
            f"number is in m/s; did you mean {t}%?"
        )
    return v


def speed_uncertainty(text):
    """argparse type of --speed-uncertainty: m/s or a percentage; a bad value is a usage error (exit 2)."""
    try:
        speed_sigma(text, 1.0)
    except CLIError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None
    return text


def byte_size(text):
    try:
        return parse_bytes(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def seconds_or_none(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if math.isnan(v) or v < 0:
        raise argparse.ArgumentTypeError(f"expected a number of seconds >= 0 (0: no limit), got {text!r}")
    return math.inf if v == 0 else v


def workers(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of workers, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected 0 (no Dask) or more workers, got {text!r}")
    return v


# ---------------------------------------------------------------------------------- option groups


def add_command(subparsers, name, help_, epilog):
    """Register one command (or fleet subcommand): its one-line help is also its description.

    ``help_`` is plain text: argparse %-formats a subcommand's help in its parent's listing, so a
    ``%`` in it is escaped here (the description and the epilog are not %-formatted).
    """
    import textwrap

    return subparsers.add_parser(
        name,
        help=help_.replace("%", "%%"),
        description=textwrap.fill(help_, 99),
        epilog=epilog,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def add_json(sp, help_=JSON_HELP):
    sp.add_argument("--json", action="store_true", help=help_)


def add_sample_rate(sp):
    sp.add_argument("--sample-rate", type=sample_rate, help=option("sample_rate").help)


#: what each command analyses without --channel (the end of --channel's help)
CHANNEL_FIRST = "the first that is not a sample counter"
CHANNEL_EVERY = "every vibration channel, the numbers from the one with the most evidence once the others agree"
CHANNEL_LENGTH = "the first in a length unit, a tensioner displacement; else the first vibration channel"


def add_channel(sp, default=CHANNEL_FIRST):
    """--channel; ``default`` says what the command analyses without it."""
    sp.add_argument("--channel", help=f"{option('channel').help} (default: {default})")


#: the reader's options: Python argument of :func:`vibkit.read_recording` -> command-line flag (declared once, in
#: :data:`vibkit.io.reader_options.READER_OPTIONS`)
READER_FLAGS = {o.name: o.flag for o in READER_OPTIONS if o.flag}
_DELIMS = {
    "comma": ",",
    ",": ",",
    "semicolon": ";",
    ";": ";",
    "tab": "\t",
    "\\t": "\t",
    "pipe": "|",
    "|": "|",
    "space": " ",
    "whitespace": " ",
}


def units_option(text):
    """--units: one unit for every channel (``g``, ``counts``, ``g/2048``) or NAME=UNIT pairs (``az=g,ax=m/s^2``)."""
    t = text.strip()
    if not t:
        raise argparse.ArgumentTypeError("expected a unit (e.g. g, m/s^2, g/2048) or NAME=UNIT,NAME=UNIT")
    if "=" not in t:
        return t
    out = {}
    for item in t.split(","):
        k, sep, v = item.partition("=")
        if not sep or not k.strip() or not v.strip():
            raise argparse.ArgumentTypeError(f"expected NAME=UNIT pairs separated by commas, got {text!r}")
        out[k.strip()] = v.strip()
    return out


def delimiter_option(text):
    d = _DELIMS.get(text.strip().lower() if text.strip() else text)
    if d is None:
        raise argparse.ArgumentTypeError(f"expected comma, semicolon, tab, pipe or whitespace, got {text!r}")
    return d


def add_recording(
    sp, *, positional=True, channel=True, channel_default=CHANNEL_FIRST, with_segment=True, segment_help=None
):
    """The RECORDING argument and the recording reader's options, the same for every command that reads one.

    ``positional=False``: the command names its input itself (``ride``'s RECORDING_OR_SCENE);
    ``channel=False``: the command picks channels its own way (``ride --channels``);
    ``channel_default``: what the command analyses without ``--channel`` (:data:`CHANNEL_EVERY` ...);
    ``with_segment=False``: no ``--segment`` (a folder's scan); ``segment_help``: what it does for the command.
    :func:`reader_options` turns the parsed options into :func:`vibkit.read_recording` arguments, and
    :func:`read_recording` keeps the ``--segment`` asked for (:func:`segment_of`).
    """
    if positional:
        sp.add_argument("recording", help="recording file (CSV/text, miniSEED ..., netCDF); '-': read stdin")
    g = sp.add_argument_group("reading the recording (all optional: the file says it)")
    if channel:
        add_channel(g, channel_default)
    if with_segment:
        g.add_argument("--segment", type=segment, metavar="START:END", help=segment_help or SEGMENT_HELP)
    for o in READER_OPTIONS:  # the reader's own options, each as vibkit.io.reader_options declares it
        if o.flag and o.name != "channel":
            g.add_argument(o.flag, help=o.help, **_READER_ARGS.get(o.name, {}), **_choices(o))


#: how the command line parses a reader option beyond its declaration (a type that checks it, a switch)
_READER_ARGS = {
    "sample_rate": {"type": sample_rate},
    "units": {"type": units_option},
    "repair_time": {"action": "store_true"},
    "delimiter": {"type": delimiter_option},
}


def _choices(o):
    return {k: v for k, v in (("choices", o.choices), ("metavar", o.metavar)) if v is not None}


def reader_options(a, *, channel=False):
    """The :func:`vibkit.read_recording` keyword arguments that :func:`add_recording`'s options give.

    ``channel=True`` adds ``--channel`` (the reader then keeps that channel only).
    """
    opts = {name: getattr(a, name, None) for name in READER_FLAGS if name != "channel"}
    opts["repair_time"] = bool(opts["repair_time"])
    tc = opts["time_column"]
    if tc is not None:  # a 0-based index, 'none' (the file has no time column) or a name as the file writes it
        opts["time_column"] = int(tc) if tc.strip().isdigit() else False if tc.strip().lower() == "none" else tc
    if channel and getattr(a, "channel", None):
        opts["channel"] = a.channel
    return opts


def read_recording(a):
    """Read ``a.recording`` with the reader options that :func:`add_recording` gave the command.

    Every channel is read (the command picks ``--channel`` among them); a file that cannot be read whole
    (a waveform file whose traces start at different times) is read again with ``--channel`` only.
    """
    from vibkit.diagnose.segment import cut_recording
    from vibkit.io import RecordingError
    from vibkit.io import read_recording as read_file
    from vibkit.io.channels import with_component

    try:
        rec = read_file(a.recording, **reader_options(a))
    except RecordingError:
        if not getattr(a, "channel", None):
            raise
        rec = read_file(a.recording, **reader_options(a, channel=True))
    rec = cut_recording(rec, segment_of(a))  # --segment, in the file's own time; outside it: an error
    rec = with_component(rec, getattr(a, "channel", None))
    _note_held_samples(rec)
    return rec


def _note_held_samples(rec):
    """Say on stderr which channels hold their values between updates, and the Nyquist frequency that follows."""
    held = {str(v): float(rec[v].attrs["update_rate_hz"]) for v in rec.data_vars if "update_rate_hz" in rec[v].attrs}
    if held:
        lo = min(held.values())
        msg(
            f"note: {', '.join(held)}: values held between updates (rows at {rec.attrs['sample_rate_hz']:.4g} Hz, "
            f"updates at {lo:.3g} Hz): nothing above {lo / 2:.3g} Hz (their Nyquist frequency) is in the data"
        )


def add_force_overwrite(sp, what):
    """--force/--overwrite of a command that refuses to replace an existing output."""
    sp.add_argument(
        "--force",
        "--overwrite",
        dest="force",
        action="store_true",
        help=f"replace an existing {what} (never an input, a link, a device or a read-only file)",
    )


LIMITS_HELP = (
    "elongation limits watch,plan,replace [%%]: three increasing percentages, comma-separated "
    f"(default {','.join(f'{v:g}' for v in DEFAULT_LIMITS)})"
)


def add_limits(sp, help_=LIMITS_HELP):
    """--limits WATCH,PLAN,REPLACE [%], the one definition of every command that rates an elongation."""
    sp.add_argument("--limits", type=limits, default=DEFAULT_LIMITS, metavar="WATCH,PLAN,REPLACE", help=help_)


#: how a chain speed and a link pitch are written (:func:`chain_speed`, :func:`pitch_length`), in every help
SPEED_FORMAT = "m/s, or 0.49m/s, 49cm/s, 29.4m/min, 96.5ft/min"
PITCH_FORMAT = "m, or 133.33mm, 13.333cm, 5.25in"


def add_speed(sp, default, what="chain speed measured on the steps"):
    """--speed: the chain speed in any of :data:`SPEED_FORMAT`'s units; ``default`` says where the command takes
    it from without the option (as :func:`vibkit.cli.settings.run_speed`: the escalator profile's before the file's)."""
    sp.add_argument("--speed", type=chain_speed, help=f"{what}: {SPEED_FORMAT} (default: {default})")


def add_nominal_pitch(sp, default, use=""):
    """--nominal-pitch: the chain's nominal link pitch in any of :data:`PITCH_FORMAT`'s units."""
    sp.add_argument(
        "--nominal-pitch", type=pitch_length, help=f"nominal link pitch: {PITCH_FORMAT} (default: {default}){use}"
    )


# ------------------------------------------------------------------------- one speed per run


def add_speed_uncertainty(sp):
    sp.add_argument(
        "--speed-uncertainty",
        type=speed_uncertainty,
        help="standard deviation of the speed, in m/s or in %% (e.g. 0.1%%); without it the speed's "
        "uncertainty is 'not stated' (an escalator profile's rated speed: the standard's tolerance)",
    )


def _profile_of(a):
    """The escalator profile that --escalator names, or None (commands without the option)."""
    if getattr(a, "escalator", None) is None:
        return None
    return escalator_profile(a)


def segment(text):
    """--segment START:END [s] -> (start, end); a bad value is a usage error (exit 2), as the library words it."""
    from vibkit.diagnose.segment import parse_segment

    try:
        return parse_segment(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(re.sub(r"^segment ", "", str(exc))) from None


#: what --segment does, for every command that analyses a recording (``ride`` says what it does there)
SEGMENT_HELP = (
    "analyse only START:END [s] of the recording, in its own time (as its time column reads); a segment "
    "outside the recording is an error"
)


def segment_of(a):
    """--segment as (start, end) [s], or None (argparse checked it: :func:`segment`)."""
    value = getattr(a, "segment", None)
    return None if value is None else tuple(value)


ESCALATOR_HELP = "the escalator's profile (TOML): unit, speed, pitch, links (an example: vibkit datasets path E07.toml)"


def add_escalator(sp, help_=ESCALATOR_HELP):
    """--escalator FILE: the user's escalator profile (vibkit.model.profile)."""
    sp.add_argument("--escalator", metavar="FILE", help=help_)


def links_count(text):
    """--links: a whole number of links, at least 2."""
    return _whole_number(text, "links", 2, "a chain has at least 2 links")


_TIME_UNITS = {"s": 1.0, "ms": 1e-3, "min": 60.0}
#: how --marker is written: seconds, or with a unit
TIME_FORMAT = "s, or 12.4s, 850ms, 2.5min"


def seconds(text):
    """--marker: a time from the recording's start, 0 or more: seconds, or with a unit (``12.4s``, ``850ms``,
    ``2.5min``), as --speed takes its unit."""
    t = str(text).strip().replace(" ", "")
    factor = 1.0
    for unit in sorted(_TIME_UNITS, key=len, reverse=True):  # min and ms before s
        if t.lower().endswith(unit):
            t, factor = t[: -len(unit)], _TIME_UNITS[unit]
            break
    try:
        v = float(t) * factor
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a time from the recording's start ({TIME_FORMAT}), got {text!r}"
        ) from None
    if not (math.isfinite(v) and v >= 0):
        raise argparse.ArgumentTypeError(f"expected a time >= 0 s from the recording's start, got {text!r}")
    return v


MARKER_HELP = (
    f"time from the recording's start ({TIME_FORMAT}) at which a marked link (chalk, tape) passed the sensor: it "
    "becomes link 1 (default: the link at the sensor when the recording starts)"
)


def add_marker(sp, help_=MARKER_HELP):
    """--marker TIME: when a marked link passed the sensor (the link map numbers from it)."""
    sp.add_argument("--marker", type=seconds, metavar="TIME", help=help_)


LINKS_HELP = "links in the chain (e.g. 159; default the --escalator profile's)"
#: --links of pitch and spectrum: what the number of links does there
LINKS_WANDER_HELP = (
    "links in the chain (default the --escalator profile's): a record over two loops is then checked for "
    "wander without the once-a-loop pattern a worn link gives"
)


def add_links(sp, help_=LINKS_HELP):
    """--links N: the chain's number of links (else the escalator profile's, :func:`vibkit.cli.settings.chain_links`)."""
    sp.add_argument("--links", type=links_count, help=help_)


def escalator_profile(a):
    """The profile named by ``--escalator`` (a Profile), None without one; a bad file is a CLIError."""
    path = getattr(a, "escalator", None)
    if path is None:
        return None
    if not str(path).strip():
        why = "expected the escalator profile's file (TOML, as vibkit datasets path E07.toml); give its path, or leave it out"
        raise CLIError(f"--escalator {path!r}: {why}")
    from vibkit.model.profile import load_profile
    from vibkit.model.scene import SceneError

    try:
        return load_profile(path)
    except SceneError as exc:
        raise CLIError(f"--escalator: {exc}") from None


#: an exception's class name before its text (``OSError: ``, ``TypeError: Error: ``)
_EXC_NAME = re.compile(r"\b(?:[A-Z][A-Za-z]*(?:Error|Exception)|Error): ")


def plain_message(text: str, args) -> str:
    """A message without Python's exception names, naming the flag the user gave that it is about.

    The library says ``band 60-80 Hz``: when the user gave that option, the message names its flag (``--band``,
    ``--channels``, ``--sample-rate``).  The reader's options need no such rewriting: the reader names them as their
    flags itself when the command line calls it (:func:`vibkit.io.reader_options.flag_spelling`).
    """
    text = _EXC_NAME.sub("", text)
    text = text.replace("give band=(low, high) [Hz]", "give --band LOW:HIGH [Hz]")
    given = {k: v for k, v in vars(args).items() if v not in (None, False)}
    if "band" in given and "--band" not in text:
        text = re.sub(r"\bband (?=[0-9])", "--band ", text, count=1)
    if "marker" in given:  # the link map's "Parameter marker_s=999.0 must lie within the recording"
        text = re.sub(r"\b(?:Parameter )?marker_s=([^ ]+)", r"--marker \1 s", text)
    if "channels" in given and "--channels" not in text and "channel" in text:
        text += f" (from --channels {given['channels']})"
    if "sample_rate" in given and "--sample-rate" not in text and ("Nyquist" in text or "matrix" in text):
        text += f" (from --sample-rate {given['sample_rate']:g})"
    return text
