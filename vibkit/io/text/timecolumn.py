"""The time column of a text recording: which column it is, and its values in seconds.

Numbers carry their unit in the header (``time (ms)``), from ``time_unit=``, from
the steps matching the header's sample rate (ms), or from their size (Unix
epoch times in s, ms, us or ns); time stamps (ISO 8601, day/month/year,
time of day) become seconds since the first.
"""

from __future__ import annotations

import math
import re
from datetime import datetime, timezone

import numpy as np
import pandas as pd

from ...runtime.reader_options import ReaderOptionError, spell
from ..errors import RecordingError
from .cells import _NUM, _STAMP_DMY, _STAMP_ISO, _STAMP_TOD, _parse_numbers
from .columns import _ColumnNames
from .fastpath import _Fallback
from .loggers import clock_units
from .units import is_time_name, parse_time_unit, parse_unit

__all__ = []

#: plausible Unix epoch times [s]: 1979-07 to 2103-02; each unit's range is 1000x the next, so they never overlap
_EPOCH_RANGE_S = (3e8, 4.2e9)
_EPOCH_UNITS = (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9))


#: names of clock columns besides ``time``: elapsed seconds, epoch, microcontroller clocks
_CLOCK_NAME = re.compile(
    r"^(?:epoch?|unix[ _-]?time|(?:seconds|secs|time)?[ _-]?elapsed(?:[ _-]?(?:time|s|ms))?"
    r"|timestamp|time ?stamp|" + "|".join(map(re.escape, clock_units())) + ")$",
    re.IGNORECASE,
)


def _is_clock_name(nm, ut):
    """Whether a column named ``nm`` with unit ``ut`` (or None) is a clock."""
    if ut is not None and parse_unit(ut) is not None and parse_time_unit(ut) is None:
        return False  # a physical unit: 'time (m)' is no clock
    return bool(is_time_name(nm) or _CLOCK_NAME.match(nm.strip()))


def _first_cell(cells):
    return cells[0] if len(cells) else ""


def _choose_time_column(
    path, time_column, colnames: _ColumnNames, n, header_line, history, cols=None, dec=".", headerless=False
):
    """(index of the time column or None, indices of other clock columns).

    As given (``time_column=``), else the first column named like time or a clock (``time``,
    ``elapsed (s)``, ``epoc (ms)``, ``seconds_elapsed``) that holds numbers, else the first
    that holds time stamps, else (a file with no header row) a first column that reads as seconds
    (:func:`_seconds_column`).  The other clock columns are no channels.
    """
    tcol = None
    clocks = []
    if cols is not None and time_column is None:
        cand = [j for j, (nm, ut, _) in enumerate(colnames.split) if _is_clock_name(nm, ut)]
        numeric = [
            j
            for j in cand
            if isinstance(cols[j], np.ndarray)
            and cols[j].dtype.kind in "fiu"
            or _NUM[dec].fullmatch(str(_first_cell(cols[j])).strip())
        ]
        if cand:
            tcol = numeric[0] if numeric else cand[0]
            if numeric and numeric[0] != cand[0]:
                history.append(
                    f"time column '{colnames.shown[tcol]}' (numbers) chosen over "
                    f"'{colnames.shown[cand[0]]}' (text time stamps)"
                )
            clocks = [j for j in cand if j != tcol]
            for j in clocks:
                history.append(f"column '{colnames.shown[j]}' is another clock, not a channel")
        elif headerless and n >= 2:
            why = _seconds_column(cols[0])
            if why is not None:
                tcol = 0
                history.append(f"no header row; column 1 read as time in seconds ({why}; --time-column none if not)")
        return tcol, clocks
    if time_column is False:
        history.append(f"no time column ({spell('time_column', False)} given)")
    elif time_column is not None:
        if isinstance(time_column, (int, np.integer)) and not isinstance(time_column, bool):
            if not 0 <= int(time_column) < n:
                raise RecordingError(
                    path,
                    header_line,
                    f"{spell('time_column', int(time_column))} is out of range: the file has {n} column(s), numbered from 0",
                )
            tcol = int(time_column)
        else:
            tcol = colnames.match(time_column)
            if tcol is None:
                raise RecordingError(
                    path,
                    header_line,
                    f"no time column {time_column!r}; columns: " + ", ".join(repr(h) for h in colnames.shown),
                )
    else:
        for j, (nm, ut, _) in enumerate(colnames.split):
            if is_time_name(nm) and (ut is None or parse_unit(ut) is None):
                tcol = j
                break
    return tcol, clocks


def _seconds_column(cells):
    """Why a headerless file's first column is a clock in seconds (phone exports such as ADVIO's: ``0.0079,
    -0.73, 8.04, 6.03``), or None: finite numbers, strictly increasing, not all whole numbers (a sample
    counter is no clock), a median step of 10 us to 60 s whose steps stay within a factor of 5 of it in
    99 % of the rows (a clock that jitters, not a measured quantity that grows)."""
    try:
        t = np.asarray(cells, dtype=float) if isinstance(cells, np.ndarray) else np.array([float(c) for c in cells])
    except (TypeError, ValueError):
        return None
    if t.size < 3 or not np.all(np.isfinite(t)):
        return None
    dt = np.diff(t)
    if not np.all(dt > 0) or np.all(t == np.round(t)):
        return None
    step = float(np.median(dt))
    if not 1e-5 <= step <= 60.0 or np.mean((dt > 5 * step) | (dt < step / 5)) > 0.01:
        return None
    return f"strictly increasing, median step {step * 1e3:.4g} ms"


#: a calendar date alone (no clock): 2026-05-04, 04.05.2026, 5/4/26
_DATE_ONLY = re.compile(r"\s*(?:[0-9]{4}-[0-9]{1,2}-[0-9]{1,2}|[0-9]{1,2}[/.-][0-9]{1,2}[/.-][0-9]{2,4})\s*")


def _is_date_only(cells):
    return len(cells) > 0 and isinstance(cells[0], str) and bool(_DATE_ONLY.fullmatch(cells[0]))


def _is_time_of_day(cells):
    return len(cells) > 0 and isinstance(cells[0], str) and bool(_STAMP_TOD.fullmatch(cells[0].strip()))


def _date_and_time(tcol, clocks, cols, colnames: _ColumnNames, history):
    """(time column, other clocks, date column or None) where a date column and a time-of-day column together
    are the clock (a logger's ``Date,Time,...``): the time-of-day column is the time column, the date column
    gives its calendar date (and carries it over midnight). Otherwise as given, with no date column."""
    if tcol is None or cols is None:
        return tcol, clocks, None
    others = [j for j in range(len(cols)) if j != tcol]
    if _is_date_only(cols[tcol]):
        pick = [j for j in others if _is_time_of_day(cols[j])]
        if not pick:
            return tcol, clocks, None
        date_col, tcol = tcol, pick[0]
    elif _is_time_of_day(cols[tcol]):
        pick = [j for j in others if _is_date_only(cols[j])]
        if not pick:
            return tcol, clocks, None
        date_col = pick[0]
    else:
        return tcol, clocks, None
    stale = {f"column '{colnames.shown[j]}' is another clock, not a channel" for j in (tcol, date_col)}
    history[:] = [h for h in history if h not in stale]
    history.append(
        f"time stamps from column '{colnames.shown[date_col]}' (dates) and column '{colnames.shown[tcol]}' "
        "(times of day) together"
    )
    return tcol, [j for j in clocks if j not in (tcol, date_col)] + [date_col], date_col


def _joined_stamps(date_cells, time_cells):
    """Each row's date and time of day as one stamp (``2026-05-04 07:30:00.005``; ``04.05.2026 07:30:00``)."""
    d = pd.Series(date_cells, dtype=object).str.strip()
    # two-digit years: 20yy (a logger's dd.mm.yy)
    d = d.str.replace(r"^([0-9]{1,2}[/.-][0-9]{1,2}[/.-])([0-9]{2})$", r"\g<1>20\2", regex=True)
    # ISO dates of one-digit month or day padded, as ISO 8601 asks
    d = d.str.replace(r"^([0-9]{4})-([0-9])-", r"\1-0\2-", regex=True).str.replace(
        r"^([0-9]{4}-[0-9]{2})-([0-9])$", r"\1-0\2", regex=True
    )
    t = pd.Series(time_cells, dtype=object).str.strip()
    t = t.str.replace(r"^([0-9]):", r"0\1:", regex=True)
    t = t.str.replace(r"^([0-9]{2}:[0-9]{2}:[0-9]{2}):([0-9]+)$", r"\1.\2", regex=True)
    return (d + " " + t).to_numpy(dtype=object)


def _zone_note(start):
    """`` (no time zone in the file: taken as UTC)`` for a naive start stamp, else empty: a report's dates are UTC."""
    from datetime import datetime

    try:
        naive = datetime.fromisoformat(str(start)).tzinfo is None
    except ValueError:
        return ""
    return " (no time zone in the file: taken as UTC)" if naive else ""


def _read_time(
    path,
    tcells,
    tname,
    unit_text,
    dec,
    rownums,
    header_line,
    time_unit,
    rate_meta,
    history,
    extra_attrs,
    date_order=None,
):
    """Seconds from the cells ``tcells`` of time column ``tname``; start time and offset go to ``extra_attrs``."""
    numeric = isinstance(tcells, np.ndarray) and tcells.dtype.kind in "fiu"
    if numeric and tcells.dtype.kind == "f" and np.isnan(tcells).any():
        raise _Fallback("a missing time")  # the line-by-line reader quotes the cell
    stamps = (
        None if numeric or _NUM[dec].fullmatch(tcells[0]) else _parse_stamps(tcells, path, rownums, tname, date_order)
    )
    if stamps is not None:
        t, start, kind, ok = stamps
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            raise RecordingError(
                path, int(rownums[i]), f"expected a time stamp like '{start}' in column '{tname}', found '{tcells[i]}'"
            )
        history.append(f"time column '{tname}' holds {kind}; time = seconds since {start}{_zone_note(start)}")
        extra_attrs["start_time"] = start
    else:
        vals, missing, bad, inf = _parse_numbers(tcells, dec)
        badall = np.union1d(np.union1d(bad, inf), np.flatnonzero(missing))
        if badall.size:
            i = int(badall[0])
            hint = (
                "; it holds dates, which are no clock on their own: name the column of the times (--time-column NAME)"
                if re.fullmatch(r"\s*\d{1,4}[/.-]\d{1,2}[/.-]\d{1,4}\s*", str(tcells[i]))
                else ""
            )
            raise RecordingError(
                path, int(rownums[i]), f"expected a time in column '{tname}', found '{tcells[i]}'{hint}"
            )
        if time_unit is not None:
            f = parse_time_unit(time_unit)
            if f is None:
                raise ReaderOptionError(
                    "time_unit",
                    f"{spell('time_unit', time_unit)} is not a time unit (expected s, ms, us, ns, min, h) for {path}",
                )
            history.append(f"time column '{tname}' in {time_unit} (given)" + ("" if f == 1 else f" -> s (x {f:g})"))
        elif unit_text is not None and parse_time_unit(unit_text) is not None:
            f = parse_time_unit(unit_text)
            history.append(f"time column '{tname}' in {unit_text}" + ("" if f == 1 else f" -> s (x {f:g})"))
        elif unit_text is not None:
            raise RecordingError(
                path,
                header_line,
                f"time column '{tname}' has unit '{unit_text}'; expected s, ms, us or time stamps (pass {spell('time_unit')})",
            )
        else:
            f = 1.0
            step = float(np.median(np.diff(vals))) if vals.size > 1 else 0.0
            if rate_meta and step > 0 and abs(step * rate_meta[0] / 1e3 - 1) < 0.05:
                f = 1e-3
                history.append(
                    f"time column '{tname}' has no unit; read as ms because its steps match "
                    f"the header's sample rate {rate_meta[0]:g} Hz"
                )
            else:
                epoch = _epoch_unit(path, vals, tname, int(rownums[0]))
                if epoch is None and step > 1 and np.all(vals[:100_000] == np.round(vals[:100_000])):
                    f = _counter_clock_unit(path, vals, step, tname, header_line, history)
                elif epoch is None:
                    history.append(f"time column '{tname}' has no unit; read as s")
                else:
                    f, eunit = epoch
                    start = datetime.fromtimestamp(float(vals[0]) * f, tz=timezone.utc)
                    history.append(
                        f"time column '{tname}' has no unit; its values ({vals[0]:.17g} ...) are "
                        f"Unix epoch times in {eunit} by their size and steps; read as {eunit} "
                        f"(start {start.isoformat()}; pass {spell('time_unit')} to override)"
                    )
                    extra_attrs.setdefault("start_time", start.isoformat())
        if vals.size and "start_time" not in extra_attrs and _EPOCH_RANGE_S[0] <= vals[0] * f <= _EPOCH_RANGE_S[1]:
            # a Unix epoch column with its unit in the header (MetaWear 'epoc (ms)')
            extra_attrs["start_time"] = datetime.fromtimestamp(float(vals[0]) * f, tz=timezone.utc).isoformat()
        if vals.size and (abs(vals[0]) * f > 1e6 or (f == 1e-9 and vals[0] != 0)):  # epoch, or since boot
            extra_attrs["time_offset_s"] = float(vals[0] * f)
            history.append(f"time shifted by {vals[0] * f:.6f} s so that it starts at 0 (epoch-like values)")
            t = (vals - vals[0]) * f
        else:
            t = vals * f
    return t


#: sample rates plausible for a vibration record from a microcontroller clock [Hz]
_CLOCK_RATES_HZ = (1.0, 20e3)


def _counter_clock_unit(path, vals, step, tname, header_line, history):
    """Factor to s of a unitless integer time column whose steps, in seconds, give under 1 Hz.

    Such a column is a microcontroller clock: Arduino ``millis()`` (ms) or ``micros()`` (us).  The unit
    that gives a rate between 1 Hz and 20 kHz is chosen when only one does; otherwise the file is refused
    naming ``time_unit=``.
    """
    named = clock_units().get(tname.strip().lower())  # a clock function's name (Arduino millis) says its unit
    fits = (
        [named]
        if named is not None
        else [
            (u, f)
            for u, f in (("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9))
            if _CLOCK_RATES_HZ[0] <= 1 / (step * f) <= _CLOCK_RATES_HZ[1]
        ]
    )
    if len(fits) != 1:
        units = (("s", 1.0), ("ms", 1e-3), ("us", 1e-6))
        units += (("ns", 1e-9),) if 1 / (step * 1e-9) <= _CLOCK_RATES_HZ[1] else ()
        rates = ", ".join(f"{1 / (step * f):.4g} Hz in {u}" for u, f in units)
        raise RecordingError(
            path,
            header_line,
            f"time column '{tname}' has no unit and whole-number steps of "
            f"{step:.6g} ({rates}): cannot tell its unit; pass {spell('time_unit')} ({', '.join(u for u, _ in units)})",
        )
    u, f = fits[0]
    what = (
        f"a clock in {u} (its name, as the logger profile says)"
        if named is not None
        else "a clock counting nanoseconds (Android's SensorEvent.timestamp, since boot)"
        if u == "ns"
        else "a microcontroller clock (Arduino millis()/micros())"
    )
    history.append(
        f"time column '{tname}' has no unit and whole-number steps of {step:.6g}: {what}; read as {u}, "
        f"giving {1 / (step * f):.6g} Hz (in seconds it would be {1 / step:.3g} Hz); pass {spell('time_unit')} to override"
    )
    return f


def _date_order(cells, path, rownums, tname, date_order):
    """``"dmy"`` or ``"mdy"`` for numeric dates ``a/b/yyyy``: as given, else where a field above 12 says, else
    ``"dmy."`` for dotted dates (``04.05.2026``: day.month.year, as they are written).

    Other dates whose two first fields never exceed 12 could be either: refused, naming ``date_order=``.
    """
    parts = cells.str.extract(r"^([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]")
    a = pd.to_numeric(parts[0], errors="coerce").to_numpy()
    b = pd.to_numeric(parts[1], errors="coerce").to_numpy()
    if date_order is not None:
        return date_order
    day_first, month_first = np.flatnonzero(a > 12), np.flatnonzero(b > 12)
    if day_first.size and month_first.size:
        i, j = int(day_first[0]), int(month_first[0])
        raise RecordingError(
            path,
            int(rownums[j]),
            f"dates in column '{tname}' mix day/month/year ('{cells.iloc[i]}', line {int(rownums[i])}) and "
            f"month/day/year ('{cells.iloc[j]}'); expected one order",
        )
    if day_first.size:
        return "dmy"
    if month_first.size:
        return "mdy"
    if cells.str.match(r"^[0-9]{1,2}\.[0-9]{1,2}\.").all():
        return "dmy."  # dotted dates are day.month.year (month.day.year is written nowhere)
    raise RecordingError(
        path,
        int(rownums[0]),
        f"dates in column '{tname}' ('{cells.iloc[0]}' ...) could be day/month/year or month/day/year "
        f"(no field above 12 says which); pass {spell('date_order')} (dmy or mdy)",
    )


def _parse_stamps(cells, path=None, rownums=None, tname="time", date_order=None):
    """Seconds since the first stamp, the first stamp (as written; ISO 8601 for day/month/year stamps), the format
    name, which rows parsed; None if not stamps."""
    s = pd.Series(cells, dtype=object)
    first = s.iloc[0]
    if _STAMP_ISO.fullmatch(first):
        t = pd.to_datetime(s.str.replace(",", ".", regex=False), format="ISO8601", utc=True, errors="coerce")
        kind = "ISO 8601 timestamps"
        ok = t.notna().to_numpy()
    elif _STAMP_DMY.fullmatch(first):
        order = _date_order(s, path, rownums if rownums is not None else np.arange(1, s.size + 1), tname, date_order)
        dotted = order == "dmy."
        order = order[:3]
        swap = r"\3-\2-\1 " if order == "dmy" else r"\3-\1-\2 "
        norm = s.str.replace(r"^([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]([0-9]{4})[ T]", swap, regex=True)
        norm = norm.str.replace(",", ".", regex=False)
        t = pd.to_datetime(norm, format="ISO8601", errors="coerce")
        kind = (
            ("day/month/year" if order == "dmy" else "month/day/year")
            + " timestamps"
            + (
                " (date_order given)"
                if date_order
                else " (dotted: day.month.year)"
                if dotted
                else " (a field above 12 says the order)"
            )
        )
        ok = t.notna().to_numpy()
    elif _STAMP_TOD.fullmatch(first):
        norm = s.str.replace(r"^([0-9]{1,2}:[0-9]{2}:[0-9]{2})[.,:]([0-9]+)$", r"\1.\2", regex=True)
        t = pd.to_timedelta(
            norm.where(norm.str.fullmatch(r"[0-9]{1,2}:[0-9]{2}:[0-9]{2}(\.[0-9]+)?"), None), errors="coerce"
        )
        kind = "time-of-day stamps"
        ok = t.notna().to_numpy()
    else:
        return None
    if not ok[0]:
        return None
    secs = (t - t.iloc[0]).dt.total_seconds().to_numpy(dtype=float, na_value=np.nan)
    # the start as ISO 8601 where the stamps carry a date in another order (what reports and the fleet read)
    start = t.iloc[0].isoformat() if _STAMP_DMY.fullmatch(first) else str(first)
    return secs, start, kind, ok


def _epoch_unit(path, vals, tname, line):
    """(factor to s, unit) when a unitless time column holds Unix epoch times, else None."""
    v0 = float(vals[0])
    for unit, f in _EPOCH_UNITS:  # noqa: B007 (unit is used after the loop)
        if _EPOCH_RANGE_S[0] <= abs(v0) * f <= _EPOCH_RANGE_S[1]:
            break
    else:
        return None
    k = min(vals.size, 100_001)
    steps = np.diff(vals[:k])
    step = float(np.median(steps)) * f if steps.size else math.nan
    if step > 0 and not 1e-7 <= step <= 1e4:  # 10 MHz to one sample every 3 hours (repeats: check_order)
        raise RecordingError(
            path,
            line,
            f"time column '{tname}' has no unit and holds {v0:.17g}, a Unix epoch "
            f"time in {unit} by its size, but its steps ({step / f:.6g} {unit}) do not give a "
            f"sample rate between 1e-4 Hz and 10 MHz; pass {spell('time_unit')} (s, ms, us, ns)",
        )
    return f, unit
