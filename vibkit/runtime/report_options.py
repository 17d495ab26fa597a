"""The report's options, declared once: :class:`ReportOptions`, a frozen dataclass whose fields are the options.

:func:`vibkit.diagnose.report.write_report` and :func:`vibkit.diagnose.report.context.analyse` take these options as
keywords (their signatures and the ``Parameters`` entries of their docstrings are made from the fields:
:func:`takes_report_options`), and the command line (:mod:`vibkit.cli.report`) adds the flags the report declares
itself (``help`` in a field's metadata) and maps every flag back to its field (``flag``).  A field's metadata:
``takes`` (what it takes, in the docstring's words), ``doc`` (what it is), ``flag`` (the command-line flag that gives
it, None: a library option only), ``help`` (the flag's help where the report declares the flag; the other flags are
the ones every command shares, :mod:`vibkit.cli.options`) and ``parse`` (how the command line reads a flag the report
declares: ``"band"``, ``"positive"`` or None, the text as given).

It lives beside the reader's options (:mod:`vibkit.runtime.reader_options`) and not in the report's package: the
command line builds its flags at start-up (``vibkit --help``), which must not load matplotlib.
"""

from __future__ import annotations

import dataclasses
import inspect
import textwrap
from dataclasses import dataclass, field

__all__ = ["ReportOptions", "report_options_doc", "takes_report_options"]


def _opt(takes, doc, default=None, *, flag=None, help=None, parse=None):
    meta = {"takes": takes, "doc": doc, "flag": flag, "help": help, "parse": parse}
    return field(default=default, metadata=meta)


@dataclass(frozen=True, kw_only=True)
class ReportOptions:
    """What a report is asked for (every field is an option of :func:`vibkit.diagnose.report.write_report`)."""

    scene: object = _opt(
        "str, os.PathLike or Scene",
        "Scene describing the escalator and sensor; simulated (the run kept on disk by scene) and compared with the "
        "recording.",
        flag="--scene",
        help="scene describing the escalator and sensor (simulated and compared); default with --escalator: the "
        "scene built from the profile",
    )
    speed: float | None = _opt(
        "float",
        "Chain speed [m/s], the one speed of every page and of the comparison; default the profile's rated speed, "
        "else the recording's ``chain_speed_m_s``, else the scene's.",
        flag="--speed",
    )
    speed_sigma: float | str | None = _opt(
        "float or str",
        'Its standard deviation [m/s], or a percentage of it (``"0.05%"``); None: not stated (a profile\'s rated '
        "speed then takes the profile's sigma).",
        flag="--speed-uncertainty",
    )
    channel: str | None = _opt("str", "The channel to analyse (default: every vibration channel).", flag="--channel")
    nominal_pitch: float | None = _opt(
        "float", "[m]; default the profile's, else the scene's link pitch.", flag="--nominal-pitch"
    )
    limits_percent: tuple | None = _opt(
        "(float, float, float)", "Elongation limits [%] (default 1.5, 2, 3).", flag="--limits"
    )
    sample_rate: float | None = _opt("float", "For files without time. [Hz]", flag="--sample-rate")
    duration: float | None = _opt(
        "float",
        "Simulated time [s] (default the scene's).",
        flag="--duration",
        help="simulated time [s] (default: the scene's)",
        parse="positive",
    )
    band: tuple | None = _opt(
        "(float, float)",
        "Link-pass search band. [Hz]",
        flag="--band",
        help="link-pass search band LOW:HIGH [Hz]",
        parse="band",
    )
    hampel_half_window_s: float = _opt(
        "float", "Half window of the spike detector [s] (longer than a spike: a knock lasts tens of ms).", 0.1
    )
    hampel_false_alarm_rate: float = _opt(
        "float", "Per-sample false-alarm probability of the spike detector on Gaussian noise.", 1e-4
    )
    progress: bool = _opt("bool", "Show the simulation's progress on stderr.", False)
    read_options: dict | None = _opt(
        "dict",
        "More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).",
    )
    date: object = _opt(
        "str or datetime.datetime",
        "When the recording was made (ISO 8601); default the file's start time, if it states one.",
        flag="--date",
        help="when the recording was made, ISO 8601 (default: the file's start time)",
    )
    profile: object = _opt(
        "Profile",
        "The escalator profile (:func:`vibkit.model.profile.load_profile`): page 1 names its unit; its rated speed, "
        "nominal pitch and teeth are the defaults; a scene's simulated ride page is shown only when the scene is "
        "this unit's.",
        flag="--escalator",
    )
    segment: tuple | None = _opt(
        "(float, float)",
        "The recording's ride segment [s] (default: detected), for its ride-quality page.",
        flag="--segment",
    )
    marker_s: float | None = _opt(
        "float",
        "When a marked link passed the sensor [s from the recording's start]: the links page numbers from it "
        "(:func:`vibkit.diagnose.links.find_worn_links`).",
        flag="--marker",
    )

    @classmethod
    def of(cls, caller: str, options: dict) -> ReportOptions:
        """The options ``options`` (keywords given to ``caller``), the others at their defaults; an unknown name is a
        TypeError that names it and the known ones, as Python's own is for a function."""
        known = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise TypeError(
                f"{caller}() got an unexpected keyword argument {unknown[0]!r} (its options: {', '.join(known)})"
            )
        return cls(**options)

    def as_dict(self) -> dict:
        """The options by name (the values themselves, not copies)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


def report_options_doc(indent: str = "    ") -> str:
    """The ``Parameters`` entries of the options, numpydoc style (a name and what it takes, then what it is)."""
    lines = []
    for f in dataclasses.fields(ReportOptions):
        doc = f.metadata["doc"]
        if f.default is not None and "default" not in doc:
            doc += f" Default {f.default!r}."
        lines.append(f"{indent}{f.name} : {f.metadata['takes']}, optional")
        lines += textwrap.wrap(doc, 112, initial_indent=indent + "    ", subsequent_indent=indent + "    ")
    return "\n".join(lines)


#: where a docstring's ``Parameters`` list the options
PLACEHOLDER = "    **options\n"


def takes_report_options(func):
    """``func(..., **options)`` shown with the options as its keyword-only parameters (``__signature__``) and
    documented (its docstring's line ``**options`` replaced by their entries)."""
    sig = inspect.signature(func)
    params = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    params += [
        inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default)
        for f in dataclasses.fields(ReportOptions)
    ]
    func.__signature__ = sig.replace(parameters=params)
    if func.__doc__ and PLACEHOLDER in func.__doc__:
        func.__doc__ = func.__doc__.replace(PLACEHOLDER, report_options_doc() + "\n", 1)
    return func
