"""What the fleet's SQLite and PostgreSQL stores share: the queries and the one-transaction insert.

A store (:class:`~vibkit.fleet.sqlite_store.SQLiteStore`, :class:`~vibkit.fleet.postgres_store.PostgresStore`)
supplies a connection, its parameter placeholder and :meth:`Store.write_transaction`, which serialises
the writers of one unit (SQLite: the database's write lock, ``BEGIN IMMEDIATE``; PostgreSQL: a
transaction-scoped advisory lock per unit).  The check for a duplicate (same SHA-256) and for the
unit's nominal pitch and the ``INSERT`` run inside it; the ``UNIQUE`` constraint on ``sha256`` is the
last word when two processes store the same file under different units at once.  A measurement's link scan
(:mod:`vibkit.fleet.links`) is written in the same transaction as its row.
"""

from __future__ import annotations

import abc
import math
from dataclasses import replace

from .errors import DuplicateRecordingError, FleetError
from .links import NOT_SCANNED, LinkScan, read_link_scans, write_link_scan
from .measurement import Measurement
from .schema import COLUMNS, measurement_values, row_to_measurement

__all__ = ["Store"]


class Store(abc.ABC):
    """Base of the fleet stores (see the module docstring); not used directly."""

    dialect = ""
    placeholder = "?"
    #: where the data live, for messages: a path, or a URL without its password
    location = ""
    #: whether the link-scan tables exist (False: an older schema read without upgrading it)
    has_link_tables = True
    #: whether ``flagged_link`` keeps each flag's alternative numbers (False: schema 3 read without upgrading it)
    has_link_alternatives = True
    #: an older history read as it is (schema < 5), whose ``speed_sigma_m_s`` 0 means "not stated"
    zero_sigma_unstated = False

    def older_schema_lacks(self) -> str:
        """What a history read at an older schema without upgrading it lacks (the oldest lack named)."""
        if self.has_link_alternatives:
            return "a speed uncertainty of 0 read as not stated"
        return "no alternative link numbers" if self.has_link_tables else "no link scans"

    # ----------------------------------------------------------------- to be supplied by a store
    @abc.abstractmethod
    def execute(self, sql, args=()): ...

    @abc.abstractmethod
    def write_transaction(self, unit):
        """Context manager: one transaction in which no other writer stores a measurement of ``unit``."""
        ...

    @abc.abstractmethod
    def _insert_row(self, values) -> int: ...

    def _is_unique_violation(self, exc) -> bool:  # a store that has no unique index to violate
        return False

    def _as_fleet_error(self, exc):
        """A :class:`FleetError` for a database error of this store (None: not one of them)."""
        return None

    @abc.abstractmethod
    def integrity_check(self) -> str: ...

    @abc.abstractmethod
    def close(self): ...

    # ------------------------------------------------------------------------------------ queries
    def q(self, sql):
        """``sql`` written with ``?`` placeholders, in this store's placeholder style."""
        return sql if self.placeholder == "?" else sql.replace("?", self.placeholder)

    def rows(self, where="", args=()):
        cur = self.execute(self.q(f"SELECT id, {', '.join(COLUMNS)} FROM measurement {where}"), args)
        try:
            return [row_to_measurement(r, zero_sigma_unstated=self.zero_sigma_unstated) for r in cur.fetchall()]
        except ValueError as exc:
            raise FleetError(f"{self.location}: {exc}") from None

    def find(self, sha256):
        r = self.rows("WHERE sha256 = ?", (str(sha256),))
        return r[0] if r else None

    def units(self):
        return [r[0] for r in self.execute("SELECT DISTINCT unit FROM measurement ORDER BY unit").fetchall()]

    def nominal_pitch(self, unit):
        r = self.execute(
            self.q("SELECT nominal_pitch_m FROM measurement WHERE unit = ? ORDER BY id DESC LIMIT 1"), (str(unit),)
        ).fetchone()
        return None if r is None else float(r[0])

    def count(self) -> int:
        return int(self.execute("SELECT count(*) FROM measurement").fetchone()[0])

    # ------------------------------------------------------------------------------------ writing
    @staticmethod
    def duplicate_message(what, m):
        return (
            f"{what}: already stored (same sha256) as measurement #{m.id} of unit {m.unit!r} dated "
            f"{m.date_utc[:10]}, from {m.path}"
        )

    def link_scans(self, unit=None):
        return read_link_scans(self, unit)

    def _check(self, m):
        """Raise what refuses ``m`` before anything of it is written: a stored duplicate, another nominal pitch."""
        old = self.find(m.sha256)
        if old is not None:
            raise DuplicateRecordingError(self.duplicate_message(m.path, old), old)
        nom = self.nominal_pitch(m.unit)
        if nom is not None and not math.isclose(nom, m.nominal_pitch_m, rel_tol=1e-9):
            raise FleetError(
                f"unit {m.unit!r} is stored with nominal pitch {nom:g} m, not "
                f"{m.nominal_pitch_m:g} m; one unit has one nominal pitch"
            )

    def _check_and_insert(self, m, link_scan=None):
        self._check(m)
        rid = self._insert_row(measurement_values(m))
        write_link_scan(self, rid, link_scan if link_scan is not None else LinkScan.not_run(NOT_SCANNED))
        return rid

    def insert(self, m: Measurement, link_scan=None) -> Measurement:
        """Store one measurement and its link scan (default: "not run") in its own transaction; the stored row
        (with its id).

        Raises
        ------
        DuplicateRecordingError
            The same file (SHA-256) is already stored (also when another process stored it a moment ago).
        FleetError
            The unit is stored with another nominal pitch.
        """
        try:
            with self.write_transaction(m.unit):
                rid = self._check_and_insert(m, link_scan)
        except (DuplicateRecordingError, FleetError):
            raise
        except Exception as exc:
            if not self._is_unique_violation(exc):
                err = self._as_fleet_error(exc)
                if err is None:
                    raise
                raise err from None
            old = self.find(m.sha256)  # stored by another process between our check and our insert
            if old is None:  # pragma: no cover - the row that collided was rolled back since
                raise FleetError(
                    f"{m.path}: another process stored the same file at the same moment and "
                    "then rolled back; run the command again"
                ) from None
            raise DuplicateRecordingError(self.duplicate_message(m.path, old), old) from None
        return replace(m, id=rid)

    def insert_batch(self, items):
        """Store ``[(Measurement, LinkScan or None)]`` in one transaction; per item, in order, the stored row (with
        its id) or the :class:`DuplicateRecordingError` / :class:`FleetError` that refused it (nothing of that item
        written: the checks run before its statements).

        Any other error (a database error, another process's row colliding on ``sha256``) rolls the whole batch
        back and is raised: nothing of it is stored, every row is whole or absent.
        """
        items = list(items)
        out = []
        if not items:
            return out
        with self.write_transaction(sorted({m.unit for m, _s in items})):
            for m, link_scan in items:
                try:
                    self._check(m)
                except (DuplicateRecordingError, FleetError) as exc:
                    out.append(exc)
                    continue
                rid = self._insert_row(measurement_values(m))
                write_link_scan(self, rid, link_scan if link_scan is not None else LinkScan.not_run(NOT_SCANNED))
                out.append(replace(m, id=rid))
        return out

    def insert_many(self, measurements, link_scans=None):
        """Store measurements in one transaction, leaving out those already stored (same SHA-256); their link
        scans from ``link_scans`` (``{sha256: LinkScan}``; a missing one is stored "not run").

        Returns ``(added, skipped)`` counts.  Any other refusal (a nominal pitch that differs from the
        unit's) rolls the whole transaction back and raises :class:`FleetError`.
        """
        ms = list(measurements)
        added = skipped = 0
        units = sorted({m.unit for m in ms})
        with self.write_transaction(units):
            for m in ms:
                try:
                    self._check_and_insert(m, (link_scans or {}).get(m.sha256))
                    added += 1
                except DuplicateRecordingError:
                    skipped += 1
        return added, skipped
