"""Measurement dates: parsing (ISO 8601, day/month/year) and the UTC text the database stores.

Dates are stored as UTC ISO 8601 text and as seconds since 1970 (``date_unix_s``).
"""

from __future__ import annotations

import datetime as _dt
import math
import re

from ..runtime import dates as runtime_dates
from .errors import FleetError

__all__ = ["check_date", "parse_date"]


def check_date(d: _dt.datetime, what="date", text=None) -> _dt.datetime:
    """A timezone-aware UTC datetime within 1970-2100 and not more than a day in the future (the validator
    every command shares: :func:`vibkit.runtime.dates.check_date`)."""
    try:
        return runtime_dates.check_date(d, what, text)
    except ValueError as exc:
        raise FleetError(str(exc)) from None


_DMY = re.compile(r"([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]([0-9]{4})(?:[ T](.*))?")


def parse_date(text, *, what="date", ambiguous_ok=False) -> _dt.datetime:
    """A timezone-aware UTC datetime from ISO 8601 text (or day/month/year as loggers write it).

    A date without time is midnight; a time without zone is UTC.  Dates outside 1970-2100 or more
    than a day in the future are refused (:func:`check_date`).

    A day/month/year date whose day and month could be swapped (``05/11/2025``) is refused unless
    ``ambiguous_ok`` (a logger's start time, whose convention is day/month): write ISO 8601.

    Raises
    ------
    FleetError
        Not a date (a time of day alone is not one), or an implausible one; ``what`` names it.
    """
    s = str(text).strip()
    if not s:
        raise FleetError(f"{what} is empty; expected ISO 8601 such as 2026-11-23 or 2026-11-23T10:15:00Z")
    t = re.sub(r",\s*", " ", re.sub(r"(?<=[0-9]),(?=[0-9])", ".", s))  # decimal comma; "date, time"
    m = _DMY.fullmatch(t)
    if (
        m
        and not ambiguous_ok
        and int(m.group(1)) <= 12
        and int(m.group(2)) <= 12
        and m.group(1).lstrip("0") != m.group(2).lstrip("0")
    ):
        day, month = int(m.group(1)), int(m.group(2))
        raise FleetError(
            f"{what} {s!r} is ambiguous: day/month ({_dt.date(2000, month, day):%d %B}) or month/day "
            f"({_dt.date(2000, day, month):%d %B})? Write it as ISO 8601 (year-month-day, e.g. "
            f"{m.group(3)}-{month:02d}-{day:02d})"
        )
    if m:
        t = f"{m.group(3)}-{int(m.group(2)):02d}-{int(m.group(1)):02d}" + (f"T{m.group(4)}" if m.group(4) else "")
    if re.match(r"^[0-9]{1,2}:[0-9]{2}", t):
        raise FleetError(f"{what} {s!r} has no calendar date (a time of day only)")
    try:
        d = _dt.datetime.fromisoformat(t)
    except ValueError:
        raise FleetError(
            f"{what} {s!r} is not an ISO 8601 date (expected e.g. 2026-11-23 or 2026-11-23T10:15:00+01:00)"
        ) from None
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    try:
        d = d.astimezone(_dt.timezone.utc)
    except (OverflowError, ValueError):  # 9999-12-31T23:59:59-23:59 is past the calendar in UTC
        raise FleetError(f"{what} {s!r} is outside 1970-2100; expected the date of the measurement") from None
    check_date(d, what, s)
    return d


def _iso(d: _dt.datetime) -> str:
    return d.astimezone(_dt.timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def _unix_to_date(sec):
    """UTC datetime of seconds since 1970, or None outside the calendar datetime can hold."""
    try:
        if not math.isfinite(sec):
            return None
        return _dt.datetime(1970, 1, 1, tzinfo=_dt.timezone.utc) + _dt.timedelta(seconds=float(sec))
    except (OverflowError, ValueError):
        return None


def _unix_to_iso(sec):
    d = _unix_to_date(sec)
    return None if d is None else _iso(d)
