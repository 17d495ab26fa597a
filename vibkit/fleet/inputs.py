"""The stated ranges of a fleet measurement's inputs, checked on numbers in SI before any analysis.

One place for every command that takes them (``fleet add``, a scan's catalogue, and whatever parses
units such as ``133.33mm`` first): parse the text into SI, then call these.  Each check raises
:class:`~vibkit.fleet.errors.FleetError` naming what was given (``what``: the option or the column),
the range and, where a unit slip is likely, the fix.

==================  =================  ====================================================
input               range (SI)         why
==================  =================  ====================================================
nominal pitch       0.05 - 0.3 m       escalator step chains: 100-200 mm (133.33 mm common)
speed               0.1 - 2 m/s        escalators run at 0.3-0.75 m/s, moving walks up to 1
speed uncertainty   0 - 20 % of speed  a step timing is good to a few %
measurement date    1970 - 2100 UTC    seconds since 1970 are stored; not in the future
==================  =================  ====================================================
"""

from __future__ import annotations

import datetime as _dt
import math

from ..runtime.dates import DATE_YEARS
from .dates import check_date, parse_date  # noqa: F401 (check_date: re-exported, its home is vibkit.fleet.dates)
from .errors import FleetError

__all__ = ["RANGES", "check_pitch", "check_speed", "check_speed_sigma", "check_date", "check_inputs"]

#: name -> (low, high, unit) of the stated ranges, SI
RANGES = {
    "nominal_pitch": (0.05, 0.3, "m"),
    "speed": (0.1, 2.0, "m/s"),
    "speed_sigma_fraction": (0.0, 0.2, "of the speed"),
    "date_year": (*DATE_YEARS, "UTC"),
}


def _finite(value, what, unit):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise FleetError(f"{what}: expected a number [{unit}], got {value!r}") from None
    if isinstance(value, bool) or not math.isfinite(v):
        raise FleetError(f"{what}: expected a finite number [{unit}], got {value!r}")
    return v


def check_pitch(value, what="nominal pitch") -> float:
    """A nominal link pitch [m] within 0.05-0.3 m (the message says metres when millimetres were given)."""
    lo, hi, unit = RANGES["nominal_pitch"]
    v = _finite(value, what, unit)
    if not lo <= v <= hi:
        hint = f" (metres: {v / 1000:g} m, not {v:g})" if lo <= v / 1000 <= hi else ""
        raise FleetError(f"{what} {v:g} m is outside {lo:g}-{hi:g} m, the pitch of escalator step chains{hint}")
    return v


def check_speed(value, what="speed") -> float:
    """A chain speed [m/s] within 0.1-2 m/s."""
    lo, hi, unit = RANGES["speed"]
    v = _finite(value, what, unit)
    if not lo <= v <= hi:
        raise FleetError(f"{what} {v:g} m/s is outside {lo:g}-{hi:g} m/s, the speeds of escalators and moving walks")
    return v


def check_speed_sigma(value, speed, what="speed uncertainty") -> float:
    """A standard deviation of the speed [m/s] within 0-20 % of the speed."""
    lo, hi, _ = RANGES["speed_sigma_fraction"]
    v = _finite(value, what, "m/s")
    if not lo <= v <= hi * speed:
        raise FleetError(
            f"{what} {v:g} m/s is {100 * v / speed:.3g} % of the speed {speed:g} m/s; expected 0-"
            f"{100 * hi:g} % (a standard deviation, in m/s or as a percentage such as 0.5%)"
        )
    return v


def check_inputs(*, unit, speed, speed_sigma=None, nominal_pitch=None, date=None):
    """Check what ``fleet add`` was given, before the recording is read; returns the parsed date (or None).

    ``speed_sigma`` None means not stated.
    ``nominal_pitch`` None means the unit's stored value (checked by the caller when it is read).
    """
    if not str(unit).strip():
        raise FleetError("unit must be a non-empty identifier (--unit)")
    speed = check_speed(speed, "--speed / speed")
    if speed_sigma is not None:
        check_speed_sigma(speed_sigma, speed, "--speed-uncertainty / speed_sigma")
    if nominal_pitch is not None:
        check_pitch(nominal_pitch, "--nominal-pitch / nominal_pitch")
    if isinstance(date, _dt.datetime):
        return check_date(date)
    if date is not None and str(date).strip():
        return parse_date(date, what="--date / date")
    return None
