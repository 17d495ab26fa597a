"""Units found in column names and headers, and their conversion to SI.

Field exports write units in many ways: ``"Acceleration x (m/s^2)"``,
``"acc [g]"``, ``"Aceleración (g)"``, ``"time_ms"``, ``"gFz"`` (g-force),
``"X (100g)"`` (an enDAQ channel: range 100 g, values in g).  This module turns
such text into a :class:`Unit` (factor to SI, SI symbol, physical quantity) and
says nothing it cannot justify: an unknown unit gives ``None``.  What one logger
means by a header (the enDAQ range, Physics Toolbox's ``gFz``) is in its entry
of :mod:`vibkit.io.text.loggers`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

# standard gravity converts g -> m/s^2 (the unit's definition, not the model's 9.81)
from ...runtime.constants import STANDARD_GRAVITY
from .loggers import header_unit

__all__ = [
    "STANDARD_GRAVITY",
    "Unit",
    "parse_unit",
    "parse_time_unit",
    "split_name_unit",
    "is_time_name",
]


@dataclass(frozen=True)
class Unit:
    """A unit and how to reach SI from it.

    Attributes
    ----------
    text : str
        The unit as written in the file or the override.
    factor : float or None
        Multiply values by this to get SI; None for raw counts (no known scale).
    si : str
        SI unit symbol of the converted values ("m/s^2", "m/s", "m", "counts" ...).
    quantity : str
        "displacement", "velocity", "acceleration" or "other".
    """

    text: str
    factor: float | None
    si: str
    quantity: str


_LENGTH = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "nm": 1e-9, "in": 0.0254, "ft": 0.3048}
_G_WORDS = {"g", "gn", "g0", "gs", "g's", "gee", "g-force", "gforce"}
_COUNTS = {"counts", "count", "cnt", "cts", "raw", "lsb", "adu", "digits", "digit"}
_OTHER = {
    "v": (1.0, "V"),
    "mv": (1e-3, "V"),
    "rad/s": (1.0, "rad/s"),
    "deg/s": (math.pi / 180.0, "rad/s"),
    "°/s": (math.pi / 180.0, "rad/s"),
    "n": (1.0, "N"),
    "kn": (1e3, "N"),
    "hz": (1.0, "Hz"),
}
_TIME = {
    "s": 1.0,
    "sec": 1.0,
    "secs": 1.0,
    "second": 1.0,
    "seconds": 1.0,
    "seg": 1.0,
    "segundos": 1.0,
    "ms": 1e-3,
    "msec": 1e-3,
    "millisecond": 1e-3,
    "milliseconds": 1e-3,
    "millis": 1e-3,
    "us": 1e-6,
    "usec": 1e-6,
    "microsecond": 1e-6,
    "microseconds": 1e-6,
    "ns": 1e-9,
    "nanoseconds": 1e-9,
    "min": 60.0,
    "minutes": 60.0,
    "h": 3600.0,
    "hours": 3600.0,
}
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_LEN_ALT = "|".join(sorted(_LENGTH, key=len, reverse=True))
_ACC_RE = re.compile(rf"^({_LEN_ALT})(?:/s(?:\^?2|/s)|\*?s\^?-2)$")
_VEL_RE = re.compile(rf"^({_LEN_ALT})(?:/s|\*?s\^?-1)$")
# units accepted as a name suffix ("time_ms", "acc_z_g"): only unambiguous ones
_SUFFIX_UNITS = {"g", "mg", "m", "cm", "mm", "um", "nm", "ms", "s", "us", "m/s2", "mm/s", "m/s"}
_TIME_NAME_RE = re.compile(
    r"^(?:t|time|tiempo|timestamp|time ?stamp|date ?time|date/time|datetime|fecha(?: y)? ?hora|hora"
    r"|elapsed(?: time)?|seconds|secs?|zeit|temps|tempo|tijd|czas|relative[ _]?time|date|datum|heure)(?:\b.*)?$",
    re.IGNORECASE,
)


#: speeds written per hour or per minute [m/s per unit]
_SPEEDS = {"km/h": 1 / 3.6, "kmh": 1 / 3.6, "kph": 1 / 3.6, "m/min": 1 / 60, "ft/min": 0.3048 / 60, "fpm": 0.3048 / 60}


def _normalise(text: str) -> str:
    t = text.strip().strip("\"'").strip()
    for a, b in (
        ("µ", "u"),
        ("μ", "u"),
        ("⁻²", "^-2"),
        ("⁻¹", "^-1"),
        ("²", "^2"),
        ("**", "^"),
        ("·", "*"),
        ("⋅", "*"),
        ("−", "-"),
    ):
        t = t.replace(a, b)
    t = t.lower()
    t = re.sub(r"\s*([/*^])\s*", r"\1", t)
    t = re.sub(r"\s+", " ", t)
    t = re.sub(r"^([a-z]+) s(\^?-[12])$", r"\1*s\2", t)  # "m s^-2" -> "m*s^-2"
    return t


def _parse_plain(t: str, text: str) -> Unit | None:
    if t in _G_WORDS:
        return Unit(text, STANDARD_GRAVITY, "m/s^2", "acceleration")
    if t in ("mg", "milli-g", "millig"):
        return Unit(text, 1e-3 * STANDARD_GRAVITY, "m/s^2", "acceleration")
    if t == "gal":
        return Unit(text, 1e-2, "m/s^2", "acceleration")
    if t in _COUNTS:
        return Unit(text, None, "counts", "other")
    if t in _LENGTH:
        return Unit(text, _LENGTH[t], "m", "displacement")
    m = _ACC_RE.match(t)
    if m:
        return Unit(text, _LENGTH[m.group(1)], "m/s^2", "acceleration")
    m = _VEL_RE.match(t)
    if m:
        return Unit(text, _LENGTH[m.group(1)], "m/s", "velocity")
    if t in _SPEEDS:  # a conveyor's or a tachometer's speed in a unit of its trade
        return Unit(text, _SPEEDS[t], "m/s", "velocity")
    if t in _OTHER:
        f, si = _OTHER[t]
        return Unit(text, f, si, "other")
    return None


def parse_unit(text: str) -> Unit | None:
    """Parse a unit of a measured quantity.

    Accepts plain units (``"m/s^2"``, ``"m/s2"``, ``"m s-2"``, ``"g"``, ``"mg"``,
    ``"mm"``, ``"um"``, ``"mm/s"``, ``"counts"`` ...) and scaled ones written
    ``"<unit>/<number>"`` or ``"<number> <unit>"`` / ``"<number>*<unit>"``
    (``"g/2048"``: one count is 1/2048 g).

    Parameters
    ----------
    text : str
        The unit as written.

    Returns
    -------
    Unit or None
        None when the text is not a unit this module knows.

    Examples
    --------
    >>> parse_unit("g").factor
    9.80665
    >>> parse_unit("mm").si, parse_unit("mm").factor
    ('m', 0.001)
    >>> parse_unit("g/2048").factor * 2048
    9.80665
    """
    if not isinstance(text, str):
        return None
    t = _normalise(text)
    if not t:
        return None
    plain = _parse_plain(t, text)
    if plain is not None:
        return plain
    m = re.match(rf"^(?P<u>.+?)/(?P<n>{_NUMBER})$", t)
    if m:
        scale = 1.0 / float(m.group("n")) if float(m.group("n")) != 0 else math.nan
    else:
        m = re.match(rf"^(?P<n>{_NUMBER})(?: |\*)(?P<u>.+)$", t)
        scale = float(m.group("n")) if m else math.nan
    if not m or not math.isfinite(scale) or scale == 0:
        return None
    base = _parse_plain(m.group("u"), m.group("u"))
    if base is None or base.factor is None:
        return None
    return Unit(text, base.factor * scale, base.si, base.quantity)


def parse_time_unit(text: str) -> float | None:
    """Factor from a time unit to seconds (``"ms"`` -> 1e-3), or None if unknown."""
    if not isinstance(text, str):
        return None
    return _TIME.get(_normalise(text))


def is_time_name(name: str) -> bool:
    """Whether a column name (without its unit) names time (``"Time"``, ``"tiempo"``, ``"t"``...)."""
    return bool(_TIME_NAME_RE.match(name.strip()))


def split_name_unit(header: str) -> tuple[str, str | None, str | None]:
    """Split a column header into name and unit text.

    Parameters
    ----------
    header : str
        Column header as found, e.g. ``"Acceleration x (m/s^2)"``.

    Returns
    -------
    name : str
        The name without the unit, e.g. ``"Acceleration x"``.
    unit : str or None
        The unit text (``"m/s^2"``), or None when the header carries none.
    note : str or None
        How the unit was read when that is not obvious (g-force columns,
        enDAQ range annotations).

    Examples
    --------
    >>> split_name_unit("acc [g]")
    ('acc', 'g', None)
    >>> split_name_unit("time_ms")
    ('time', 'ms', None)
    """
    h = " ".join(str(header).strip().strip("\"'").split())
    run = re.match(r"^(?P<head>.*\S)\s+(?P<run>run\s*#\s*[0-9]+)$", h, re.IGNORECASE)
    if run:  # PASCO SPARKvue/Capstone: 'Acceleration (m/s²) Run #1'; the run goes to the name
        name, unit, note = split_name_unit(run.group("head"))
        return f"{name} {run.group('run')}", unit, note
    m = re.match(r"^(?P<name>.*?)\s*[\(\[\{]\s*(?P<unit>[^()\[\]{}]*?)\s*[\)\]\}]\s*$", h)
    if m and m.group("unit"):
        name = m.group("name") or h
        unit = m.group("unit")
        quirk = header_unit(h, unit)
        if quirk is not None:  # a logger's own meaning of the bracket (enDAQ "X (100g)": a range, values in g)
            return name, quirk[0], quirk[1]
        return name, unit, None
    m = re.match(r"^(?P<name>.*\S)\s+in\s+(?P<unit>\S+)$", h)
    if m and (parse_unit(m.group("unit")) or parse_time_unit(m.group("unit"))):
        return m.group("name"), m.group("unit"), None
    # a unit spelt in a programmer's name, its slash an underscore: "accel_m_s2", "disp_mm", "vel_mm_s"
    m = re.match(r"^(?P<name>.*?[A-Za-z0-9])_(?P<len>m|cm|mm|um)_s(?P<sq>_?2)?$", h)
    if m:
        return m.group("name"), f"{m.group('len')}/s{'^2' if m.group('sq') else ''}", None
    m = re.match(r"^(?P<name>.*?[A-Za-z0-9])[ _\-](?P<unit>[A-Za-zµμ/0-9^]+)$", h)
    if m and _normalise(m.group("unit")) in _SUFFIX_UNITS:
        return m.group("name"), m.group("unit"), None
    quirk = header_unit(h)
    if quirk is not None:  # a logger's header that is its own unit (Physics Toolbox "gFz": g-force, in g)
        return h, quirk[0], quirk[1]
    return h, None, None
