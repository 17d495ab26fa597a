"""Measurement history of a fleet of escalators: pitch and elongation over time, trends, forecasts.

Maintenance firms measure each escalator (a *unit*) again and again.  :class:`FleetDB` keeps every
measurement in an embedded SQLite database (standard library; WAL journal, one transaction per
measurement): the link-pass estimate of :func:`vibkit.diagnose.pitch.estimate_pitch`, the pitch and the
elongation with their standard deviations, quality figures (SNR, warnings) and provenance (SHA-256
of the file, its path, vibkit's version, the time of analysis).  A file already stored (same
SHA-256) is refused, so re-running a scan skips what it has done.

:meth:`FleetDB.scan` analyses a folder of recordings on a Dask cluster
(:func:`vibkit.runtime.cluster.dask_client`); the workers only analyse, the calling process alone writes,
one committed transaction per recording, so a killed scan leaves complete rows only.

:meth:`FleetDB.status` fits, per unit, the elongation against time by weighted least squares
(:func:`fit_trend`, a pure function) and forecasts when each elongation limit will be reached
(:func:`forecast_limits`), ranking the units by urgency (:class:`UnitTrend`).

The catalogue of a scan is a CSV file (``#`` starts a comment line) with these columns, in any
order (header names are case-insensitive):

========================  ========  ============================================================
column                    required  meaning
========================  ========  ============================================================
``file``                  yes       file name, path relative to the scanned folder, or a glob
                                    (``E07/*.csv``); an exact name wins over a glob, else the
                                    first matching line
``unit``                  yes       escalator identifier
``speed_m_s``             yes       chain (step) speed measured on the steps or handrail [m/s]
``date``                  yes       measurement date, ISO 8601 (``2026-11-23``,
                                    ``2026-11-23T10:15:00+01:00``); empty: the recording's start
                                    time; dates without a time zone are UTC
``nominal_pitch_m``       yes       nominal link pitch [m]; empty: the unit's value from another
                                    line of the catalogue or from the database
``speed_sigma_m_s``       no        standard deviation of the speed [m/s] (default 0)
``channel``               no        channel to analyse (default: the first)
========================  ========  ============================================================

Dates are stored as UTC ISO 8601 text and as seconds since 1970 (``date_unix_s``); trends are in
percent per Julian year (365.25 days).
"""

from __future__ import annotations

import csv
import datetime as _dt
import fnmatch
import hashlib
import io
import json
import math
import os
import posixpath
import re
import sqlite3
from dataclasses import asdict, dataclass, field

import numpy as np

from ..diagnose.pitch import DEFAULT_LIMITS_PERCENT, elongation_verdict

__all__ = [
    "DB_ENV",
    "DEFAULT_DB_NAME",
    "CATALOGUE_COLUMNS",
    "CatalogueRow",
    "DuplicateRecordingError",
    "FleetDB",
    "FleetError",
    "LimitForecast",
    "Measurement",
    "ScanResult",
    "TrendFit",
    "UnitTrend",
    "analyse_recording",
    "fit_trend",
    "forecast_limits",
    "parse_date",
    "read_catalogue",
    "resolve_db_path",
]

#: environment variable naming the fleet database (a path or a ``sqlite:///path`` URL)
DB_ENV = "VIBKIT_FLEET_DB"
#: database file used when neither ``--db`` nor :data:`DB_ENV` names one (current directory)
DEFAULT_DB_NAME = "vibkit-fleet.sqlite"
#: required and optional catalogue columns
CATALOGUE_COLUMNS = ("file", "unit", "speed_m_s", "date", "nominal_pitch_m")
CATALOGUE_OPTIONAL = ("speed_sigma_m_s", "channel")
SECONDS_PER_YEAR = 365.25 * 86400.0
SCHEMA_VERSION = 1
#: SQLite ``PRAGMA application_id`` of a vibkit fleet database ("VBKF")
APPLICATION_ID = 0x56424B46
#: file suffixes a scan treats as recordings
RECORDING_SUFFIXES = (".csv", ".txt", ".tsv", ".dat", ".log", ".nc", ".nc4", ".h5", ".hdf5", ".mseed", ".miniseed",
                      ".msd", ".seed", ".sac")
_SQLITE_MAGIC = b"SQLite format 3\x00"


class FleetError(ValueError):
    """A problem with the fleet's inputs (database, catalogue, options), in one line."""


class DuplicateRecordingError(FleetError):
    """The recording is already stored (same SHA-256); ``existing`` is the stored :class:`Measurement`."""

    def __init__(self, message, existing):
        super().__init__(message)
        self.existing = existing


# ------------------------------------------------------------------------------------------ dates


_DMY = re.compile(r"([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]([0-9]{4})(?:[ T](.*))?")


def parse_date(text, *, what="date") -> _dt.datetime:
    """A timezone-aware UTC datetime from ISO 8601 text (or day/month/year as loggers write it).

    A date without time is midnight; a time without zone is UTC.  Dates before 1900 or more than a
    day in the future are refused (a measurement cannot be in the future).

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
    if m:
        t = f"{m.group(3)}-{int(m.group(2)):02d}-{int(m.group(1)):02d}" + (f"T{m.group(4)}" if m.group(4) else "")
    if re.match(r"^[0-9]{1,2}:[0-9]{2}", t):
        raise FleetError(f"{what} {s!r} has no calendar date (a time of day only)")
    try:
        d = _dt.datetime.fromisoformat(t)
    except ValueError:
        raise FleetError(f"{what} {s!r} is not an ISO 8601 date (expected e.g. 2026-11-23 or "
                         "2026-11-23T10:15:00+01:00)") from None
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    d = d.astimezone(_dt.timezone.utc)
    if d.year < 1900:
        raise FleetError(f"{what} {s!r} is before 1900; expected the date of the measurement")
    if d > _dt.datetime.now(_dt.timezone.utc) + _dt.timedelta(days=1):
        raise FleetError(f"{what} {s!r} lies in the future; expected the date of the measurement")
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


# ------------------------------------------------------------------------------------ trend, forecast


@dataclass(frozen=True)
class TrendFit:
    """Weighted least-squares line ``e(t) = e_ref + slope (t - t_ref)`` of elongation against time.

    Attributes
    ----------
    n : int
        Measurements fitted.
    t_ref_unix_s : float
        Reference time: the weighted mean of the times (there intercept and slope are uncorrelated).
        [s since 1970]
    elongation_ref_percent, elongation_ref_sigma_percent : float
        Fitted elongation at ``t_ref`` and its standard deviation. [%]
    slope_percent_per_year, slope_sigma_percent_per_year : float
        Elongation rate and its standard deviation. [%/year]
    chi2_per_dof : float
        Weighted residual sum over ``n - 2`` (NaN for two measurements).
    sigma_scale : float
        Factor applied to the sigmas: ``max(1, sqrt(chi2_per_dof))`` (1 for two measurements).
    """

    n: int
    t_ref_unix_s: float
    elongation_ref_percent: float
    elongation_ref_sigma_percent: float
    slope_percent_per_year: float
    slope_sigma_percent_per_year: float
    chi2_per_dof: float
    sigma_scale: float

    def elongation_at(self, t_unix_s):
        """Fitted elongation at times [s since 1970]. [%]"""
        return self.elongation_ref_percent + self.slope_percent_per_year * (
            (np.asarray(t_unix_s, dtype=float) - self.t_ref_unix_s) / SECONDS_PER_YEAR)


def fit_trend(t_unix_s, elongation_percent, sigma_percent) -> TrendFit:
    """Weighted least-squares trend of elongation against time, with the slope's uncertainty.

    Parameters
    ----------
    t_unix_s : array_like
        Measurement times. [s since 1970]
    elongation_percent : array_like
        Elongations. [%]
    sigma_percent : array_like
        Their standard deviations (> 0). [%]

    Returns
    -------
    TrendFit

    Raises
    ------
    ValueError
        Fewer than two measurements, arrays of different lengths, non-finite values, a sigma that is
        not positive, or all measurements at the same time.

    Notes
    -----
    With weights ``w_i = 1 / sigma_i^2``, ``t_ref = sum(w t) / sum(w)`` and ``tau = (t - t_ref)`` in
    years:

        slope = sum(w tau e) / sum(w tau^2),   e_ref = sum(w e) / sum(w),
        sigma_slope^2 = 1 / sum(w tau^2),      sigma_ref^2 = 1 / sum(w).

    When the residuals scatter more than the sigmas allow (``chi2 / (n - 2) > 1``: speed errors,
    sensor moved between visits), both sigmas are multiplied by ``sqrt(chi2 / (n - 2))`` (the Birge
    ratio); they are never reduced.
    """
    t = np.asarray(t_unix_s, dtype=float).ravel()
    e = np.asarray(elongation_percent, dtype=float).ravel()
    s = np.asarray(sigma_percent, dtype=float).ravel()
    if not t.size == e.size == s.size:
        raise ValueError(f"t_unix_s, elongation_percent and sigma_percent must have the same length, got "
                         f"{t.size}, {e.size}, {s.size}")
    if t.size < 2:
        raise ValueError(f"a trend needs at least two measurements, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(e)) and np.all(np.isfinite(s))):
        raise ValueError("t_unix_s, elongation_percent and sigma_percent must be finite")
    if np.any(s <= 0):
        raise ValueError(f"sigma_percent must be > 0, got {s[s <= 0][0]!r}")
    w = 1.0 / s**2
    t_ref = float(np.sum(w * t) / np.sum(w))
    tau = (t - t_ref) / SECONDS_PER_YEAR
    stt = float(np.sum(w * tau**2))
    if not stt > 0 or np.ptp(t) < 1.0:
        raise ValueError("a trend needs measurements at different times (all share one date)")
    e_ref = float(np.sum(w * e) / np.sum(w))
    slope = float(np.sum(w * tau * (e - e_ref)) / stt)
    chi2 = float(np.sum(w * (e - e_ref - slope * tau) ** 2))
    dof = t.size - 2
    chi2_dof = chi2 / dof if dof > 0 else float("nan")
    scale = max(1.0, math.sqrt(chi2_dof)) if dof > 0 else 1.0
    return TrendFit(int(t.size), t_ref, e_ref, scale / math.sqrt(float(np.sum(w))), slope, scale / math.sqrt(stt),
                    chi2_dof, scale)


@dataclass(frozen=True)
class LimitForecast:
    """When a unit reaches one elongation limit.

    Attributes
    ----------
    limit_percent : float
        [%]
    status : str
        ``"reached"`` (the latest measurement is at or over the limit), ``"forecast"`` (the slope is
        significantly positive: a date and an interval), ``"not before"`` (the slope is not
        significantly positive but may be: only the earliest date is known) or ``"none"`` (no
        growth within the uncertainty, or fewer than two measurements).
    date_utc : str or None
        Forecast date where the fitted line reaches the limit (``"forecast"``).
    earliest_utc, latest_utc : str or None
        The interval from the slope's (and the intercept's) ``coverage_sigma`` bounds.
    """

    limit_percent: float
    status: str
    date_utc: str | None = None
    earliest_utc: str | None = None
    latest_utc: str | None = None

    def urgency_unix_s(self):
        """Date used to rank units: the forecast, else the earliest date; +inf without one."""
        d = self.date_utc or self.earliest_utc
        return _dt.datetime.fromisoformat(d).timestamp() if d else math.inf


def forecast_limits(fit, limits_percent=DEFAULT_LIMITS_PERCENT, *, latest_elongation_percent=None,
                    coverage_sigma=2.0):
    """Dates at which the fitted trend reaches each elongation limit, with an interval.

    Parameters
    ----------
    fit : TrendFit or None
        The unit's trend (None: fewer than two measurements, every limit not reached is ``"none"``).
    limits_percent : sequence of float
        Elongation limits. [%]
    latest_elongation_percent : float, optional
        The latest measured elongation; a limit it reaches is ``"reached"``. [%]
    coverage_sigma : float
        Half-width of the intervals in standard deviations (2: about 95 %).

    Returns
    -------
    tuple of LimitForecast

    Notes
    -----
    The slope is *significantly positive* when ``slope > k sigma_slope`` (``k = coverage_sigma``).
    Then the forecast is ``t_ref + (L - e_ref) / slope`` and the interval the extreme crossing times
    of the lines with ``e_ref +- k sigma_ref`` and ``slope +- k sigma_slope``.  When only
    ``slope + k sigma_slope > 0``, the limit is reached *not before* the crossing of the steepest of
    those lines; when even that is not positive, no date is given.
    """
    k = float(coverage_sigma)
    if not (math.isfinite(k) and k > 0):
        raise ValueError(f"coverage_sigma must be > 0, got {coverage_sigma!r}")
    out = []
    for lim in limits_percent:
        lim = float(lim)
        if latest_elongation_percent is not None and latest_elongation_percent >= lim:
            out.append(LimitForecast(lim, "reached"))
            continue
        if fit is None:
            out.append(LimitForecast(lim, "none"))
            continue
        b, sb = fit.slope_percent_per_year, fit.slope_sigma_percent_per_year
        a, sa = fit.elongation_ref_percent, fit.elongation_ref_sigma_percent
        year = SECONDS_PER_YEAR

        def cross(a_, b_):
            return fit.t_ref_unix_s + (lim - a_) / b_ * year

        if b > k * sb:
            corners = [cross(a_, b_) for a_ in (a - k * sa, a + k * sa) for b_ in (b - k * sb, b + k * sb)]
            out.append(LimitForecast(lim, "forecast", _unix_to_iso(cross(a, b)), _unix_to_iso(min(corners)),
                                     _unix_to_iso(max(corners))))
        elif b + k * sb > 0:
            out.append(LimitForecast(lim, "not before", None, _unix_to_iso(cross(a + k * sa, b + k * sb)), None))
        else:
            out.append(LimitForecast(lim, "none"))
    return tuple(out)


# ----------------------------------------------------------------------------------------- records


@dataclass(frozen=True)
class Measurement:
    """One stored measurement (a row of the database).  Lengths [m], speeds [m/s], elongation [%]."""

    id: int | None
    unit: str
    date_utc: str
    date_unix_s: float
    date_source: str
    speed_m_s: float
    speed_sigma_m_s: float
    nominal_pitch_m: float
    channel: str
    fundamental_hz: float
    fundamental_sigma_hz: float
    pitch_m: float
    pitch_sigma_m: float
    elongation_percent: float
    elongation_sigma_percent: float
    snr_db: float | None
    warnings: tuple
    sha256: str
    path: str
    size_bytes: int
    vibkit_version: str
    analysed_utc: str

    def as_dict(self) -> dict:
        d = asdict(self)
        d["warnings"] = list(self.warnings)
        return d


_COLUMNS = tuple(f for f in Measurement.__dataclass_fields__ if f != "id")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS measurement (
    id INTEGER PRIMARY KEY,
    unit TEXT NOT NULL CHECK (length(unit) > 0),
    date_utc TEXT NOT NULL,
    date_unix_s REAL NOT NULL,
    date_source TEXT NOT NULL,
    speed_m_s REAL NOT NULL CHECK (speed_m_s > 0),
    speed_sigma_m_s REAL NOT NULL CHECK (speed_sigma_m_s >= 0),
    nominal_pitch_m REAL NOT NULL CHECK (nominal_pitch_m > 0),
    channel TEXT NOT NULL,
    fundamental_hz REAL NOT NULL,
    fundamental_sigma_hz REAL NOT NULL,
    pitch_m REAL NOT NULL,
    pitch_sigma_m REAL NOT NULL,
    elongation_percent REAL NOT NULL,
    elongation_sigma_percent REAL NOT NULL,
    snr_db REAL,
    warnings TEXT NOT NULL,
    sha256 TEXT NOT NULL UNIQUE CHECK (length(sha256) = 64),
    path TEXT NOT NULL,
    size_bytes INTEGER NOT NULL,
    vibkit_version TEXT NOT NULL,
    analysed_utc TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS measurement_unit_date ON measurement (unit, date_unix_s);
"""


def _file_sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def analyse_recording(path, *, unit, speed, speed_sigma=0.0, nominal_pitch, date=None, channel=None):
    """Read and analyse one recording; the :class:`Measurement` it gives (not stored, ``id`` None).

    Parameters
    ----------
    path : str or os.PathLike
        The recording (any format :func:`vibkit.read_recording` reads).
    unit : str
        Escalator identifier.
    speed, speed_sigma : float
        Chain speed and its standard deviation. [m/s]
    nominal_pitch : float
        Nominal link pitch. [m]
    date : str or datetime, optional
        Measurement date (ISO 8601); default the recording's start time.
    channel : str, optional

    Raises
    ------
    FleetError
        No date (neither given nor in the recording), or no link-pass found in the recording.
    RecordingError, ValueError
        The file cannot be read, or an option is invalid.
    """
    import vibkit
    from vibkit.io import read_recording
    from vibkit.diagnose.pitch import estimate_pitch

    unit = str(unit).strip()
    if not unit:
        raise FleetError("unit must be a non-empty identifier")
    if nominal_pitch is None or not (math.isfinite(float(nominal_pitch)) and float(nominal_pitch) > 0):
        raise FleetError(f"nominal_pitch must be a positive length [m], got {nominal_pitch!r}")
    spath = os.fspath(path)
    rec = read_recording(spath, channel=channel)
    if isinstance(date, _dt.datetime):
        d, source = (date if date.tzinfo else date.replace(tzinfo=_dt.timezone.utc)), "given"
    elif date is not None and str(date).strip():
        d, source = parse_date(date), "given"
    else:
        start = rec.attrs.get("start_time")
        if start is None:
            raise FleetError(f"{spath}: the recording has no start time; give the measurement date "
                             "(--date, or the catalogue's date column) as ISO 8601, e.g. 2026-11-23")
        try:
            d = parse_date(start, what="the recording's start time")
        except FleetError as exc:
            raise FleetError(f"{spath}: {exc}; give the measurement date (--date, or the catalogue's date column)") \
                from None
        source = "recording start time"
    try:
        est = estimate_pitch(rec, speed=speed, speed_sigma=speed_sigma, channel=channel, nominal_pitch=nominal_pitch)
    except ValueError as exc:
        raise FleetError(f"{spath}: {' '.join(str(exc).split())}") from None
    detected = getattr(est, "detected", None)
    if detected is None:  # before PitchEstimate carried a verdict: no harmonic above its 3-sigma level
        detected = any(h.get("detected", False) for h in est.harmonics)
    if not detected:
        status = getattr(est, "status", "no link-pass found")
        raise FleetError(f"{spath}: {status} (SNR {est.snr_db:.1f} dB); nothing stored")
    snr = float(est.snr_db) if math.isfinite(est.snr_db) else None
    return Measurement(
        id=None, unit=unit, date_utc=_iso(d), date_unix_s=d.timestamp(), date_source=source,
        speed_m_s=float(est.speed_m_s), speed_sigma_m_s=float(est.speed_sigma_m_s),
        nominal_pitch_m=float(est.nominal_pitch_m), channel=str(est.channel), fundamental_hz=float(est.fundamental_hz),
        fundamental_sigma_hz=float(est.fundamental_sigma_hz), pitch_m=float(est.pitch_m),
        pitch_sigma_m=float(est.pitch_sigma_m), elongation_percent=float(est.elongation_percent),
        elongation_sigma_percent=float(est.elongation_sigma_percent), snr_db=snr, warnings=tuple(est.warnings),
        sha256=str(rec.attrs["sha256"]), path=os.path.abspath(spath), size_bytes=os.path.getsize(spath),
        vibkit_version=vibkit.__version__,
        analysed_utc=_iso(_dt.datetime.now(_dt.timezone.utc)))


# --------------------------------------------------------------------------------------- catalogue


@dataclass(frozen=True)
class CatalogueRow:
    """One line of a scan catalogue (see the module docstring for the columns)."""

    line: int
    file: str
    unit: str
    speed_m_s: float
    speed_sigma_m_s: float = 0.0
    date: str | None = None
    nominal_pitch_m: float | None = None
    channel: str | None = None

    @property
    def is_glob(self) -> bool:
        return any(c in self.file for c in "*?[")


def _number(text, path, line, col, *, lo, hi, unit, hint=""):
    try:
        v = float(text)
    except ValueError:
        raise FleetError(f"{path}, line {line}: column {col}: expected a number [{unit}], got {text!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi) or (lo == 0 and v == 0 and col != "speed_sigma_m_s"):
        raise FleetError(f"{path}, line {line}: column {col}: {text!r} is outside {lo:g}-{hi:g} {unit}{hint}")
    return v


def read_catalogue(path):
    """Read and validate a scan catalogue (CSV); a list of :class:`CatalogueRow`.

    Raises
    ------
    FleetError
        Missing file, missing or unknown columns, a line with too few or too many cells, an empty
        file/unit/speed, a value that is not a number or not plausible, a bad date, or two nominal
        pitches for one unit; the message names the file and the line.
    """
    spath = os.fspath(path)
    try:
        with open(spath, "rb") as fh:
            raw = fh.read()
    except FileNotFoundError:
        raise FleetError(f"{spath}: catalogue not found") from None
    except OSError as exc:
        raise FleetError(f"{spath}: catalogue cannot be read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    lines = [(i, ln) for i, ln in enumerate(text.splitlines(), 1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise FleetError(f"{spath}: catalogue is empty; expected a header line with columns "
                         f"{', '.join(CATALOGUE_COLUMNS)}")
    head_line, head = lines[0]
    delim = ";" if head.count(";") > head.count(",") else ","
    cells = lambda s: next(csv.reader(io.StringIO(s), delimiter=delim, skipinitialspace=True))  # noqa: E731
    header = [c.strip().lower() for c in cells(head)]
    missing = [c for c in CATALOGUE_COLUMNS if c not in header]
    if missing:
        raise FleetError(f"{spath}, line {head_line}: missing column(s) {', '.join(missing)}; a catalogue has the "
                         f"columns {', '.join(CATALOGUE_COLUMNS)} (optional: {', '.join(CATALOGUE_OPTIONAL)})")
    unknown = [c for c in header if c not in CATALOGUE_COLUMNS + CATALOGUE_OPTIONAL]
    if unknown:
        raise FleetError(f"{spath}, line {head_line}: unknown column(s) {', '.join(map(repr, unknown))}; known: "
                         f"{', '.join(CATALOGUE_COLUMNS + CATALOGUE_OPTIONAL)}")
    if len(set(header)) != len(header):
        raise FleetError(f"{spath}, line {head_line}: a column appears twice")
    rows, nominal = [], {}
    for n, ln in lines[1:]:
        c = [v.strip() for v in cells(ln)]
        if len(c) != len(header):
            raise FleetError(f"{spath}, line {n}: {len(c)} cell(s), expected {len(header)} "
                             f"({', '.join(header)}); a missing value is an empty cell between commas")
        v = dict(zip(header, c))
        for col in ("file", "unit", "speed_m_s"):
            if not v[col]:
                raise FleetError(f"{spath}, line {n}: column {col} is empty")
        if os.path.isabs(v["file"]) or ".." in v["file"].replace("\\", "/").split("/"):
            raise FleetError(f"{spath}, line {n}: file {v['file']!r} must be relative to the scanned folder")
        speed = _number(v["speed_m_s"], spath, n, "speed_m_s", lo=0.0, hi=10.0, unit="m/s")
        ssig = _number(v["speed_sigma_m_s"], spath, n, "speed_sigma_m_s", lo=0.0, hi=speed, unit="m/s") \
            if v.get("speed_sigma_m_s") else 0.0
        date = None
        if v["date"]:
            try:
                date = _iso(parse_date(v["date"]))
            except FleetError as exc:
                raise FleetError(f"{spath}, line {n}: {exc}") from None
        nom = None
        if v["nominal_pitch_m"]:
            nom = _number(v["nominal_pitch_m"], spath, n, "nominal_pitch_m", lo=0.0, hi=1.0, unit="m",
                          hint=" (metres: 0.13333, not 133.33)")
            prev = nominal.get(v["unit"])
            if prev is not None and not math.isclose(prev[0], nom, rel_tol=1e-9):
                raise FleetError(f"{spath}, line {n}: unit {v['unit']!r} has nominal_pitch_m {nom:g} here but "
                                 f"{prev[0]:g} on line {prev[1]}")
            nominal.setdefault(v["unit"], (nom, n))
        rows.append(CatalogueRow(n, posixpath.normpath(v["file"].replace("\\", "/")), v["unit"], speed, ssig, date, nom,
                                 v.get("channel") or None))
    if not rows:
        raise FleetError(f"{spath}: catalogue has a header but no line")
    return rows


# ------------------------------------------------------------------------------------------- scan


@dataclass(frozen=True)
class _Job:
    path: str
    unit: str
    speed_m_s: float
    speed_sigma_m_s: float
    nominal_pitch_m: float
    date: str | None
    channel: str | None
    sha256: str


def _analyse_job(job):
    """Worker side of a scan: analyse one recording; never raises (a failure is a message)."""
    try:
        m = analyse_recording(job.path, unit=job.unit, speed=job.speed_m_s, speed_sigma=job.speed_sigma_m_s,
                              nominal_pitch=job.nominal_pitch_m, date=job.date, channel=job.channel)
        return {"ok": True, "measurement": m}
    except (ValueError, OSError) as exc:  # RecordingError and FleetError are ValueErrors
        msg = " ".join(str(exc).split()) or type(exc).__name__
        if not msg.startswith(job.path):
            msg = f"{job.path}: {msg}"
        return {"ok": False, "error": msg}
    except Exception as exc:  # noqa: BLE001 - a bad file must never stop the scan
        return {"ok": False, "error": f"{job.path}: unexpected {type(exc).__name__}: {' '.join(str(exc).split())}"}


@dataclass
class ScanResult:
    """What :meth:`FleetDB.scan` did.

    Attributes
    ----------
    added : list of Measurement
    skipped : list of (str, str)
        Files already stored (same SHA-256), with the reason.
    failed : list of (str, str)
        Files (or catalogue lines) that could not be added, with the reason.
    notes : list of str
    """

    added: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"added": len(self.added), "skipped_duplicates": len(self.skipped), "failed": len(self.failed),
                "added_files": [m.path for m in self.added],
                "skipped_files": [{"file": p, "reason": r} for p, r in self.skipped],
                "failed_files": [{"file": p, "reason": r} for p, r in self.failed], "notes": list(self.notes)}


def _candidate_files(directory, exclude):
    out = []
    for root, dirs, files in os.walk(directory):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for f in sorted(files):
            if f.startswith(".") or os.path.splitext(f)[1].lower() not in RECORDING_SUFFIXES:
                continue
            full = os.path.join(root, f)
            if os.path.abspath(full) in exclude:
                continue
            out.append(os.path.relpath(full, directory).replace(os.sep, "/"))
    return sorted(out)


def _match(rel, rows):
    base = rel.rsplit("/", 1)[-1]
    exact = [r for r in rows if not r.is_glob and r.file in (rel, base)]
    if exact:
        return exact[0]
    for r in rows:
        if r.is_glob and (fnmatch.fnmatchcase(rel, r.file) or fnmatch.fnmatchcase(base, r.file)):
            return r
    return None


# --------------------------------------------------------------------------------------- database


def resolve_db_path(db=None) -> str:
    """The database file: ``db`` if given, else ``$VIBKIT_FLEET_DB``, else ``./vibkit-fleet.sqlite``.

    ``db`` may be a path or a ``sqlite:///relative/path`` / ``sqlite:////absolute/path`` URL.

    Raises
    ------
    FleetError
        A URL of another scheme (server databases are not supported yet) or an in-memory one.
    """
    spec = db if db not in (None, "") else (os.environ.get(DB_ENV) or DEFAULT_DB_NAME)
    spec = os.fspath(spec)
    m = re.match(r"^([A-Za-z][A-Za-z0-9+.-]*)://", spec)
    if not m:
        return spec
    scheme = m.group(1).lower()
    if scheme != "sqlite":
        raise FleetError(f"database URL {spec!r}: scheme {scheme!r} is not supported yet; vibkit's fleet database "
                         "is a SQLite file (a path, or sqlite:///relative/path, sqlite:////absolute/path)")
    if not spec.startswith("sqlite:///") or len(spec) == len("sqlite:///"):
        raise FleetError(f"database URL {spec!r}: expected sqlite:///path (an in-memory database would lose "
                         "every measurement)")
    path = spec[len("sqlite:///"):]
    return path.split("?", 1)[0]


class FleetDB:
    """The measurement history of a fleet, in one SQLite file.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file or ``sqlite:///path`` URL (see :func:`resolve_db_path`).
    create : bool
        Create the database if it does not exist (``False``: a missing database is an error).

    Raises
    ------
    FleetError
        Missing database with ``create=False``, a file that is not a SQLite database, a SQLite
        database of another application or of a newer vibkit.

    Examples
    --------
    >>> with FleetDB("fleet.sqlite") as db:  # doctest: +SKIP
    ...     db.add("E07-2026-11-23.csv", unit="E07", speed=0.5, nominal_pitch=0.13333)
    ...     for trend in db.status():
    ...         print(trend.unit, trend.slope_percent_per_year)
    """

    def __init__(self, path=None, *, create=True):
        self.path = resolve_db_path(path)
        p = self.path
        if os.path.isdir(p):
            raise FleetError(f"{p}: is a folder; expected the fleet database file")
        exists = os.path.exists(p) and os.path.getsize(p) > 0
        if not exists and not create:
            raise FleetError(f"{p}: no fleet database here (vibkit fleet add or scan creates one; --db or "
                             f"{DB_ENV} names another)")
        if exists:
            with open(p, "rb") as fh:
                if fh.read(16) != _SQLITE_MAGIC:
                    raise FleetError(f"{p}: not a SQLite database; expected a vibkit fleet database")
        parent = os.path.dirname(os.path.abspath(p))
        if not os.path.isdir(parent):
            raise FleetError(f"{p}: folder {parent} does not exist")
        try:
            self._con = sqlite3.connect(p, timeout=60.0, isolation_level=None)
        except sqlite3.Error as exc:
            raise FleetError(f"{p}: cannot open the database: {exc}") from None
        try:
            self._prepare(exists)
        except sqlite3.DatabaseError as exc:
            self._con.close()
            raise FleetError(f"{p}: not a usable fleet database: {exc}") from None
        except FleetError:
            self._con.close()
            raise

    def _prepare(self, exists):
        con = self._con
        app = con.execute("PRAGMA application_id").fetchone()[0]
        ver = con.execute("PRAGMA user_version").fetchone()[0]
        tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        if app not in (0, APPLICATION_ID) or (app == 0 and tables and "measurement" not in tables):
            raise FleetError(f"{self.path}: a SQLite database of another application (tables: "
                             f"{', '.join(tables) or 'none'}); refusing to write into it")
        if ver > SCHEMA_VERSION:
            raise FleetError(f"{self.path}: written by a newer vibkit (schema {ver}, this one reads {SCHEMA_VERSION})")
        mode = con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        if str(mode).lower() != "wal":  # pragma: no cover - file systems without shared memory
            raise FleetError(f"{self.path}: SQLite cannot use its WAL journal here (mode {mode!r})")
        con.execute("PRAGMA synchronous=FULL")
        con.execute("PRAGMA foreign_keys=ON")
        if "measurement" not in tables:
            con.execute("BEGIN IMMEDIATE")
            try:
                for stmt in _SCHEMA.strip().split(";"):
                    if stmt.strip():
                        con.execute(stmt)
                con.execute(f"PRAGMA application_id={APPLICATION_ID}")
                con.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
                con.execute("COMMIT")
            except BaseException:
                con.execute("ROLLBACK")
                raise

    # context manager
    def close(self):
        self._con.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    # ---------------------------------------------------------------------------------- queries
    def _rows(self, where="", args=()):
        cur = self._con.execute(f"SELECT id, {', '.join(_COLUMNS)} FROM measurement {where}", args)
        out = []
        for r in cur.fetchall():
            d = dict(zip(("id",) + _COLUMNS, r))
            d["warnings"] = tuple(json.loads(d["warnings"]))
            out.append(Measurement(**d))
        return out

    def measurements(self, unit=None):
        """Stored measurements, by unit then date (of one unit if given)."""
        if unit is None:
            return self._rows("ORDER BY unit, date_unix_s, id")
        return self._rows("WHERE unit = ? ORDER BY date_unix_s, id", (str(unit),))

    def find(self, sha256):
        """The stored measurement of a file with this SHA-256, or None."""
        r = self._rows("WHERE sha256 = ?", (str(sha256),))
        return r[0] if r else None

    def units(self):
        """Unit identifiers, sorted."""
        return [r[0] for r in self._con.execute("SELECT DISTINCT unit FROM measurement ORDER BY unit")]

    def nominal_pitch(self, unit):
        """The nominal pitch stored for a unit [m], or None for a new unit."""
        r = self._con.execute("SELECT nominal_pitch_m FROM measurement WHERE unit = ? ORDER BY id DESC LIMIT 1",
                              (str(unit),)).fetchone()
        return None if r is None else float(r[0])

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` (``"ok"`` when the file is sound)."""
        return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    # ---------------------------------------------------------------------------------- writing
    def _duplicate_message(self, what, m):
        return (f"{what}: already stored (same sha256) as measurement #{m.id} of unit {m.unit!r} dated "
                f"{m.date_utc[:10]}, from {m.path}")

    def insert(self, m: Measurement) -> Measurement:
        """Store one analysed measurement in its own transaction; the stored row (with its id).

        Raises
        ------
        DuplicateRecordingError
            The same file (SHA-256) is already stored.
        FleetError
            The unit is stored with another nominal pitch.
        """
        con = self._con
        con.execute("BEGIN IMMEDIATE")
        try:
            old = self.find(m.sha256)
            if old is not None:
                raise DuplicateRecordingError(self._duplicate_message(m.path, old), old)
            nom = self.nominal_pitch(m.unit)
            if nom is not None and not math.isclose(nom, m.nominal_pitch_m, rel_tol=1e-9):
                raise FleetError(f"unit {m.unit!r} is stored with nominal pitch {nom:g} m, not "
                                 f"{m.nominal_pitch_m:g} m; one unit has one nominal pitch")
            vals = [json.dumps(list(m.warnings)) if c == "warnings" else getattr(m, c) for c in _COLUMNS]
            cur = con.execute(f"INSERT INTO measurement ({', '.join(_COLUMNS)}) VALUES "
                              f"({', '.join('?' * len(_COLUMNS))})", vals)
            rid = cur.lastrowid
            con.execute("COMMIT")
        except BaseException:
            con.execute("ROLLBACK")
            raise
        d = asdict(m)
        d["id"] = rid
        return Measurement(**d)

    def add(self, recording, *, unit, speed, speed_sigma=0.0, date=None, nominal_pitch=None, channel=None):
        """Analyse a recording and store its measurement.

        Parameters
        ----------
        recording : str or os.PathLike
        unit : str
            Escalator identifier.
        speed, speed_sigma : float
            Chain speed and its standard deviation. [m/s]
        date : str, optional
            Measurement date, ISO 8601 (default: the recording's start time; refused without one).
        nominal_pitch : float, optional
            Nominal link pitch [m]; default the unit's stored value (required for a new unit).
        channel : str, optional

        Returns
        -------
        Measurement
            The stored row.

        Raises
        ------
        DuplicateRecordingError
            The file (same SHA-256) is already stored.
        FleetError
            No date, no link-pass, no nominal pitch for a new unit, another nominal pitch than the
            unit's.
        """
        spath = os.fspath(recording)
        if not os.path.exists(spath):
            raise FleetError(f"{spath}: file not found; expected a recording")
        if os.path.isfile(spath):
            old = self.find(_file_sha256(spath))
            if old is not None:
                raise DuplicateRecordingError(self._duplicate_message(spath, old), old)
        nom = nominal_pitch if nominal_pitch is not None else self.nominal_pitch(unit)
        if nom is None:
            raise FleetError(f"unit {str(unit)!r} is new: give its nominal link pitch (--nominal-pitch, in m)")
        m = analyse_recording(spath, unit=unit, speed=speed, speed_sigma=speed_sigma, nominal_pitch=nom, date=date,
                              channel=channel)
        return self.insert(m)

    def scan(self, directory, catalogue, *, scheduler=None, n_workers=None, client=None, parallel=True,
             on_failure=None, progress=False):
        """Add every recording of a folder that a catalogue describes; analyses run on Dask workers.

        Parameters
        ----------
        directory : str or os.PathLike
            Folder scanned (recursively; hidden files and folders are left out) for recordings
            (suffixes in ``RECORDING_SUFFIXES``).
        catalogue : str or os.PathLike
            CSV catalogue (columns in the module docstring).
        scheduler : str, optional
            Dask scheduler address; default a local cluster (see :func:`vibkit.runtime.cluster.dask_client`).
        n_workers : int, optional
            Worker processes of the local cluster.
        client : distributed.Client, optional
            Use this client (its cluster stays up).
        parallel : bool
            False: analyse in this process, one file after another (no Dask).
        on_failure : callable, optional
            Called as ``on_failure(file, reason)`` for each failed file as it happens.
        progress : bool
            Draw a progress bar on a terminal.

        Returns
        -------
        ScanResult

        Notes
        -----
        Only this process writes the database, one transaction per recording (WAL journal,
        ``synchronous=FULL``): a killed scan leaves complete rows, and the next scan skips them.
        A local cluster spawns its worker processes: a script that calls ``scan`` needs the
        ``if __name__ == "__main__":`` guard (or ``parallel=False``).
        """
        from ..runtime.progress import Progress

        d = os.fspath(directory)
        if not os.path.isdir(d):
            raise FleetError(f"{d}: not a folder; expected the folder of recordings to scan")
        rows = read_catalogue(catalogue)
        res = ScanResult()

        def fail(name, why):
            res.failed.append((name, why))
            if on_failure is not None:
                on_failure(name, why)

        exclude = {os.path.abspath(os.fspath(catalogue)), os.path.abspath(self.path),
                   os.path.abspath(self.path) + "-wal", os.path.abspath(self.path) + "-shm"}
        files = _candidate_files(d, exclude)
        # a file the catalogue names exactly is a recording whatever its suffix
        named = [r.file for r in rows if not r.is_glob and os.path.isfile(os.path.join(d, r.file))
                 and os.path.abspath(os.path.join(d, r.file)) not in exclude]
        files = sorted(set(files) | {os.path.normpath(f).replace(os.sep, "/") for f in named})
        unit_nominal = {}
        for r in rows:
            if r.nominal_pitch_m is not None:
                unit_nominal.setdefault(r.unit, r.nominal_pitch_m)
        used = set()
        jobs, seen = [], {}
        for rel in files:
            full = os.path.join(d, rel)
            r = _match(rel, rows)
            if r is None:
                fail(full, "unknown unit: no catalogue line matches this file")
                continue
            used.add(r.line)
            try:
                sha = _file_sha256(full)
            except OSError as exc:
                fail(full, f"cannot be read: {exc.strerror or exc}")
                continue
            old = self.find(sha)
            if old is not None:
                res.skipped.append((full, f"already stored as measurement #{old.id} of unit {old.unit!r}"))
                continue
            if sha in seen:
                res.skipped.append((full, f"same content (sha256) as {seen[sha]} in this scan"))
                continue
            seen[sha] = full
            nom = r.nominal_pitch_m or unit_nominal.get(r.unit) or self.nominal_pitch(r.unit)
            if nom is None:
                fail(full, f"unit {r.unit!r} has no nominal pitch (catalogue line {r.line}: fill nominal_pitch_m "
                           "on one line of the unit)")
                continue
            jobs.append(_Job(os.path.abspath(full), r.unit, r.speed_m_s, r.speed_sigma_m_s, nom, r.date, r.channel,
                             sha))
        for r in rows:
            if r.line not in used:
                if r.is_glob:
                    res.notes.append(f"catalogue line {r.line}: {r.file!r} matches no recording")
                elif any(r.file in (f, f.rsplit("/", 1)[-1]) for f in files):
                    f = next(f for f in files if r.file in (f, f.rsplit("/", 1)[-1]))
                    res.notes.append(f"catalogue line {r.line}: {r.file!r} is also on line "
                                     f"{_match(f, rows).line}, which is used")
                else:
                    fail(os.path.join(d, r.file), f"file not found (catalogue line {r.line})")
        bar = Progress(len(jobs), "fleet scan", enabled=progress)

        def take(job, outcome):
            if not outcome["ok"]:
                fail(job.path, outcome["error"])
                return
            try:
                res.added.append(self.insert(outcome["measurement"]))
            except DuplicateRecordingError as exc:
                res.skipped.append((job.path, str(exc)))
            except FleetError as exc:
                fail(job.path, str(exc))

        try:
            if not jobs:
                pass
            elif not parallel:
                for i, job in enumerate(jobs, 1):
                    take(job, _analyse_job(job))
                    bar.update(i)
            else:
                self._scan_dask(jobs, take, bar, client=client, scheduler=scheduler, n_workers=n_workers)
        finally:
            bar.close()
        return res

    def _scan_dask(self, jobs, take, bar, *, client, scheduler, n_workers):
        import contextlib

        from distributed import as_completed

        from ..runtime.cluster import dask_client

        ctx = contextlib.nullcontext(client) if client is not None else dask_client(scheduler, n_workers=n_workers)
        try:
            cl = ctx.__enter__()
        except (OSError, RuntimeError, TimeoutError, ValueError) as exc:
            where = f"the Dask scheduler at {scheduler}" if scheduler else "a local Dask cluster"
            raise FleetError(f"cannot start or reach {where}: {' '.join(str(exc).split()) or type(exc).__name__} "
                             "(--workers 0 analyses in this process, without Dask)") from None
        with contextlib.ExitStack() as stack:
            stack.push(ctx)
            futs = {}
            for i, job in enumerate(jobs):
                f = cl.submit(_analyse_job, job, key=f"vibkit-fleet-{job.sha256}-{i}", pure=False)
                futs[f] = job
            for n, f in enumerate(as_completed(list(futs)), 1):
                job = futs.pop(f)
                try:
                    outcome = f.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker fails one row, not the scan
                    outcome = {"ok": False, "error": f"{job.path}: analysis lost ({type(exc).__name__}: "
                                                     f"{' '.join(str(exc).split())})"}
                f.release()
                take(job, outcome)
                bar.update(n)

    # ----------------------------------------------------------------------------------- status
    def status(self, *, limits_percent=DEFAULT_LIMITS_PERCENT, coverage_sigma=2.0, units=None):
        """Per unit: latest elongation, trend and forecasts, ranked by urgency (most urgent first).

        Parameters
        ----------
        limits_percent : (float, float, float)
            Elongation limits. [%]
        coverage_sigma : float
            Half-width of the forecast intervals in standard deviations.
        units : sequence of str, optional
            Only these units.

        Returns
        -------
        list of UnitTrend
        """
        from ..diagnose.pitch import _check_limits

        limits = _check_limits(limits_percent)
        by_unit = {}
        for m in self.measurements():
            if units is None or m.unit in units:
                by_unit.setdefault(m.unit, []).append(m)
        out = [unit_trend(u, ms, limits_percent=limits, coverage_sigma=coverage_sigma) for u, ms in by_unit.items()]
        return rank_units(out)


@dataclass(frozen=True)
class UnitTrend:
    """The state of one unit: latest measurement, elongation trend and limit forecasts.

    Attributes
    ----------
    unit : str
    n_measurements : int
    first_date_utc, latest_date_utc : str
    nominal_pitch_m : float
        [m]
    latest_elongation_percent, latest_elongation_sigma_percent : float
        [%]
    latest_verdict : str
        :func:`vibkit.diagnose.pitch.elongation_verdict` of the latest elongation.
    slope_percent_per_year, slope_sigma_percent_per_year : float or None
        Elongation rate and its standard deviation (None with one measurement or one date). [%/year]
    chi2_per_dof : float or None
    over_limit_percent : float or None
        The highest limit the latest measurement reaches. [%]
    forecasts : tuple of LimitForecast
    rank : int
        1 = most urgent.
    """

    unit: str
    n_measurements: int
    first_date_utc: str
    latest_date_utc: str
    nominal_pitch_m: float
    latest_elongation_percent: float
    latest_elongation_sigma_percent: float
    latest_verdict: str
    slope_percent_per_year: float | None
    slope_sigma_percent_per_year: float | None
    chi2_per_dof: float | None
    over_limit_percent: float | None
    forecasts: tuple
    fit: TrendFit | None = None
    rank: int = 0

    def as_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k not in ("forecasts", "fit")}
        d["forecasts"] = [asdict(f) for f in self.forecasts]
        if self.fit is not None:
            d["trend_reference_utc"] = _unix_to_iso(self.fit.t_ref_unix_s)
            d["elongation_at_reference_percent"] = self.fit.elongation_ref_percent
            d["elongation_at_reference_sigma_percent"] = self.fit.elongation_ref_sigma_percent
        return d


def unit_trend(unit, measurements, *, limits_percent=DEFAULT_LIMITS_PERCENT, coverage_sigma=2.0) -> UnitTrend:
    """The :class:`UnitTrend` of one unit's measurements (any order)."""
    ms = sorted(measurements, key=lambda m: (m.date_unix_s, m.id or 0))
    last = ms[-1]
    fit = None
    if len(ms) >= 2:
        try:
            fit = fit_trend([m.date_unix_s for m in ms], [m.elongation_percent for m in ms],
                            [m.elongation_sigma_percent for m in ms])
        except ValueError:  # one date only
            fit = None
    reached = [lim for lim in limits_percent if last.elongation_percent >= lim]
    fc = forecast_limits(fit, limits_percent, latest_elongation_percent=last.elongation_percent,
                         coverage_sigma=coverage_sigma)
    return UnitTrend(
        unit=str(unit), n_measurements=len(ms), first_date_utc=ms[0].date_utc, latest_date_utc=last.date_utc,
        nominal_pitch_m=last.nominal_pitch_m, latest_elongation_percent=last.elongation_percent,
        latest_elongation_sigma_percent=last.elongation_sigma_percent,
        latest_verdict=elongation_verdict(last.elongation_percent, limits_percent),
        slope_percent_per_year=None if fit is None else fit.slope_percent_per_year,
        slope_sigma_percent_per_year=None if fit is None else fit.slope_sigma_percent_per_year,
        chi2_per_dof=None if fit is None or math.isnan(fit.chi2_per_dof) else fit.chi2_per_dof,
        over_limit_percent=max(reached) if reached else None, forecasts=fc, fit=fit)


def rank_units(trends):
    """Sort by urgency: units over a limit first (highest limit, then largest elongation), then by the
    earliest forecast date of a limit not yet reached, then units without a forecast (largest
    elongation first); ``rank`` set from 1."""
    def key(u):
        if u.over_limit_percent is not None:
            return (0, -u.over_limit_percent, -u.latest_elongation_percent, u.unit)
        when = min((f.urgency_unix_s() for f in u.forecasts if f.status != "reached"), default=math.inf)
        if math.isfinite(when):
            return (1, when, 0.0, u.unit)
        return (2, -u.latest_elongation_percent, 0.0, u.unit)

    out = sorted(trends, key=key)
    return [UnitTrend(**{**{k: getattr(u, k) for k in u.__dataclass_fields__}, "rank": i})
            for i, u in enumerate(out, 1)]
