"""The fleet database: every measurement of every unit, in a SQLite file or on a PostgreSQL server.

:class:`FleetDB` keeps every measurement: the link-pass estimate of
:func:`vibkit.diagnose.pitch.estimate_pitch`, the pitch and the elongation with their standard
deviations, quality figures (SNR, warnings, the quality flag of :mod:`vibkit.fleet.quality`) and
provenance (SHA-256 of the file, its path, vibkit's version, the time of analysis).  A file already
stored (same SHA-256) is refused, so re-running a scan skips what it has done.  One transaction per
measurement.  Where the rows live: an embedded SQLite file (:mod:`vibkit.fleet.sqlite_store`, the
default) or a PostgreSQL server (:mod:`vibkit.fleet.postgres_store`, ``postgresql://...``) that many
technicians' processes write at once.  :func:`migrate` copies a history from one to the other.  The
trend maths lives in :mod:`vibkit.fleet.trends`, the scan machinery in :mod:`vibkit.fleet.scan`.
"""

from __future__ import annotations

import functools
import os
import re
import sqlite3

from ..diagnose.decision import check_limits
from ..diagnose.pitch import DEFAULT_LIMITS_PERCENT
from ..io import HEAD_BYTES, check_head
from ..model.profile import load_profile
from .errors import DuplicateRecordingError, FleetError
from .inputs import check_inputs, check_pitch
from .link_scan import NO_LINK_COUNT_ADD, measure_with_links, profile_scene
from .links import BEFORE_LINK_SCANS, LinkScan, links_history
from .measurement import Measurement, _file_sha256
from .postgres_store import PostgresStore, redact_url
from .scan import scan_folder
from .schema import APPLICATION_ID, SCHEMA_VERSION  # noqa: F401 - public through vibkit.fleet.history
from .sqlite_store import SQLiteStore, sqlite_error
from .trends import rank_units, unit_trend

__all__ = ["DB_ENV", "DEFAULT_DB_NAME", "FleetDB", "is_server_url", "migrate", "resolve_db_path"]

#: environment variable naming the fleet database (a path, a ``sqlite:///path`` or a ``postgresql://`` URL)
DB_ENV = "VIBKIT_FLEET_DB"
#: database file used when neither ``--db`` nor :data:`DB_ENV` names one (current directory)
DEFAULT_DB_NAME = "vibkit-fleet.sqlite"
_SERVER_SCHEMES = ("postgresql", "postgres")


def is_server_url(spec) -> bool:
    """Whether ``spec`` names a PostgreSQL server (``postgresql://`` or ``postgres://``)."""
    m = re.match(r"^([A-Za-z][A-Za-z0-9+.-]*)://", os.fspath(spec))
    return bool(m) and m.group(1).lower() in _SERVER_SCHEMES


def resolve_db_path(db=None) -> str:
    """The database: ``db`` if given, else ``$VIBKIT_FLEET_DB``, else ``./vibkit-fleet.sqlite``.

    ``db`` may be a path, a ``sqlite:///relative/path`` / ``sqlite:////absolute/path`` URL (the file
    path is returned) or a ``postgresql://`` URL (returned as it is).

    Raises
    ------
    FleetError
        A URL of another scheme, or an in-memory SQLite one.
    """
    if db is not None and not os.fspath(db).strip():
        raise FleetError(
            "--db / database is empty; expected a database file such as fleet.sqlite, sqlite:///PATH or "
            "postgresql://user@host/dbname (leave --db out for $VIBKIT_FLEET_DB, else ./vibkit-fleet.sqlite)"
        )
    env = os.environ.get(DB_ENV)
    if db is None and env is not None and env and not env.strip():
        raise FleetError(
            f"${DB_ENV} is blank; set it to a database (a file such as fleet.sqlite, or "
            "postgresql://user@host/dbname), or unset it for ./vibkit-fleet.sqlite"
        )
    spec = db if db is not None else (env or DEFAULT_DB_NAME)
    spec = os.fspath(spec)
    m = re.match(r"^([A-Za-z][A-Za-z0-9+.-]*)://", spec)
    if not m:
        return spec
    scheme = m.group(1).lower()
    if scheme in _SERVER_SCHEMES:
        _check_server_url(spec)
        return spec
    if scheme != "sqlite":
        raise FleetError(
            f"database URL {spec!r}: scheme {scheme!r} is not supported; vibkit's fleet database "
            "is a SQLite file (a path, or sqlite:///relative/path, sqlite:////absolute/path) or a "
            "PostgreSQL server (postgresql://user@host/dbname)"
        )
    if not spec.startswith("sqlite:///") or len(spec) == len("sqlite:///"):
        raise FleetError(
            f"database URL {spec!r}: expected sqlite:///path (an in-memory database would lose every measurement)"
        )
    path = spec[len("sqlite:///") :]
    return path.split("?", 1)[0]


def _check_server_url(spec):
    """A ``postgresql://`` URL that names a server or a database, with a port in range: refused before any
    connection is tried (a socket failure would hide that the URL is what is wrong)."""
    import urllib.parse

    shown = redact_url(spec)
    fix = "expected postgresql://user@host/dbname (postgresql:///dbname: the local server's socket)"
    try:
        u = urllib.parse.urlsplit(spec)
        u.port  # noqa: B018 - raises ValueError on a port that is not a number in 0-65535
    except ValueError as exc:
        raise FleetError(f"database URL {shown!r}: {exc}; {fix}") from None
    if not u.hostname and u.path in ("", "/") and not u.query:
        raise FleetError(f"database URL {shown!r} names no server and no database; {fix}")


def _open_store(spec, create, readonly):
    if is_server_url(spec):
        return PostgresStore(spec, create=create and not readonly, readonly=readonly, db_env=DB_ENV)
    return SQLiteStore(spec, create=create, readonly=readonly, db_env=DB_ENV)


def _translated(method):
    """SQLite's exceptions of a :class:`FleetDB` method as one-line :class:`FleetError`\\ s naming the file."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        try:
            return method(self, *args, **kwargs)
        except sqlite3.Error as exc:
            raise sqlite_error(self.path, exc) from None

    return wrapper


class FleetDB:
    """The measurement history of a fleet, in a SQLite file or on a PostgreSQL server.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file, ``sqlite:///path`` or ``postgresql://`` URL (see :func:`resolve_db_path`).
    create : bool
        Create the database (the file, or the tables on the server) if it does not exist
        (``False``: a missing database is an error).
    readonly : bool
        Open it read-only (SQLite's ``mode=ro``): for status and reports; never writes, not even
        vibkit's schema into a SQLite file that lacks it (that is an error).  A file of an older
        schema is read as the upgrade would leave it, without upgrading it (see :attr:`notes`); opened
        for writing, it is upgraded in place, in one transaction.

    Attributes
    ----------
    path : str
        The file, or the server URL without its password.
    kind : str
        ``"sqlite"`` or ``"postgresql"``.
    notes : list of str
        What opening it did that a user should know (an older schema read without upgrading it).

    Raises
    ------
    FleetError
        Missing database with ``create=False``, a file that is not a SQLite database, a database of
        another application or of a newer vibkit, a server that cannot be reached; and every SQLite
        error (a damaged, read-only or locked file) in one line naming the database and what to do.

    Examples
    --------
    >>> with FleetDB("fleet.sqlite") as db:  # doctest: +SKIP
    ...     db.add("E07-2026-11-23.csv", unit="E07", speed=0.5, nominal_pitch=0.13333)
    ...     for trend in db.status():
    ...         print(trend.unit, trend.slope_percent_per_year)
    """

    #: seconds a SQLite write waits for another process's transaction before it is an error
    TIMEOUT_S = 60.0

    def __init__(self, path=None, *, create=True, readonly=False):
        self.readonly = bool(readonly)
        self._store = _open_store(resolve_db_path(path), create, self.readonly)
        if self._store.dialect == "sqlite":
            self._store.set_timeout(self.TIMEOUT_S)
        self.path = self._store.location
        self.kind = self._store.dialect
        self.notes = list(getattr(self._store, "notes", ()))

    @property
    def local_files(self):
        """Files of the database on this machine (a scan leaves them out); none for a server."""
        return self._store.local_files

    # context manager
    def close(self):
        self._store.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    # ---------------------------------------------------------------------------------- queries
    @_translated
    def measurements(self, unit=None):
        """Stored measurements, by unit then date (of one unit if given)."""
        if unit is None:
            return self._store.rows("ORDER BY unit, date_unix_s, id")
        return self._store.rows("WHERE unit = ? ORDER BY date_unix_s, id", (str(unit),))

    @_translated
    def find(self, sha256):
        """The stored measurement of a file with this SHA-256, or None."""
        return self._store.find(sha256)

    @_translated
    def units(self):
        """Unit identifiers, sorted."""
        return self._store.units()

    @_translated
    def link_scans(self, unit=None):
        """``{measurement id: LinkScan}``: the stored link scans (of one unit if given; :mod:`vibkit.fleet.links`)."""
        return self._store.link_scans(unit)

    @_translated
    def links_history(self, unit, *, coverage_sigma=2.0):
        """The link scans of a unit's visits and which links came back worse (:func:`vibkit.fleet.links.links_history`)."""
        return links_history(self, unit, coverage_sigma=coverage_sigma)

    @_translated
    def nominal_pitch(self, unit):
        """The nominal pitch stored for a unit [m], or None for a new unit."""
        return self._store.nominal_pitch(unit)

    @_translated
    def integrity_check(self) -> str:
        """``"ok"`` when the store is sound (SQLite's ``PRAGMA integrity_check``; PostgreSQL: valid indexes)."""
        return self._store.integrity_check()

    # ---------------------------------------------------------------------------------- writing
    @_translated
    def insert(self, m: Measurement, link_scan=None) -> Measurement:
        """Store one analysed measurement and its link scan (:class:`~vibkit.fleet.links.LinkScan`; default "not
        run") in its own transaction; the stored row (with its id).

        Safe when other processes (on other machines, for PostgreSQL) insert at the same time.

        Raises
        ------
        DuplicateRecordingError
            The same file (SHA-256) is already stored.
        FleetError
            The unit is stored with another nominal pitch.
        """
        return self._store.insert(m, link_scan)

    def insert_batch(self, items):
        """Store ``[(Measurement, LinkScan or None)]`` in one transaction: what a scan stores of its last analyses.

        Returns, per item in order, the stored row (with its id) or the :class:`DuplicateRecordingError` /
        :class:`FleetError` that refused it, as :meth:`insert` would have raised it.  Where the batch as a whole
        fails (a database error, another process storing one of the files at the same moment), nothing of it is
        stored and each item is stored again in its own transaction (:meth:`insert`), so that one bad row costs
        only itself.  Every row is whole or absent, whenever the process is killed.
        """
        items = list(items)
        try:
            return self._store.insert_batch(items)
        except Exception:  # noqa: BLE001 - rolled back: each row on its own says what refuses it
            out = []
            for m, link_scan in items:
                try:
                    out.append(self.insert(m, link_scan))
                except (DuplicateRecordingError, FleetError) as exc:
                    out.append(exc)
            return out

    @_translated
    def insert_many(self, measurements, link_scans=None):
        """Store measurements in one transaction, leaving out those already stored; ``(added, skipped)``.
        ``link_scans``: ``{sha256: LinkScan}`` (a measurement without one is stored "not run")."""
        return self._store.insert_many(measurements, link_scans)

    @_translated
    def add(
        self,
        recording,
        *,
        unit,
        speed,
        speed_sigma=None,
        date=None,
        nominal_pitch=None,
        channel=None,
        replaced=False,
        read_options=None,
        n_links=None,
        marker_s=None,
        escalator=None,
        segment=None,
    ):
        """Analyse a recording and store its measurement with its link scan.

        Parameters
        ----------
        recording : str or os.PathLike
        unit : str
            Escalator identifier.
        speed, speed_sigma : float
            Chain speed and its standard deviation [m/s]; ``speed_sigma`` None: not stated (stored as NULL).
        date : str, optional
            Measurement date, ISO 8601 (default: the recording's start time; refused without one).
        nominal_pitch : float, optional
            Nominal link pitch [m]; default the unit's stored value (required for a new unit).
        channel : str, optional
        replaced : bool
            The unit's chain was replaced since its previous measurement: a new trend segment starts.
        read_options : dict, optional
            More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).
        n_links : int, optional
            Links in the chain (default: the ``escalator`` profile's ``chain.n_links``): the links are scanned as
            :meth:`scan` scans them (:func:`vibkit.fleet.link_scan.measure_with_links`); without it the scan is
            stored "not run" with the reason.
        marker_s : float, optional
            When a marked link passed the sensor [s from the recording's start]: it is link 1.
        escalator : str or os.PathLike, optional
            The unit's escalator profile: its number of links, its sprocket's teeth and links per step (the
            analysis's, as ``vibkit pitch --escalator`` takes them), and its forward scene for a tensioner's
            worn-link signature (a profile whose geometry gives no scene: a line in :attr:`notes`).
        segment : (float, float), optional
            Only this part of the recording [s, in its own time] is analysed (outside it: a ValueError naming the
            recording's span); the file's SHA-256 still names the measurement.

        Returns
        -------
        Measurement
            The stored row, with its quality flag (an implausible or inconclusive one is stored
            flagged and left out of the trend); its link scan: ``link_scans(unit)[m.id]``.

        Raises
        ------
        DuplicateRecordingError
            The file (same SHA-256) is already stored.
        FleetError
            No date, no link-pass, no nominal pitch for a new unit, another nominal pitch than the
            unit's.
        """
        check_inputs(unit=unit, speed=speed, speed_sigma=speed_sigma, nominal_pitch=nominal_pitch, date=date)
        spath = os.fspath(recording)
        if not os.path.exists(spath):
            raise FleetError(f"{spath}: file not found; expected a recording")
        if os.path.isfile(spath):
            with open(spath, "rb") as fh:  # a file no reader takes is refused before all of it is hashed
                check_head(spath, fh.read(HEAD_BYTES))
            old = self.find(_file_sha256(spath))
            if old is not None:
                raise DuplicateRecordingError(self._store.duplicate_message(spath, old), old)
        nom = nominal_pitch if nominal_pitch is not None else self.nominal_pitch(unit)
        if nom is None:
            raise FleetError(f"unit {str(unit)!r} is new: give its nominal link pitch (--nominal-pitch, in m)")
        check_pitch(nom, f"the nominal pitch stored for unit {str(unit)!r} in {self.path}")
        scene = None
        profile = load_profile(escalator) if escalator is not None else None
        if profile is not None:
            if n_links is None:
                n_links = profile.n_links
            if n_links is not None:
                scene = profile_scene(os.fspath(escalator), self.notes)
        m, link_scan = measure_with_links(
            spath,
            n_links=n_links,
            marker_s=marker_s,
            scene=scene,
            no_count=NO_LINK_COUNT_ADD,
            segment=segment,
            profile=profile,
            unit=unit,
            speed=speed,
            speed_sigma=speed_sigma,
            nominal_pitch=nom,
            date=date,
            channel=channel,
            replaced=replaced,
            read_options=read_options,
        )
        return self.insert(m, link_scan)

    @_translated
    def scan(
        self,
        directory,
        catalogue,
        *,
        scheduler=None,
        n_workers=None,
        client=None,
        parallel=None,
        on_failure=None,
        progress=False,
        read_options=None,
    ):
        """Add every recording of a folder that a catalogue describes; analyses run on Dask workers where that pays.

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
        parallel : bool, optional
            None (default): on ``client`` or a running scheduler (``scheduler``, Dask's configuration) when there
            is one; else the files are analysed in this process, and once two are, the rest go to a fresh local
            cluster only when they would end sooner there (:func:`vibkit.runtime.cluster.dask_pays`: the files
            left times one file's analysis here, less their share on ``n_workers`` workers, beyond the cluster's
            start-up; on two cores a few hundred small files).  True: always on Dask.  False: in this process, one
            file after another (no Dask).  The stored numbers are the same wherever the analyses run.
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
        Only this process writes the database, one transaction per batch of recordings analysed (at most
        :data:`vibkit.fleet.scan.BATCH_ROWS` of them, or those of :data:`~vibkit.fleet.scan.BATCH_S` seconds;
        SQLite: WAL journal, ``synchronous=FULL``): a killed scan leaves complete rows, loses at most the last
        second's analyses, and the next scan skips what it stored.
        Several scans (and adds) may run at once, on one machine for SQLite, on many for PostgreSQL:
        each file is stored once, the others are skipped as duplicates.
        A local cluster spawns its worker processes: a script that calls ``scan`` needs the
        ``if __name__ == "__main__":`` guard (or ``parallel=False``).
        """
        return scan_folder(
            self,
            directory,
            catalogue,
            scheduler=scheduler,
            n_workers=n_workers,
            client=client,
            parallel=parallel,
            on_failure=on_failure,
            progress=progress,
            read_options=read_options,
        )

    # ----------------------------------------------------------------------------------- status
    @_translated
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
        limits = check_limits(limits_percent)
        by_unit = {}
        for m in self.measurements():
            if units is None or m.unit in units:
                by_unit.setdefault(m.unit, []).append(m)
        out = [unit_trend(u, ms, limits_percent=limits, coverage_sigma=coverage_sigma) for u, ms in by_unit.items()]
        return rank_units(out)


def migrate(source, target):
    """Copy every measurement of one fleet database into another (e.g. a SQLite file to PostgreSQL).

    Parameters
    ----------
    source : str or os.PathLike
        The existing database (path or URL); opened read-only: nothing is created, written or upgraded in it
        (a file of an older schema is read as the upgrade would leave it).
    target : str or os.PathLike
        The database that receives the rows (created if missing).

    Returns
    -------
    dict
        ``source``, ``target`` (URLs without password), ``copied``, ``skipped`` (already in the
        target: same SHA-256) and ``target_total``.

    Notes
    -----
    One transaction on the target: a failed or interrupted migration copies nothing, and running it
    again copies only what is missing.  Rows keep every field (provenance, quality flag, replaced) and
    their link scans, except ``id``, which the target numbers.

    Raises
    ------
    FleetError
        Source and target are the same, a database cannot be opened, or a unit's nominal pitch differs
        between them (nothing copied).
    """
    src_spec, dst_spec = resolve_db_path(source), resolve_db_path(target)
    if (
        not is_server_url(src_spec)
        and not is_server_url(dst_spec)
        and os.path.exists(dst_spec)
        and os.path.exists(src_spec)
        and os.path.samefile(src_spec, dst_spec)
    ):
        raise FleetError(f"{src_spec}: source and target of the migration are the same database")
    with FleetDB(src_spec, create=False, readonly=True) as src:  # the source is read, never upgraded
        rows = sorted(src.measurements(), key=lambda m: m.id)
        scans = src.link_scans()
        scans = {m.sha256: scans.get(m.id) or LinkScan.not_run(BEFORE_LINK_SCANS) for m in rows}
        with FleetDB(dst_spec) as dst:
            if src.path == dst.path and src.kind == dst.kind:
                raise FleetError(f"{src.path}: source and target of the migration are the same database")
            added, skipped = dst.insert_many(rows, scans)
            return {
                "source": src.path,
                "target": dst.path,
                "copied": added,
                "skipped": skipped,
                "target_total": len(dst.measurements()),
            }
