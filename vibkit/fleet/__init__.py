"""Fleet history: measurements of many escalators over years, trends and forecasts of chain elongation.

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

Dates are stored as UTC ISO 8601 text and as seconds since 1970 (``date_unix_s``); trends are in
percent per Julian year (365.25 days).

Modules
-------
:mod:`~vibkit.fleet.errors`       :class:`FleetError`, :class:`DuplicateRecordingError`
:mod:`~vibkit.fleet.dates`        :func:`parse_date` and the UTC text the database stores
:mod:`~vibkit.fleet.trends`       :func:`fit_trend`, :func:`forecast_limits`, :class:`UnitTrend`, ranking (no database)
:mod:`~vibkit.fleet.measurement`  :class:`Measurement`, :func:`analyse_recording`
:mod:`~vibkit.fleet.catalogue`    the CSV catalogue of a scan (its columns), :func:`read_catalogue`
:mod:`~vibkit.fleet.scan`         folder scans: file matching, Dask workers, :class:`ScanResult`
:mod:`~vibkit.fleet.storage`      :class:`FleetDB` (SQLite), :func:`resolve_db_path`
"""

from .catalogue import CATALOGUE_COLUMNS, CatalogueRow, read_catalogue
from .dates import parse_date
from .errors import DuplicateRecordingError, FleetError
from .measurement import Measurement, analyse_recording
from .scan import ScanResult
from .storage import DB_ENV, DEFAULT_DB_NAME, FleetDB, resolve_db_path
from .trends import LimitForecast, TrendFit, UnitTrend, fit_trend, forecast_limits

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
