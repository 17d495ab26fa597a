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
import time
import urllib.parse

from .errors import FleetError
from .links import BEFORE_LINK_SCANS
from .quality import measurement_quality
from .schema import (
    APPLICATION_ID,
    COLUMNS,
    FLAG_ALTERNATIVES_DDL,
    QUALITY_FLAG_SQL,
    QUALITY_REASON_SQL,
    SCHEMA_VERSION,
    SIGMA_UNSTATED_SQL,
    SIGMA_ZERO_UNSTATED_BEFORE,
    V2_COLUMNS,
    column_def,
    link_ddl,
    measurement_ddl,
    signature_problem,
    upgraded_view_sql,
)
from .store import Store

__all__ = ["SQLiteStore", "sqlite_error"]

_SQLITE_MAGIC = b"SQLite format 3\x00"


def _no_room(path) -> str:
    """Why the folder of ``path`` takes no more bytes (a full disk, a file-size limit), or "" when it does."""
    import shutil

    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if soft != resource.RLIM_INFINITY:
            return f"a file-size limit of {soft} bytes is set (ulimit -f); raise it"
    except (ImportError, OSError, ValueError):
        pass
    try:
        free = shutil.disk_usage(os.path.dirname(os.path.abspath(os.fspath(path)))).free
    except OSError:
        return ""
    return f"the disk is full ({free} bytes free); free space, or give a --db elsewhere" if free < 1 << 20 else ""


def sqlite_error(path, exc) -> FleetError:
    """One line naming the database, what went wrong and what to do, for a ``sqlite3.Error``."""
    text = " ".join(str(exc).split())
    low = text.lower()
    if "malformed" in low or "not a database" in low or "corrupt" in low:
        why = (
            f"the database file is damaged ({text}); left as it is, nothing stored; restore it from a backup, or recover what is readable "
            f"with: sqlite3 {path} .recover | sqlite3 recovered.sqlite"
        )
    elif "readonly" in low or "read-only" in low:
        why = f"cannot write: the file or its folder is read-only ({text}); make both writable, or give a writable --db"
    elif "locked" in low or "busy" in low:
        why = f"locked by another process ({text}); try again when it has finished"
    elif ("unable to open" in low or "disk i/o" in low or "cannot open" in low or "full" in low) and (
        space := _no_room(path)
    ):
        why = f"cannot write the database's files ({text}): {space}; nothing was stored"
    elif "unable to open" in low or "disk i/o" in low or "cannot open" in low:
        why = (
            f"cannot open the database ({text}); check that the file and its folder exist and can be read "
            f"(and written, to add)"
        )
    elif "full" in low:
        why = f"the disk is full ({text}); nothing was stored"
    else:
        why = f"SQLite error: {text}"
    return FleetError(f"{path}: {why}")


class SQLiteStore(Store):
    """A fleet database file.  ``create=False``: a missing file is an error (nothing is created);
    ``readonly=True``: opened with SQLite's ``mode=ro`` and never written, not even the schema: a file of an
    older schema is read as it is, through a connection-private view (:attr:`notes` says so)."""

    dialect = "sqlite"
    placeholder = "?"

    def __init__(self, path, *, create=True, readonly=False, db_env="VIBKIT_FLEET_DB"):
        p = self.location = self.path = os.fspath(path)
        self.readonly = bool(readonly)
        #: what opening the file did that a user should know (one line each, for stderr)
        self.notes = []
        #: the schema version of the file as it was found
        self.file_schema_version = None
        if os.path.isdir(p):
            raise FleetError(f"{p}: is a folder; expected the fleet database file")
        exists = os.path.exists(p) and os.path.getsize(p) > 0
        if not exists and (not create or self.readonly):
            raise FleetError(
                f"{p}: no fleet database here (vibkit fleet add or scan creates one; --db or {db_env} names another)"
            )
        if exists:
            try:
                with open(p, "rb") as fh:
                    head = fh.read(16)
            except OSError as exc:
                raise FleetError(
                    f"{p}: cannot read the database: {exc.strerror or exc}; check its permissions"
                ) from None
            if head != _SQLITE_MAGIC:
                raise FleetError(f"{p}: not a SQLite database; expected a vibkit fleet database")
        parent = os.path.dirname(os.path.abspath(p))
        if not os.path.isdir(parent):
            raise FleetError(f"{p}: folder {parent} does not exist")
        #: no file at the path yet: the store answers from an empty in-memory database, and the file is made
        #: (atomically, O_EXCL) only at the first write; a command that fails before it leaves no file, and
        #: nothing is ever removed on the way out (another process may have made and filled it meanwhile)
        self._pending = not os.path.lexists(p)
        self._timeout_ms = 60000
        try:
            self._con = self._connect(":memory:" if self._pending else p)
        except sqlite3.Error as exc:
            raise sqlite_error(p, exc) from None
        try:
            self._prepare()
        except sqlite3.Error as exc:
            self._con.close()
            raise sqlite_error(p, exc) from None
        except FleetError:
            self._con.close()
            raise

    def _connect(self, p):
        if p == ":memory:":
            return sqlite3.connect(p, isolation_level=None)
        if not self.readonly:
            return sqlite3.connect(p, timeout=60.0, isolation_level=None)
        # read-only use (status, report) never writes, not even a journal: SQLite's read-only mode; a WAL
        # database in a read-only folder (no -shm file can be made) is read as immutable
        uri = "file:" + urllib.parse.quote(os.path.abspath(p)) + "?mode=ro"
        con = sqlite3.connect(uri, uri=True, timeout=60.0, isolation_level=None)
        try:
            con.execute("SELECT count(*) FROM sqlite_master").fetchone()
        except sqlite3.OperationalError:
            con.close()
            if os.access(os.path.dirname(os.path.abspath(p)), os.W_OK):
                raise
            con = sqlite3.connect(uri + "&immutable=1", uri=True, timeout=60.0, isolation_level=None)
        return con

    def set_timeout(self, seconds):
        """How long a write waits for another process's transaction before it is an error. [s]"""
        self._timeout_ms = int(float(seconds) * 1000)
        self._con.execute(f"PRAGMA busy_timeout = {self._timeout_ms}")

    def _materialise(self):
        """The first write of a store whose file did not exist: make the file, unless another process made it
        meanwhile (``O_CREAT | O_EXCL``: one of them creates it, none replaces it), and open it as an existing one.
        An empty file is a new SQLite database; its tables are created inside the write lock (:meth:`_prepare`), so
        two processes creating the same store at the same moment both store their rows in it."""
        p = self.path
        try:
            fd = os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            pass  # made by another process since this store was opened: used as it is
        except OSError as exc:
            raise FleetError(
                f"{p}: cannot create the database: {exc.strerror or exc}; check that its folder is writable "
                "(or give another --db)"
            ) from None
        else:
            os.close(fd)
        mem = self._con
        try:
            con = self._connect(p)
        except sqlite3.Error as exc:
            raise sqlite_error(p, exc) from None
        self._con, self._pending = con, False
        mem.close()
        con.execute(f"PRAGMA busy_timeout = {self._timeout_ms}")
        try:
            self._prepare()
        except sqlite3.Error as exc:
            raise sqlite_error(p, exc) from None

    @property
    def local_files(self):
        """The files of this database (a scan leaves them out)."""
        a = os.path.abspath(self.path)
        return (a, a + "-wal", a + "-shm", a + "-journal")

    def _check_sound(self):
        """SQLite's ``quick_check`` of an existing file before anything is read from or written to it: a damaged
        file (bytes overwritten in its middle) is refused whole, left as it is, rather than read in part or
        written into."""
        if self._pending or os.path.getsize(self.path) == 0:
            return
        res = [str(r[0]) for r in self._con.execute("PRAGMA quick_check(3)").fetchall()]
        if res != ["ok"]:
            raise sqlite_error(self.path, f"database disk image is malformed: {'; '.join(res)[:200]}")

    def _wal(self, con):
        """Put the database in WAL mode and say the mode it is in.  Changing the journal mode takes the database's
        exclusive lock, and SQLite answers "database is locked" at once, without its busy handler, while another
        process holds any lock (several processes adding to a store none of them has made yet: each makes it on its
        first write); so the change is tried again for as long as a write would wait."""
        deadline = time.monotonic() + self._timeout_ms / 1000.0
        while True:
            try:
                return con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
            except sqlite3.OperationalError as exc:
                if "locked" not in str(exc).lower() or time.monotonic() > deadline:
                    raise
                time.sleep(0.02)

    def _prepare(self):
        con = self._con
        self._check_sound()
        app = con.execute("PRAGMA application_id").fetchone()[0]
        ver = self.file_schema_version = con.execute("PRAGMA user_version").fetchone()[0]
        tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        if app not in (0, APPLICATION_ID) or (app == 0 and tables and "measurement" not in tables):
            raise FleetError(
                f"{self.path}: not a vibkit fleet database: a SQLite database of another application (tables: "
                f"{', '.join(tables) or 'none'}); refusing to write into it"
            )
        if "measurement" in tables:  # the table's signature before anything is written (not even the journal mode)
            problem = signature_problem(r[1] for r in con.execute("PRAGMA main.table_info(measurement)"))
            if problem:
                raise FleetError(f"{self.path}: {problem}")
        if ver > SCHEMA_VERSION:
            raise FleetError(f"{self.path}: written by a newer vibkit (schema {ver}, this one reads {SCHEMA_VERSION})")
        #: an older file read as it is: its speed_sigma_m_s 0 means "not stated" (schema 5 stores NULL)
        self.zero_sigma_unstated = self.readonly and ver < SIGMA_ZERO_UNSTATED_BEFORE
        if self.readonly:
            if "measurement" not in tables:
                raise FleetError(
                    f"{self.path}: a SQLite database without vibkit's measurement table, not a fleet "
                    f"history (vibkit fleet add or scan makes one; --db names another); left as it is"
                )
            self.has_link_tables = "link_scan" in tables
            self.has_link_alternatives = self.has_link_tables and "alternatives" in self._flag_columns()
            if ver < SCHEMA_VERSION:
                self._read_older_schema(ver)
            return
        if self._pending:  # nothing at the path yet: an empty fleet database in memory answers until the first write
            self._create_or_upgrade()
            return
        mode = self._wal(con)
        if str(mode).lower() != "wal":  # pragma: no cover - file systems without shared memory
            raise FleetError(f"{self.path}: SQLite cannot use its WAL journal here (mode {mode!r})")
        con.execute("PRAGMA synchronous=FULL")
        if "measurement" not in tables or ver < SCHEMA_VERSION:
            # the upgrade to schema 5 rebuilds the measurement table: without foreign keys while it does (the link
            # scans would cascade away with the old table), checked before it commits
            con.execute("PRAGMA foreign_keys=OFF")
            try:
                with self.write_transaction(()):
                    self._create_or_upgrade()
            except sqlite3.OperationalError as exc:
                if "readonly" not in str(exc).replace(" ", "").lower():
                    raise
                raise FleetError(
                    f"{self.path}: written by an older vibkit (schema {ver}); this one upgrades it to "
                    f"schema {SCHEMA_VERSION} in place, which needs write access to the file and its "
                    "folder (vibkit fleet status and report read it without upgrading it)"
                ) from None
            if "measurement" in tables:
                self.notes.append(f"{self.path}: upgraded in place from schema {ver} to schema {SCHEMA_VERSION}")
        con.execute("PRAGMA foreign_keys=ON")

    def _flag_columns(self):
        return {r[1] for r in self._con.execute("PRAGMA main.table_info(flagged_link)")}

    def _read_older_schema(self, ver):
        """Read-only: the rows of an older schema as the upgrade would store them, through a ``temp`` view that
        shadows the file's table on this connection only.  Nothing is written to the file, nothing copied: the
        view is evaluated row by row as a query reads it (the quality flag computed then), so opening costs no memory
        and no time that grow with the file."""
        con = self._con
        have = [r[1] for r in con.execute("PRAGMA main.table_info(measurement)")]
        if set(V2_COLUMNS) <= set(have):  # schema 2: the rows are as stored; only the link scans are missing
            self.notes.append(self._older_note(ver))
            return
        try:
            sql = upgraded_view_sql(have)
        except ValueError as exc:
            raise FleetError(f"{self.path}: schema {ver}: {exc}") from None

        def flag(e, s):
            return measurement_quality(e, s)[0]

        def reason(e, s):
            return measurement_quality(e, s)[1]

        con.create_function(QUALITY_FLAG_SQL, 2, flag, deterministic=True)
        con.create_function(QUALITY_REASON_SQL, 2, reason, deterministic=True)
        con.execute("PRAGMA temp_store=MEMORY")
        con.execute(sql)
        self.notes.append(self._older_note(ver))

    def _older_note(self, ver):
        lacks = self.older_schema_lacks()
        return (
            f"{self.path}: read a schema-{ver} history without upgrading it (left as it is; {lacks}); run "
            f"vibkit fleet add or scan on it with write access to upgrade it to schema {SCHEMA_VERSION}"
        )

    def _create_or_upgrade(self):
        """Inside the write lock: create the tables, or bring a version-1 to -4 file to the current schema."""
        con = self._con
        ver = con.execute("PRAGMA user_version").fetchone()[0]  # again: another process may have upgraded it
        tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        if "measurement" not in tables:
            for stmt in measurement_ddl("sqlite"):
                con.execute(stmt)
        else:
            have = {r[1] for r in con.execute("PRAGMA table_info(measurement)")}
            for col in V2_COLUMNS:
                if col not in have:
                    con.execute(f"ALTER TABLE measurement ADD COLUMN {column_def(col, 'sqlite')}")
            # the rows of a version-1 file get the quality flag by today's rules (a version-2 file's rows have it)
            v1 = not set(V2_COLUMNS) <= have
            for rid, e, s in con.execute(
                "SELECT id, elongation_percent, elongation_sigma_percent FROM measurement WHERE quality = 'ok' AND ?",
                (int(v1),),
            ).fetchall():
                flag, why = measurement_quality(e, s)
                if flag != "ok":
                    con.execute("UPDATE measurement SET quality = ?, quality_reason = ? WHERE id = ?", (flag, why, rid))
            if ver < SIGMA_ZERO_UNSTATED_BEFORE:
                self._rebuild_nullable_sigma()
        for stmt in link_ddl("sqlite"):
            con.execute(stmt)
        if "alternatives" not in self._flag_columns():  # a version-3 file: its flags are one number each
            con.execute(f"ALTER TABLE flagged_link ADD COLUMN {FLAG_ALTERNATIVES_DDL}")
        # every measurement stored before the link scans: "not run", so that none reads as scanned without a flag
        con.execute(
            "INSERT INTO link_scan (measurement_id, status, reason) SELECT id, 'not run', ? FROM measurement "
            "WHERE id NOT IN (SELECT measurement_id FROM link_scan)",
            (BEFORE_LINK_SCANS,),
        )
        con.execute(f"PRAGMA application_id={APPLICATION_ID}")
        con.execute(f"PRAGMA user_version={SCHEMA_VERSION}")

    def _rebuild_nullable_sigma(self):
        """Schema 4 -> 5, inside the write lock with foreign keys off: the measurement table rebuilt without
        ``speed_sigma_m_s NOT NULL`` (SQLite cannot drop a constraint in place; its documented procedure: a new
        table, the rows copied with their ids, the old one dropped, the new one renamed), the stored 0s, which meant
        "not stated", as NULL.  The link scans keep their rows (they name the same ids); a dangling reference
        stops the upgrade before it commits."""
        con = self._con
        new = "measurement_v5"
        create, index = measurement_ddl("sqlite", table=new)
        cols = ", ".join(("id",) + COLUMNS)
        con.execute(f"DROP TABLE IF EXISTS {new}")
        con.execute(create)
        con.execute(f"INSERT INTO {new} ({cols}) SELECT {cols} FROM measurement")
        con.execute("DROP TABLE measurement")
        con.execute(f"ALTER TABLE {new} RENAME TO measurement")
        con.execute(index)
        con.execute(SIGMA_UNSTATED_SQL)
        bad = con.execute("PRAGMA foreign_key_check").fetchall()
        if bad:  # pragma: no cover - every link scan names a stored measurement
            raise FleetError(
                f"{self.path}: the upgrade to schema {SCHEMA_VERSION} found {len(bad)} link scan row(s) "
                "naming no measurement; left as it was"
            )

    @contextlib.contextmanager
    def write_transaction(self, unit):
        if self.readonly:  # before any statement: an older file's rows are a view here, not the file's table
            raise sqlite_error(self.path, "opened read-only (mode=ro): attempt to write a readonly database")
        if self._pending:
            self._materialise()
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
        cur = self._con.execute(
            f"INSERT INTO measurement ({', '.join(COLUMNS)}) VALUES ({', '.join('?' * len(COLUMNS))})", values
        )
        return int(cur.lastrowid)

    def _is_unique_violation(self, exc):
        return isinstance(exc, sqlite3.IntegrityError) and "UNIQUE" in str(exc)

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` (``"ok"`` when the file is sound)."""
        return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    def close(self):
        self._con.close()
