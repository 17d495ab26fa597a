"""The work list as flat records for other systems: one row per unit, for CSV (a CMMS, a spreadsheet).

:func:`work_list_records` flattens what ``vibkit fleet status --json`` says of each unit
(:meth:`vibkit.fleet.trends.UnitTrend.as_dict`) into the columns :data:`RECORD_COLUMNS`: numbers as
numbers (SI or percent, as named), dates as UTC ISO 8601 text, booleans, None where there is no
value; :func:`write_csv` writes them so that a spreadsheet importer or ``pandas.read_csv`` reads
back the same values (floats in their shortest exact form, empty cells for None).
:func:`units_past_limit` names the units whose latest elongation has reached a limit (what a
scheduled job alerts on).
"""

from __future__ import annotations

import csv

__all__ = ["RECORD_COLUMNS", "work_list_records", "write_csv", "units_past_limit"]

#: the columns of one unit's record, in order (units: percent, m, UTC ISO 8601 dates)
RECORD_COLUMNS = (
    "rank",
    "unit",
    "n_measurements",
    "n_used",
    "first_date_utc",
    "latest_date_utc",
    "nominal_pitch_m",
    "latest_elongation_percent",
    "latest_elongation_sigma_percent",
    "latest_verdict",
    "slope_percent_per_year",
    "slope_sigma_percent_per_year",
    "rate_verdict",
    "over_limit_percent",
    "next_limit_percent",
    "next_limit_status",
    "next_limit_date_utc",
    "next_limit_earliest_utc",
    "next_limit_latest_utc",
    "overdue",
    "segment_start_utc",
    "flags",
    "links_statement",
)


def work_list_records(trends, today_unix_s, links=None) -> list[dict]:
    """One dict per unit (ranked :class:`~vibkit.fleet.trends.UnitTrend`), keyed by :data:`RECORD_COLUMNS`.

    ``links`` maps a unit to its :class:`~vibkit.fleet.links.UnitLinks` (its ``statement`` becomes
    ``links_statement``); ``flags`` are joined with ``"; "``.
    """
    out = []
    for t in trends:
        d = t.as_dict(today_unix_s)
        nxt = d.get("next_limit") or {}
        rec = {k: d.get(k) for k in RECORD_COLUMNS if k in d}
        rec.update(
            next_limit_percent=nxt.get("limit_percent"),
            next_limit_status=nxt.get("status"),
            next_limit_date_utc=nxt.get("date_utc"),
            next_limit_earliest_utc=nxt.get("earliest_utc"),
            next_limit_latest_utc=nxt.get("latest_utc"),
            overdue=bool(d.get("overdue", False)),
            flags="; ".join(d.get("flags", [])),
            links_statement=(links[t.unit].statement if links and t.unit in links else None),
        )
        out.append({k: rec.get(k) for k in RECORD_COLUMNS})
    return out


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)  # the shortest text that reads back as the same float
    return str(v)


def write_csv(records, stream) -> None:
    """Write ``records`` (:func:`work_list_records`) as CSV (RFC 4180, a header row) to a text stream."""
    w = csv.writer(stream, lineterminator="\n")
    w.writerow(RECORD_COLUMNS)
    for r in records:
        w.writerow([_cell(r[k]) for k in RECORD_COLUMNS])


def units_past_limit(trends, limit_percent) -> list[str]:
    """The units whose latest usable elongation has reached ``limit_percent`` (their highest reached limit). [%]"""
    return [t.unit for t in trends if t.over_limit_percent is not None and t.over_limit_percent >= limit_percent]
