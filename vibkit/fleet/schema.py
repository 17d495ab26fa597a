"""The fleet database's schema, shared by its SQLite and PostgreSQL stores.

One table, ``measurement``: one row per analysed recording (the fields of
:class:`~vibkit.fleet.measurement.Measurement`), ``sha256`` unique.  Schema version 2 added the quality
flag (``quality``, ``quality_reason``) and ``replaced`` (a chain replacement starts a new trend
segment); a version-1 SQLite file is upgraded in place, its rows flagged by the same rules, when it is
opened for writing.  Read-only use reads a version-1 file as it is, through :func:`upgraded_view_sql`:
a view that gives every row as the upgrade would have stored it, the file left untouched.

Schema version 3 added the link scans (:mod:`vibkit.fleet.links`): ``link_scan``, one row per measurement
(whether its links were scanned, the status, the numbering reference ``marker_s``), and ``flagged_link``,
one row per link a scan flagged; both cascade when their measurement is deleted.  An older file or server
is upgraded in place when opened for writing (every measurement gets a ``link_scan`` row "not run"); read
only, it is read as it is, every measurement "not run".

Schema version 4 added ``alternatives`` to ``flagged_link``: the other numbers of a link the recording cannot place
uniquely (a JSON list, ``[]`` when it is one number; "55 or 10").  A version-3 file or server gets the column (every
stored flag ``[]``) when opened for writing; read only, it is read as it is, its flags without alternatives.

Schema version 5 stores a speed uncertainty that was not stated as ``NULL`` in ``speed_sigma_m_s`` (until version 4
the column was ``NOT NULL`` and 0 meant "not stated", so a sigma stated as 0, an exact speed, could not be kept).  An
older SQLite file's table is rebuilt without the ``NOT NULL`` (SQLite cannot drop it in place) and a PostgreSQL
column loses it by ``ALTER TABLE``; in both, the stored 0s become ``NULL``, which is what they meant then.  Read
only, an older history is read as it is, its 0s read as "not stated" (:data:`SIGMA_ZERO_UNSTATED_BEFORE`).
"""

from __future__ import annotations

import datetime as _dt
import json
import math

from .measurement import Measurement

__all__ = [
    "APPLICATION_ID",
    "COLUMNS",
    "SCHEMA_VERSION",
    "measurement_ddl",
    "row_to_measurement",
    "measurement_values",
    "upgraded_view_sql",
    "QUALITY_FLAG_SQL",
    "QUALITY_REASON_SQL",
    "LINK_STATUSES",
    "link_ddl",
    "FLAG_ALTERNATIVES_DDL",
    "SIGMA_ZERO_UNSTATED_BEFORE",
    "SIGMA_UNSTATED_SQL",
]

SCHEMA_VERSION = 5
#: histories of a schema version below this one stored a speed uncertainty that was not stated as 0 (version 5: NULL)
SIGMA_ZERO_UNSTATED_BEFORE = 5
#: what the upgrade to version 5 runs on the old rows: their 0s meant "not stated"
SIGMA_UNSTATED_SQL = "UPDATE measurement SET speed_sigma_m_s = NULL WHERE speed_sigma_m_s = 0"
#: SQLite ``PRAGMA application_id`` of a vibkit fleet database ("VBKF"); PostgreSQL: its advisory lock key
APPLICATION_ID = 0x56424B46
#: stored columns, in :class:`Measurement` order (without ``id``)
COLUMNS = tuple(f for f in Measurement.__dataclass_fields__ if f != "id")

_TYPES = {  # column: (SQLite type, PostgreSQL type, constraint)
    "unit": ("TEXT", "TEXT", "NOT NULL CHECK (length(unit) > 0)"),
    "date_utc": ("TEXT", "TEXT", "NOT NULL"),
    "date_unix_s": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "date_source": ("TEXT", "TEXT", "NOT NULL"),
    "speed_m_s": ("REAL", "DOUBLE PRECISION", "NOT NULL CHECK (speed_m_s > 0)"),
    "speed_sigma_m_s": ("REAL", "DOUBLE PRECISION", "CHECK (speed_sigma_m_s IS NULL OR speed_sigma_m_s >= 0)"),
    "nominal_pitch_m": ("REAL", "DOUBLE PRECISION", "NOT NULL CHECK (nominal_pitch_m > 0)"),
    "channel": ("TEXT", "TEXT", "NOT NULL"),
    "fundamental_hz": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "fundamental_sigma_hz": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "pitch_m": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "pitch_sigma_m": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "elongation_percent": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "elongation_sigma_percent": ("REAL", "DOUBLE PRECISION", "NOT NULL"),
    "snr_db": ("REAL", "DOUBLE PRECISION", ""),
    "warnings": ("TEXT", "TEXT", "NOT NULL"),
    "sha256": ("TEXT", "TEXT", "NOT NULL UNIQUE CHECK (length(sha256) = 64)"),
    "path": ("TEXT", "TEXT", "NOT NULL"),
    "size_bytes": ("INTEGER", "BIGINT", "NOT NULL"),
    "vibkit_version": ("TEXT", "TEXT", "NOT NULL"),
    "analysed_utc": ("TEXT", "TEXT", "NOT NULL"),
    "quality": ("TEXT", "TEXT", "NOT NULL DEFAULT 'ok' CHECK (quality IN ('ok', 'inconclusive', 'implausible'))"),
    "quality_reason": ("TEXT", "TEXT", "NOT NULL DEFAULT ''"),
    "replaced": ("INTEGER", "BOOLEAN", "NOT NULL DEFAULT {false}"),
}
assert set(_TYPES) == set(COLUMNS)
#: columns added by schema version 2 (a version-1 SQLite file gets them by ALTER TABLE)
V2_COLUMNS = ("quality", "quality_reason", "replaced")


#: SQL functions the SQLite store registers for :func:`upgraded_view_sql`: the quality flag and its reason of
#: (elongation_percent, elongation_sigma_percent), by :func:`vibkit.fleet.quality.measurement_quality`
QUALITY_FLAG_SQL, QUALITY_REASON_SQL = "vibkit_quality_flag", "vibkit_quality_reason"
#: what the upgrade to version 2 stores in a column a version-1 row lacks (before the quality flag is set)
_V2_DEFAULTS = {"quality": "'ok'", "quality_reason": "''", "replaced": "0"}


def signature_problem(have_columns):
    """What keeps a ``measurement`` table with these columns from being vibkit's (None when it is, of any
    schema version vibkit reads): checked before anything is written into a database."""
    have = set(have_columns)
    missing = [c for c in ("id",) + COLUMNS if c not in have and c not in _V2_DEFAULTS]
    if not missing:
        return None
    shown = ", ".join(sorted(have)) or "none"
    return (
        f"not a vibkit fleet database: its table 'measurement' (columns {shown}) lacks "
        f"{', '.join(missing[:4])}{' ...' if len(missing) > 4 else ''}; refusing to read or write it "
        "(--db names another database)"
    )


def upgraded_view_sql(have_columns, name="temp.measurement", source="main.measurement"):
    """``CREATE VIEW`` of an older ``measurement`` table with the columns it has (``have_columns``), giving
    every row exactly as the upgrade to :data:`SCHEMA_VERSION` would store it (the same defaults, the quality
    flag by today's rules on the rows still ``'ok'``), without writing into the table.  A ``temp`` view needs no
    write access to the file: read-only use of an old file reads its rows through it, one at a time (no copy)."""
    have = set(have_columns)
    missing = [c for c in ("id",) + COLUMNS if c not in have and c not in _V2_DEFAULTS]
    if missing:
        raise ValueError(f"the measurement table lacks {', '.join(missing)}; not a vibkit schema this one reads")
    base = {c: (c if c in have else _V2_DEFAULTS[c]) for c in V2_COLUMNS}
    ok = f"({base['quality']}) = 'ok'"
    e = "elongation_percent, elongation_sigma_percent"
    expr = dict(base)
    expr["quality"] = f"CASE WHEN {ok} THEN {QUALITY_FLAG_SQL}({e}) ELSE {base['quality']} END"
    expr["quality_reason"] = (
        f"CASE WHEN {ok} AND {QUALITY_FLAG_SQL}({e}) != 'ok' THEN {QUALITY_REASON_SQL}({e}) "
        f"ELSE {base['quality_reason']} END"
    )
    cols = ", ".join(["id"] + [f"{expr[c]} AS {c}" if c in expr else c for c in COLUMNS])
    return f"CREATE VIEW {name} AS SELECT {cols} FROM {source}"


def column_def(col, dialect):
    sq, pg, cons = _TYPES[col]
    cons = cons.format(false="FALSE" if dialect == "postgresql" else "0")
    return f"{col} {pg if dialect == 'postgresql' else sq} {cons}".rstrip()


def measurement_ddl(dialect, table="measurement"):
    """``CREATE TABLE`` and ``CREATE INDEX`` statements for ``"sqlite"`` or ``"postgresql"`` (``table``: another
    name for the table, as the SQLite upgrade to version 5 builds it before it replaces the old one)."""
    ident = "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY" if dialect == "postgresql" else "INTEGER PRIMARY KEY"
    cols = ",\n    ".join([f"id {ident}"] + [column_def(c, dialect) for c in COLUMNS])
    return [
        f"CREATE TABLE IF NOT EXISTS {table} (\n    {cols}\n)",
        "CREATE INDEX IF NOT EXISTS measurement_unit_date ON measurement (unit, date_unix_s)",
    ]


#: the status of a measurement's link scan: scanned ("ok": flagged links or none), "inconclusive" (deviations
#: no link number can be given for), "too few loops" (the recording covers fewer than two loops of the chain),
#: "failed" (the scan stopped on an error, named in the reason), "not run" (not attempted: the reason says why)
LINK_STATUSES = ("ok", "inconclusive", "too few loops", "failed", "not run")


#: the column that schema version 4 added to ``flagged_link`` (a version-3 table gets it by ALTER TABLE)
FLAG_ALTERNATIVES_DDL = "alternatives TEXT NOT NULL DEFAULT '[]'"


def link_ddl(dialect):
    """``CREATE TABLE`` statements of the link scans (schema versions 3 and 4) for ``"sqlite"`` or ``"postgresql"``."""
    pg = dialect == "postgresql"
    real, mid = ("DOUBLE PRECISION", "BIGINT") if pg else ("REAL", "INTEGER")
    statuses = ", ".join(f"'{s}'" for s in LINK_STATUSES)
    return [
        f"""CREATE TABLE IF NOT EXISTS link_scan (
    measurement_id {mid} PRIMARY KEY REFERENCES measurement (id) ON DELETE CASCADE,
    status TEXT NOT NULL CHECK (status IN ({statuses})),
    reason TEXT NOT NULL DEFAULT '',
    n_links INTEGER CHECK (n_links IS NULL OR n_links >= 2),
    loops INTEGER,
    marker_s {real} CHECK (marker_s IS NULL OR marker_s >= 0),
    method TEXT NOT NULL DEFAULT '',
    false_alarm {real}
)""",
        f"""CREATE TABLE IF NOT EXISTS flagged_link (
    measurement_id {mid} NOT NULL REFERENCES link_scan (measurement_id) ON DELETE CASCADE,
    link INTEGER NOT NULL CHECK (link >= 1),
    excess_pitch_m {real},
    sigma_m {real} CHECK (sigma_m IS NULL OR sigma_m >= 0),
    statistic {real},
    feature TEXT NOT NULL DEFAULT '',
    loops TEXT NOT NULL DEFAULT '[]',
    {FLAG_ALTERNATIVES_DDL},
    PRIMARY KEY (measurement_id, link)
)""",
    ]


def measurement_values(m: Measurement) -> list:
    """The row values of a measurement, in :data:`COLUMNS` order."""
    out = []
    for c in COLUMNS:
        v = getattr(m, c)
        out.append(json.dumps(list(v)) if c == "warnings" else bool(v) if c == "replaced" else v)
    return out


def _checked_row(d):
    """Raise ValueError naming the column when a row holds what vibkit never writes (a value another tool
    put there: text in a number column, NaN, a date that is not a date)."""
    for c in COLUMNS:
        v = d[c]
        if _TYPES[c][0] == "REAL" and not (v is None and c in ("snr_db", "speed_sigma_m_s")):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"column {c} holds {v!r}, not a finite number")
    if not -62135596800.0 < d["date_unix_s"] < 253402300800.0:  # years 1-9999, what a calendar date can be
        raise ValueError(f"column date_unix_s holds {d['date_unix_s']!r}, not seconds since 1970 of a date")
    try:
        _dt.datetime.fromisoformat(str(d["date_utc"]).replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(f"column date_utc holds {d['date_utc']!r}, not an ISO 8601 date") from None


def row_to_measurement(row, *, zero_sigma_unstated=False) -> Measurement:
    """A :class:`Measurement` from a row ``(id, *COLUMNS)``; ``zero_sigma_unstated``: the row is of a history older
    than schema version 5 read as it is, whose ``speed_sigma_m_s`` 0 means "not stated" (read as None).

    Raises
    ------
    ValueError
        The row holds a value vibkit never writes (the message names the measurement and the column).
    """
    d = dict(zip(("id",) + COLUMNS, row))
    try:
        _checked_row(d)
        d["warnings"] = tuple(json.loads(d["warnings"]))
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"measurement #{d['id']}: {exc}; the row was changed outside vibkit (correct or delete it)"
        ) from None
    d["replaced"] = bool(d["replaced"])
    if zero_sigma_unstated and d["speed_sigma_m_s"] == 0:
        d["speed_sigma_m_s"] = None
    return Measurement(**d)
