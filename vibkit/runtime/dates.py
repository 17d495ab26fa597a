"""Measurement dates: the one validator every command uses (``report --date``, ``fleet add --date``, a scan's
catalogue).

A measurement date is ISO 8601 (``2026-11-23``, ``2026-11-23T10:15:00+01:00``; without a zone: UTC),
within 1970-2100 UTC (what seconds since 1970 and a maintenance record can hold) and not more than a
day in the future.  Imports only the standard library.
"""

from __future__ import annotations

import datetime as _dt

__all__ = ["DATE_YEARS", "check_date", "parse_iso_date"]

#: years a measurement date may have (UTC)
DATE_YEARS = (1970, 2100)


def check_date(d: _dt.datetime, what="date", text=None) -> _dt.datetime:
    """A timezone-aware UTC datetime within :data:`DATE_YEARS` and not more than a day in the future.

    Raises
    ------
    ValueError
        Outside those years or in the future; ``what`` (the flag or the column) and ``text`` named.
    """
    lo, hi = DATE_YEARS
    shown = repr(text) if text is not None else d.isoformat()
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    if not lo <= d.year <= hi:
        raise ValueError(f"{what} {shown} is outside {lo}-{hi}; expected the date of the measurement")
    if d > _dt.datetime.now(_dt.timezone.utc) + _dt.timedelta(days=1):
        raise ValueError(f"{what} {shown} lies in the future; expected the date of the measurement")
    return d


def parse_iso_date(text, what="date") -> _dt.datetime:
    """A checked UTC datetime from ISO 8601 text (see the module docstring).

    Raises
    ------
    ValueError
        Not ISO 8601, or a date :func:`check_date` refuses.
    """
    s = str(text).strip()
    if not s:
        raise ValueError(f"{what} is empty; expected ISO 8601 such as 2026-11-23 or 2026-11-23T10:15:00Z")
    try:
        d = _dt.datetime.fromisoformat(s.replace("Z", "+00:00") if s.endswith("Z") else s)
    except ValueError:
        raise ValueError(
            f"{what} {s!r} is not an ISO 8601 date (expected e.g. 2026-11-23 or 2026-11-23T10:15:00+01:00)"
        ) from None
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    try:
        d = d.astimezone(_dt.timezone.utc)
    except (OverflowError, ValueError):  # 9999-12-31T23:59:59-23:59 is past the calendar in UTC
        raise ValueError(
            f"{what} {s!r} is outside {DATE_YEARS[0]}-{DATE_YEARS[1]}; expected the date of the measurement"
        ) from None
    return check_date(d, what, s)
