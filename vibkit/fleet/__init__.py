"""Fleet history: measurements of many escalators over years, trends and forecasts of chain elongation.

Maintenance firms measure each escalator (a *unit*) again and again.  :class:`FleetDB` keeps every
measurement, one transaction each, in an embedded SQLite file (standard library; WAL journal) or on a
PostgreSQL server (``postgresql://...``, psycopg 3) that many technicians' processes write at once
(:func:`migrate` copies a history from one to the other): the link-pass estimate of :func:`vibkit.diagnose.pitch.estimate_pitch`, the pitch and the
elongation with their standard deviations, quality figures (SNR, warnings) and provenance (SHA-256
of the file, its path, vibkit's version, the time of analysis).  A file already stored (same
SHA-256) is refused, so re-running a scan skips what it has done.

:meth:`FleetDB.scan` analyses a folder of recordings on a Dask cluster
(:func:`vibkit.runtime.cluster.dask_client`); the workers only analyse, the calling process alone writes,
one committed transaction per recording, so a killed scan leaves complete rows only.

:meth:`FleetDB.status` fits, per unit, the elongation against time by weighted least squares
(:func:`fit_trend`, a pure function) and forecasts when each elongation limit will be reached
(:func:`forecast_limits`), ranking the units by urgency (:class:`UnitTrend`: the work list).  Only
measurements fit for a trend are fitted: each is stored with a quality flag (ok / inconclusive /
implausible); outliers (> 5 sigma from the trend of the others) are left out and listed; a drop in
elongation (or ``replaced``) starts a new segment; a shortening rate is implausible, not forecast.

Each measurement also stores its recording's link scan, when :meth:`FleetDB.scan` knows the number of links
(:mod:`vibkit.fleet.links`): its status and the links it flagged; :func:`links_history` says which link came back
worse, only between visits whose link numbers count from a marked link.

Dates are stored as UTC ISO 8601 text and as seconds since 1970 (``date_unix_s``); trends are in
percent per Julian year (365.25 days).

Modules
-------
:mod:`~vibkit.fleet.errors`       :class:`FleetError`, :class:`DuplicateRecordingError`
:mod:`~vibkit.fleet.dates`        :func:`parse_date` and the UTC text the database stores
:mod:`~vibkit.fleet.trends`       :func:`fit_trend`, :func:`forecast_limits`, :class:`UnitTrend`, ranking (no database)
:mod:`~vibkit.fleet.quality`      the quality flag of a measurement (physical window, resolution)
:mod:`~vibkit.fleet.segments`     which measurements enter a trend: flags, replacements, outliers
:mod:`~vibkit.fleet.measurement`  :class:`Measurement`, :func:`analyse_recording`
:mod:`~vibkit.fleet.catalogue`    the CSV catalogue of a scan (its columns), :func:`read_catalogue`
:mod:`~vibkit.fleet.scan`         folder scans: file matching, Dask workers, :class:`ScanResult`
:mod:`~vibkit.fleet.links`        :class:`LinkScan`, :func:`links_history`: worn links across visits
:mod:`~vibkit.fleet.link_scan`    the link scan of a scan's recording (never costs its measurement)
:mod:`~vibkit.fleet.schema`       the ``measurement`` and link-scan tables of both stores
:mod:`~vibkit.fleet.store`        what both stores share: queries, the one-transaction insert
:mod:`~vibkit.fleet.sqlite_store` the SQLite file
:mod:`~vibkit.fleet.postgres_store` the PostgreSQL server (psycopg 3, advisory locks per unit)
:mod:`~vibkit.fleet.storage`      :class:`FleetDB`, :func:`resolve_db_path`, :func:`migrate`
"""

from .catalogue import CATALOGUE_COLUMNS, CatalogueRow, read_catalogue
from .dates import parse_date
from .errors import DuplicateRecordingError, FleetError
from .links import FlaggedLink, LinkScan, UnitLinks, links_history
from .measurement import Measurement, analyse_recording
from .scan import ScanResult
from .storage import DB_ENV, DEFAULT_DB_NAME, FleetDB, migrate, resolve_db_path
from .trends import LimitForecast, TrendFit, UnitTrend, fit_trend, forecast_limits

__all__ = [
    "DB_ENV",
    "DEFAULT_DB_NAME",
    "CATALOGUE_COLUMNS",
    "CatalogueRow",
    "DuplicateRecordingError",
    "FlaggedLink",
    "FleetDB",
    "FleetError",
    "LimitForecast",
    "LinkScan",
    "Measurement",
    "ScanResult",
    "TrendFit",
    "UnitLinks",
    "UnitTrend",
    "analyse_recording",
    "fit_trend",
    "forecast_limits",
    "links_history",
    "migrate",
    "parse_date",
    "read_catalogue",
    "resolve_db_path",
]
