"""The fleet history in one embedded SQLite file (standard library; the default store).

WAL journal and ``synchronous=FULL``: each measurement is one committed transaction, so a killed
process leaves complete rows only.  Writers take the database's write lock (``BEGIN IMMEDIATE``,
waiting up to 60 s), so many processes on one machine may add at once.  SQLite on a shared network
drive is not safe for writers on several machines: use the PostgreSQL store there.
"""

from __future__ import annotations

import contextlib
import os
import sqlite3

from .errors import FleetError
from .quality import measurement_quality
from .schema import APPLICATION_ID, COLUMNS, SCHEMA_VERSION, V2_COLUMNS, column_def, measurement_ddl
from .store import Store

__all__ = ["SQLiteStore"]

_SQLITE_MAGIC = b"SQLite format 3\x00"


class SQLiteStore(Store):
    """A fleet database file.  ``create=False``: a missing file is an error (nothing is created)."""

    dialect = "sqlite"
    placeholder = "?"

    def __init__(self, path, *, create=True, db_env="VIBKIT_FLEET_DB"):
        p = self.location = self.path = os.fspath(path)
        if os.path.isdir(p):
            raise FleetError(f"{p}: is a folder; expected the fleet database file")
        exists = os.path.exists(p) and os.path.getsize(p) > 0
        if not exists and not create:
            raise FleetError(f"{p}: no fleet database here (vibkit fleet add or scan creates one; --db or "
                             f"{db_env} names another)")
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
            self._prepare()
        except sqlite3.DatabaseError as exc:
            self._con.close()
            raise FleetError(f"{p}: not a usable fleet database: {exc}") from None
        except FleetError:
            self._con.close()
            raise

    @property
    def local_files(self):
        """The files of this database (a scan leaves them out)."""
        a = os.path.abspath(self.path)
        return (a, a + "-wal", a + "-shm", a + "-journal")

    def _prepare(self):
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
        if "measurement" not in tables or ver < SCHEMA_VERSION:
            try:
                with self.write_transaction(()):
                    self._create_or_upgrade()
            except sqlite3.OperationalError as exc:
                if "readonly" not in str(exc).replace(" ", "").lower():
                    raise
                raise FleetError(f"{self.path}: written by an older vibkit (schema {ver}); this one upgrades it to "
                                 f"schema {SCHEMA_VERSION} in place, which needs write access to the file and its "
                                 "folder (run any fleet command once where it may write)") from None

    def _create_or_upgrade(self):
        """Inside the write lock: create the table, or bring a version-1 file to the current schema."""
        con = self._con
        tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        if "measurement" not in tables:
            for stmt in measurement_ddl("sqlite"):
                con.execute(stmt)
        else:
            have = {r[1] for r in con.execute("PRAGMA table_info(measurement)")}
            for col in V2_COLUMNS:
                if col not in have:
                    con.execute(f"ALTER TABLE measurement ADD COLUMN {column_def(col, 'sqlite')}")
            # the rows of a version-1 file get the quality flag by today's rules
            for rid, e, s in con.execute("SELECT id, elongation_percent, elongation_sigma_percent FROM measurement "
                                         "WHERE quality = 'ok'").fetchall():
                flag, why = measurement_quality(e, s)
                if flag != "ok":
                    con.execute("UPDATE measurement SET quality = ?, quality_reason = ? WHERE id = ?", (flag, why, rid))
        con.execute(f"PRAGMA application_id={APPLICATION_ID}")
        con.execute(f"PRAGMA user_version={SCHEMA_VERSION}")

    @contextlib.contextmanager
    def write_transaction(self, unit):
        con = self._con
        con.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            con.execute("ROLLBACK")
            raise
        con.execute("COMMIT")

    def execute(self, sql, args=()):
        return self._con.execute(sql, args)

    def _insert_row(self, values):
        cur = self._con.execute(f"INSERT INTO measurement ({', '.join(COLUMNS)}) VALUES "
                                f"({', '.join('?' * len(COLUMNS))})", values)
        return int(cur.lastrowid)

    def _is_unique_violation(self, exc):
        return isinstance(exc, sqlite3.IntegrityError) and "UNIQUE" in str(exc)

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` (``"ok"`` when the file is sound)."""
        return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    def close(self):
        self._con.close()
