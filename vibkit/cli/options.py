"""Option types, validators and the option groups that several commands share.

A bad option value is a usage error (argparse, exit 2), except where a command checks it later.
Each shared option is defined here once; a command adds the groups it takes.
"""

from __future__ import annotations

import argparse
import math

from .output import CLIError

JSON_HELP = "JSON on stdout (with a schema version)"
DEFAULT_LIMITS = (1.5, 2.0, 3.0)

# ------------------------------------------------------------------------------------------ types


def band(text):
    try:
        lo, hi = (float(v) for v in text.replace(",", ":").split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LOW:HIGH in Hz (e.g. 2.5:6), got {text!r}") from None
    if not 0 < lo < hi:
        raise argparse.ArgumentTypeError(f"expected 0 < LOW < HIGH, got {text!r}")
    return (lo, hi)


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


def teeth(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of sprocket teeth, got {text!r}") from None
    if v < 3:
        raise argparse.ArgumentTypeError(f"a sprocket has at least 3 teeth, got {text!r}")
    return v


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
    return v


def speed_uncertainty(text):
    """argparse type of --speed-uncertainty: m/s or a percentage; a bad value is a usage error (exit 2)."""
    try:
        speed_sigma(text, 1.0)
    except CLIError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None
    return text


def byte_size(text):
    from vibkit.runtime.budget import parse_bytes

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
    return subparsers.add_parser(name, help=help_.replace("%", "%%"), description=help_, epilog=epilog,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)


def add_json(sp, help_=JSON_HELP):
    sp.add_argument("--json", action="store_true", help=help_)


def add_sample_rate(sp):
    sp.add_argument("--sample-rate", type=positive, help="sample rate for files without time [Hz]")


def add_channel(sp, help_="channel to analyse, named as the file writes it or as vibkit does "
                          "(default: the first that is not a sample counter)"):
    sp.add_argument("--channel", help=help_)


def add_recording(sp, *, time_options=True):
    """The RECORDING argument and the recording reader's options (applied by :func:`read_recording`).

    ``time_options=False``: no --time-column, --time-unit, --repair-time (``report`` reads the file
    itself, in :mod:`vibkit.diagnose.report`).
    """
    sp.add_argument("recording", help="recording file (CSV/text, miniSEED ..., netCDF)")
    add_channel(sp)
    add_sample_rate(sp)
    if time_options:
        sp.add_argument("--time-column", metavar="NAME|INDEX|none",
                        help="time column by name or 0-based index; 'none': the file has no time column")
        sp.add_argument("--time-unit", choices=("s", "ms", "us", "ns", "min", "h"),
                        help="unit of a numeric time column (overrides the header and the epoch guess)")
        sp.add_argument("--repair-time", action="store_true",
                        help="undo a clock set back at midnight or by a DST change, sort other backward "
                             "rows and drop repeated stamps instead of refusing the file (in the history)")


def read_recording(a):
    """Read ``a.recording`` with the reader options that :func:`add_recording` gave the command."""
    import vibkit

    tc = getattr(a, "time_column", None)
    if tc is not None:  # a 0-based index, 'none' (the file has no time column) or a name as the file writes it
        tc = int(tc) if tc.strip().isdigit() else False if tc.strip().lower() == "none" else tc
    return vibkit.read_recording(a.recording, sample_rate=getattr(a, "sample_rate", None), time_column=tc,
                                 time_unit=getattr(a, "time_unit", None),
                                 repair_time=bool(getattr(a, "repair_time", False)))


def add_force_overwrite(sp, what):
    """--force/--overwrite of a command that refuses to replace an existing output."""
    sp.add_argument("--force", "--overwrite", dest="force", action="store_true",
                    help=f"replace an existing {what} (never an input, a link, a device or a read-only file)")


def add_limits(sp, help_="elongation limits watch,plan,replace [%%] (default 1.5,2,3)"):
    sp.add_argument("--limits", type=limits, default=DEFAULT_LIMITS, help=help_)
