"""The reader's options, declared once: name, what it takes, its command-line flag, its help.

:data:`READER_OPTIONS` is the one list.  :func:`vibkit.read_recording`'s keyword parameters are these names (a test
holds them equal), the readers of :mod:`vibkit.io.registry` are handed the ones of their :attr:`ReaderOption.scope`
(:func:`options_of`), and the command line (:func:`vibkit.cli.options.add_recording`) adds one flag for each that has
one, with its help and choices, and maps the parsed flags back (:func:`vibkit.cli.options.reader_options`).

A message that tells the user to give an option names it with :func:`spell`: ``time_unit=`` in Python, ``--time-unit``
on the command line (which calls the reader inside :func:`flag_spelling`).  The command line never rewrites a
message: the message is written in the caller's words when it is made.  :class:`ReaderOptionError` is a bad option
value, with the option's name in its ``parameter`` attribute.

The declarations live here, beside the guards every layer shares, and not in :mod:`vibkit.io`: the command line
builds its flags from them at start-up (``vibkit --help``), which must not load the readers (xarray).
"""

from __future__ import annotations

import contextlib
import contextvars
from dataclasses import dataclass

__all__ = [
    "READER_OPTIONS",
    "ReaderOption",
    "as_flags",
    "ReaderOptionError",
    "either",
    "flag_spelling",
    "option",
    "options_of",
    "spell",
]


@dataclass(frozen=True)
class ReaderOption:
    """One option of :func:`vibkit.read_recording`.

    ``name`` is the Python parameter; ``takes`` what it takes, in words; ``flag`` the command-line flag (None: a
    library option only); ``help`` the flag's help; ``default`` the parameter's default; ``scope`` which readers
    are handed it: ``"all"`` (every reader), ``"text"`` (text files; the waveform reader takes ``units`` too) or
    ``"open"`` (:func:`vibkit.read_recording` itself, before a reader is chosen); ``choices`` and ``metavar`` the
    flag's."""

    name: str
    takes: str
    flag: str | None
    help: str
    default: object = None
    scope: str = "text"
    choices: tuple | None = None
    metavar: str | None = None


#: every option of :func:`vibkit.read_recording`, in its signature's order
READER_OPTIONS: tuple[ReaderOption, ...] = (
    ReaderOption(
        "channel",
        "str or list of str",
        "--channel",
        "channel to analyse, named as the file writes it or as vibkit does",
        scope="all",
    ),
    ReaderOption("sample_rate", "float [Hz]", "--sample-rate", "sample rate for files without time [Hz]", scope="all"),
    ReaderOption(
        "time_column",
        "str, int or False",
        "--time-column",
        "time column by name or 0-based index; 'none': the file has no time column",
        metavar="NAME|INDEX|none",
    ),
    ReaderOption(
        "time_unit",
        "str",
        "--time-unit",
        "unit of a numeric time column (overrides the header and the epoch guess)",
        choices=("s", "ms", "us", "ns", "min", "h"),
    ),
    ReaderOption(
        "units",
        "str or dict",
        "--units",
        "unit of every channel (m/s^2, g, mm, counts, or scaled counts like g/2048: one count is 1/2048 g), or per "
        "channel az=g,ax=g/2048; overrides the file's header",
        metavar="UNIT|NAME=UNIT,...",
    ),
    ReaderOption("resample", '{None, "linear"}', None, "resample each segment to the nominal rate", scope="all"),
    ReaderOption("gap_factor", "float", None, "a step this many periods long splits bursts", 5.0, scope="all"),
    ReaderOption(
        "repair_time",
        "bool",
        "--repair-time",
        "undo a clock set back at midnight or by a DST change, sort other backward rows and drop repeated stamps "
        "instead of refusing the file (in the history)",
        False,
        scope="all",
    ),
    ReaderOption(
        "delimiter",
        "str",
        "--delimiter",
        "text files: the delimiter (default: detected)",
        metavar="comma|semicolon|tab|pipe|whitespace",
    ),
    ReaderOption("decimal", "str", "--decimal", "text files: the decimal mark (default: detected)", choices=(".", ",")),
    ReaderOption(
        "encoding", "str", "--encoding", "text files: the encoding, e.g. cp1252 (default: UTF-8, else cp1252)"
    ),
    ReaderOption("max_bytes", "int [bytes]", None, "refuse files larger than this", scope="open"),
    ReaderOption("format", "str", None, "read with this entry of the reader table", scope="open"),
    ReaderOption(
        "date_order",
        "str",
        "--date-order",
        "text files: numeric dates are day/month/year (dmy) or month/day/year (mdy) (default: the order a day above "
        "12 shows; dates that could be either are refused)",
        choices=("dmy", "mdy"),
    ),
)

_BY_NAME = {o.name: o for o in READER_OPTIONS}


def option(name) -> ReaderOption:
    """The declared option ``name`` (a KeyError for a name that is none)."""
    return _BY_NAME[name]


def options_of(scope) -> tuple[str, ...]:
    """The names of the options handed to the readers of ``scope``: ``"all"`` those every reader takes, ``"text"``
    those and the text reader's own."""
    scopes = {"all": ("all",), "text": ("all", "text")}[scope]
    return tuple(o.name for o in READER_OPTIONS if o.scope in scopes)


class ReaderOptionError(ValueError):
    """A bad value of a reader option; ``parameter`` is the option's name (:data:`READER_OPTIONS`)."""

    def __init__(self, parameter, message):
        super().__init__(message)
        self.parameter = parameter


_AS_FLAGS = contextvars.ContextVar("vibkit_reader_options_as_flags", default=False)
_UNSET = object()


@contextlib.contextmanager
def flag_spelling():
    """Within it, :func:`spell` names the options as their command-line flags (the command line reads so)."""
    token = _AS_FLAGS.set(True)
    try:
        yield
    finally:
        _AS_FLAGS.reset(token)


def as_flags() -> bool:
    """Whether messages now name the options as their command-line flags (within :func:`flag_spelling`)."""
    return _AS_FLAGS.get()


def spell(name, value=_UNSET) -> str:
    """How a message names the option ``name`` (with ``value`` when given), in the caller's words.

    In Python: ``time_unit=``, ``repair_time=True``, ``units={'ax': 'g'}``.  Within :func:`flag_spelling`:
    ``--time-unit``, ``--repair-time``, ``--units ax=g``, ``--time-column none``.  An option without a flag is
    spelled as in Python everywhere.
    """
    opt = _BY_NAME[name]
    if not (_AS_FLAGS.get() and opt.flag):
        return f"{name}=" if value is _UNSET else f"{name}={value!r}"
    if value is _UNSET or value is True:
        return opt.flag
    if value is False:
        return f"{opt.flag} none"
    if isinstance(value, dict):
        return f"{opt.flag} " + ",".join(f"{k}={v}" for k, v in value.items())
    return f"{opt.flag} {value}"


def either(name, other) -> str:
    """``"<option> or <other>"``, or ``other`` alone where the caller has no way to give the option (a library option
    on the command line: ``max_bytes`` there is the environment variable only)."""
    if _AS_FLAGS.get() and not _BY_NAME[name].flag:
        return other
    return f"{spell(name)} or {other}"
