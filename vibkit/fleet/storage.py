"""The fleet database: every measurement of every unit in one embedded SQLite file.

:class:`FleetDB` keeps every measurement in an embedded SQLite database (standard library; WAL
journal, one transaction per measurement): the link-pass estimate of
:func:`vibkit.diagnose.pitch.estimate_pitch`, the pitch and the elongation with their standard
deviations, quality figures (SNR, warnings) and provenance (SHA-256 of the file, its path,
vibkit's version, the time of analysis).  A file already stored (same SHA-256) is refused, so
re-running a scan skips what it has done.  The trend maths lives in :mod:`vibkit.fleet.trends`,
the scan machinery in :mod:`vibkit.fleet.scan`.
"""

from __future__ import annotations

import json
import math
import os
import re
import sqlite3
from dataclasses import asdict

from ..diagnose.pitch import DEFAULT_LIMITS_PERCENT
from .errors import DuplicateRecordingError, FleetError
from .measurement import Measurement, _file_sha256, analyse_recording
from .scan import scan_folder
from .trends import rank_units, unit_trend

__all__ = ["DB_ENV", "DEFAULT_DB_NAME", "FleetDB", "resolve_db_path"]

#: environment variable naming the fleet database (a path or a ``sqlite:///path`` URL)
DB_ENV = "VIBKIT_FLEET_DB"
#: database file used when neither ``--db`` nor :data:`DB_ENV` names one (current directory)
DEFAULT_DB_NAME = "vibkit-fleet.sqlite"
SCHEMA_VERSION = 1
#: SQLite ``PRAGMA application_id`` of a vibkit fleet database ("VBKF")
APPLICATION_ID = 0x56424B46
_SQLITE_MAGIC = b"SQLite format 3\x00"

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

    def add(self, recording, *, unit, speed, speed_sigma=0.0, date=None, nominal_pitch=None, channel=None,
            read_options=None):
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
        read_options : dict, optional
            More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).

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
                              channel=channel, read_options=read_options)
        return self.insert(m)

    def scan(self, directory, catalogue, *, scheduler=None, n_workers=None, client=None, parallel=True,
             on_failure=None, progress=False, read_options=None):
        """Add every recording of a folder that a catalogue describes; analyses run on Dask workers.

        Parameters
        ----------
        directory : str or os.PathLike
            Folder scanned (recursively; hidden files and folders are left out) for recordings
            (suffixes in :data:`vibkit.fleet.scan.RECORDING_SUFFIXES`).
        catalogue : str or os.PathLike
            CSV catalogue (columns in :mod:`vibkit.fleet.catalogue`).
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
        read_options : dict, optional
            :func:`vibkit.read_recording` arguments for every file (``time_unit``, ``units`` ...); the
            catalogue's ``channel`` column names each file's channel.

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
        return scan_folder(self, directory, catalogue, scheduler=scheduler, n_workers=n_workers, client=client,
                           parallel=parallel, on_failure=on_failure, progress=progress,
                           read_options=read_options)

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
