"""The fleet history on a PostgreSQL server, for many technicians adding at once (psycopg 3).

The same ``measurement`` table as the SQLite file (:mod:`vibkit.fleet.schema`; ``DOUBLE PRECISION``
for the reals, an identity column for ``id``) next to a small ``vibkit_fleet_meta`` table that says
whose it is and its schema version.  Every measurement is one transaction in which the writer holds
a transaction-scoped advisory lock on its unit (``pg_advisory_xact_lock``), so the duplicate check,
the unit's nominal pitch and the ``INSERT`` see no other writer of that unit; the ``UNIQUE``
constraint on ``sha256`` refuses the same file stored under two units at once.  Readers never wait.

The URL is libpq's (``postgresql://user@host:5432/dbname``, ``?host=/socket/dir``, ``sslmode=...``);
a password is best left to ``PGPASSWORD`` or ``~/.pgpass`` rather than the URL.

Who may do what is the server's business: :func:`roles_sql` gives the statements of two group roles, a
technician's (:data:`TECHNICIAN_ROLE`: may add visits, and read) and a reader's (:data:`READER_ROLE`: may
only read), for the database's owner to run once; a role refused a write gets one line naming the role and
what it lacks.
"""

from __future__ import annotations

import contextlib
import re

from .errors import FleetError
from .links import BEFORE_LINK_SCANS
from .schema import (
    APPLICATION_ID,
    COLUMNS,
    FLAG_ALTERNATIVES_DDL,
    SCHEMA_VERSION,
    SIGMA_UNSTATED_SQL,
    SIGMA_ZERO_UNSTATED_BEFORE,
    link_ddl,
    measurement_ddl,
    signature_problem,
)
from .store import Store

__all__ = ["PostgresStore", "redact_url", "roles_sql", "TECHNICIAN_ROLE", "READER_ROLE"]

_META = "vibkit_fleet_meta"
_APPLICATION = "vibkit-fleet"
#: the group role of those who add visits (fleet add, scan, migrate into the history): INSERT, and all a reader has
TECHNICIAN_ROLE = "vibkit_technician"
#: the group role of those who only read (fleet status, report): SELECT
READER_ROLE = "vibkit_reader"


def _ident(name) -> str:
    """``name`` as a quoted SQL identifier."""
    return '"' + str(name).replace('"', '""') + '"'


def roles_sql(database="fleet", schema="public") -> str:
    """The SQL that gives a fleet history on PostgreSQL its two group roles, for the database's owner (or a
    superuser) to run once, e.g. with ``psql -d fleet -f roles.sql``; running it again changes nothing.

    :data:`READER_ROLE` may connect and read every table of ``schema`` (``fleet status``, ``fleet report``);
    :data:`TECHNICIAN_ROLE` may also insert (``fleet add``, ``fleet scan``, ``fleet migrate`` into it), but
    neither update nor delete: a visit once stored stays as it was.  Neither may create tables, so the owner
    creates the history (a first ``vibkit fleet add`` or ``migrate`` as the owner) and upgrades it after a
    vibkit that changes the schema; the default privileges cover the tables an upgrade adds.  A person gets a
    login role of their own that is a member of one of the two (the SQL's last lines, commented out).  The
    grants are on every table of ``schema``: keep the fleet in a database or schema of its own.
    """
    db, sch, tech, reader = _ident(database), _ident(schema), TECHNICIAN_ROLE, READER_ROLE
    return "\n".join(
        [
            f"-- vibkit fleet history {database}: a reader ({reader}) may only read, a technician ({tech}) may also",
            "-- add visits; run as the database's owner, after the history exists (a first vibkit fleet add as the owner)",
            "DO $$ BEGIN",
            f"  IF NOT EXISTS (SELECT FROM pg_roles WHERE rolname = '{reader}') THEN CREATE ROLE {reader} NOLOGIN; END IF;",
            f"  IF NOT EXISTS (SELECT FROM pg_roles WHERE rolname = '{tech}') THEN CREATE ROLE {tech} NOLOGIN; END IF;",
            "END $$;",
            f"GRANT {reader} TO {tech};",
            f"REVOKE ALL ON DATABASE {db} FROM PUBLIC;",
            f"GRANT CONNECT ON DATABASE {db} TO {reader};",
            f"GRANT USAGE ON SCHEMA {sch} TO {reader};",
            f"GRANT SELECT ON ALL TABLES IN SCHEMA {sch} TO {reader};",
            f"GRANT INSERT ON ALL TABLES IN SCHEMA {sch} TO {tech};",
            f"GRANT USAGE ON ALL SEQUENCES IN SCHEMA {sch} TO {tech};",
            f"ALTER DEFAULT PRIVILEGES IN SCHEMA {sch} GRANT SELECT ON TABLES TO {reader};",
            f"ALTER DEFAULT PRIVILEGES IN SCHEMA {sch} GRANT INSERT ON TABLES TO {tech};",
            f"ALTER DEFAULT PRIVILEGES IN SCHEMA {sch} GRANT USAGE ON SEQUENCES TO {tech};",
            "-- one login role a person, e.g.:",
            f"-- CREATE ROLE alice LOGIN PASSWORD '...' IN ROLE {tech};   -- a technician",
            f"-- CREATE ROLE bob LOGIN PASSWORD '...' IN ROLE {reader};   -- a manager who reads",
            "",
        ]
    )


def redact_url(url) -> str:
    """The URL with its password replaced by ``***`` (for messages)."""
    s = re.sub(r"(://[^/@:]*:)[^@/]*@", r"\1***@", str(url))
    return re.sub(r"(password=)[^&\s]*", r"\1***", s)


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


def _refused(location, con, exc, doing):
    """One line for a privilege the server refused (``doing``: what was tried), naming the role and the fix."""
    try:
        user = con.info.user
    except Exception:  # noqa: BLE001 - a closed connection: the message without the name
        user = "?"
    return FleetError(
        f"{location}: role {user!r} may not {doing}: {_one_line(exc)} (a {READER_ROLE} may only read; adding "
        f"visits needs {TECHNICIAN_ROLE}, creating or upgrading the history its owner: see vibkit fleet roles)"
    )


class PostgresStore(Store):
    """A fleet history on a PostgreSQL server.  ``create=False``: no tables are created; ``readonly=True``: nothing
    is written (a history of an older schema is read as it is, without link scans: :attr:`notes` says so)."""

    dialect = "postgresql"
    placeholder = "%s"
    local_files = ()

    def __init__(self, url, *, create=True, readonly=False, db_env="VIBKIT_FLEET_DB"):
        self.location = self.path = redact_url(url)
        self.readonly = bool(readonly)
        #: what opening it did that a user should know (one line each, for stderr)
        self.notes = []
        try:
            import psycopg
        except ImportError:
            raise FleetError(
                f"{self.location}: a PostgreSQL fleet database needs the psycopg package "
                "(pip install 'vibkit[postgres]')"
            ) from None
        self._psycopg = psycopg
        try:
            self._con = psycopg.connect(str(url), autocommit=True, connect_timeout=30, application_name="vibkit fleet")
        except psycopg.Error as exc:
            raise FleetError(
                f"{self.location}: cannot connect to the PostgreSQL server: {_one_line(exc)} (check the "
                f"URL given by --db or {db_env}, that the server runs, and PGPASSWORD or ~/.pgpass)"
            ) from None
        try:
            self._prepare(create, db_env)
        except psycopg.errors.InsufficientPrivilege as exc:
            err = _refused(self.location, self._con, exc, "open this fleet history as asked")
            self._con.close()
            raise err from None
        except psycopg.Error as exc:
            self._con.close()
            raise FleetError(f"{self.location}: not a usable fleet database: {_one_line(exc)}") from None
        except BaseException:
            self._con.close()
            raise

    def _tables(self):
        """Whether ``measurement`` and the meta table exist in the current schema (an MVCC query of the
        catalogue: it sees what another creator committed a moment ago)."""
        r = self._con.execute(
            "SELECT count(*) FILTER (WHERE c.relname = 'measurement'), "
            "count(*) FILTER (WHERE c.relname = %s) FROM pg_class c JOIN pg_namespace n "
            "ON n.oid = c.relnamespace WHERE n.nspname = current_schema() "
            "AND c.relname IN ('measurement', %s)",
            (_META, _META),
        ).fetchone()
        return bool(r[0]), bool(r[1])

    def _prepare(self, create, db_env):
        con = self._con
        have_m, have_meta = self._tables()
        if not have_meta:
            if have_m:
                raise FleetError(
                    f"{self.location}: has a table 'measurement' that is not a vibkit fleet's (no "
                    f"{_META} table); refusing to write into it (use another database or schema)"
                )
            if not create:
                raise FleetError(
                    f"{self.location}: no fleet database here (vibkit fleet add, scan or migrate creates "
                    f"one; --db or {db_env} names another)"
                )
            with con.transaction():
                con.execute("SELECT pg_advisory_xact_lock(%s)", (APPLICATION_ID,))  # one creator at a time
                have_m, have_meta = self._tables()
                if not have_meta:
                    for stmt in measurement_ddl("postgresql") + link_ddl("postgresql"):
                        con.execute(stmt)
                    con.execute(f"CREATE TABLE {_META} (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
                    con.execute(
                        f"INSERT INTO {_META} VALUES ('application', %s), ('schema_version', %s)",
                        (_APPLICATION, str(SCHEMA_VERSION)),
                    )
        meta = dict(con.execute(f"SELECT key, value FROM {_META}").fetchall())
        if meta.get("application") != _APPLICATION:
            raise FleetError(
                f"{self.location}: table {_META} names application {meta.get('application')!r}, "
                f"not {_APPLICATION!r}; refusing to write into it"
            )
        have = con.execute(
            "SELECT column_name FROM information_schema.columns WHERE table_schema = current_schema() "
            "AND table_name = 'measurement'"
        ).fetchall()
        problem = signature_problem(r[0] for r in have)
        if problem:  # the table's signature before anything is written
            raise FleetError(f"{self.location}: {problem}")
        ver = int(meta.get("schema_version", "0"))
        if ver > SCHEMA_VERSION:
            raise FleetError(
                f"{self.location}: written by a newer vibkit (schema {ver}, this one reads {SCHEMA_VERSION})"
            )
        if ver < 2:  # pragma: no cover - every PostgreSQL history has been schema 2 or later
            raise FleetError(f"{self.location}: schema {ver} is older than this vibkit reads (2 to {SCHEMA_VERSION})")
        if ver < SCHEMA_VERSION:
            self._upgrade(ver)

    def _upgrade(self, ver):
        """Schema 2 -> 3 (the link scans), 3 -> 4 (a flagged link's alternatives) and 4 -> 5 (a speed uncertainty not
        stated stored as NULL, not 0): in place, in one transaction under the creators' lock; read only, the history
        is read as it is (schema 2: every measurement's link scan "not run"; schema 3: its flagged links without
        alternatives; before 5: a sigma of 0 read as not stated)."""
        if self.readonly:
            self.has_link_tables = ver >= 3
            self.has_link_alternatives = ver >= 4
            self.zero_sigma_unstated = ver < SIGMA_ZERO_UNSTATED_BEFORE
            lacks = self.older_schema_lacks()
            self.notes.append(
                f"{self.location}: read a schema-{ver} history without upgrading it ({lacks}); vibkit fleet "
                f"add or scan upgrades it to schema {SCHEMA_VERSION}"
            )
            return
        con = self._con
        with con.transaction():
            con.execute("SELECT pg_advisory_xact_lock(%s)", (APPLICATION_ID,))  # one upgrader at a time
            now = int(con.execute(f"SELECT value FROM {_META} WHERE key = 'schema_version'").fetchone()[0])
            if now >= SCHEMA_VERSION:  # another process upgraded it a moment ago
                return
            for stmt in link_ddl("postgresql"):
                con.execute(stmt)
            con.execute(f"ALTER TABLE flagged_link ADD COLUMN IF NOT EXISTS {FLAG_ALTERNATIVES_DDL}")
            if now < SIGMA_ZERO_UNSTATED_BEFORE:  # its 0s meant "not stated"
                con.execute("ALTER TABLE measurement ALTER COLUMN speed_sigma_m_s DROP NOT NULL")
                con.execute(SIGMA_UNSTATED_SQL)
            con.execute(
                "INSERT INTO link_scan (measurement_id, status, reason) SELECT id, 'not run', %s FROM measurement "
                "WHERE id NOT IN (SELECT measurement_id FROM link_scan)",
                (BEFORE_LINK_SCANS,),
            )
            con.execute(f"UPDATE {_META} SET value = %s WHERE key = 'schema_version'", (str(SCHEMA_VERSION),))
        self.notes.append(f"{self.location}: upgraded in place from schema {ver} to schema {SCHEMA_VERSION}")

    @contextlib.contextmanager
    def write_transaction(self, unit):
        units = [unit] if isinstance(unit, str) else sorted(unit)
        with self._con.transaction():
            for u in units:  # sorted: two writers of several units never wait on each other in a circle
                self._con.execute("SELECT pg_advisory_xact_lock(%s, hashtext(%s))", (APPLICATION_ID, str(u)))
            yield

    def execute(self, sql, args=()):
        try:
            return self._con.execute(sql, args)
        except self._psycopg.errors.InsufficientPrivilege as exc:
            raise _refused(self.location, self._con, exc, "do this on the fleet history") from None
        except self._psycopg.Error as exc:
            raise FleetError(f"{self.location}: query failed on the PostgreSQL server: {_one_line(exc)}") from None

    def _insert_row(self, values):
        r = self._con.execute(
            f"INSERT INTO measurement ({', '.join(COLUMNS)}) VALUES ({', '.join(['%s'] * len(COLUMNS))}) RETURNING id",
            values,
        ).fetchone()
        return int(r[0])

    def _is_unique_violation(self, exc):
        return isinstance(exc, self._psycopg.errors.UniqueViolation)

    def _as_fleet_error(self, exc):
        if isinstance(exc, self._psycopg.errors.InsufficientPrivilege):
            return _refused(self.location, self._con, exc, "add visits to this fleet history (nothing was stored)")
        if isinstance(exc, self._psycopg.Error):
            return FleetError(
                f"{self.location}: the PostgreSQL server refused the measurement or the connection was "
                f"lost: {_one_line(exc)} (nothing of it was stored)"
            )
        return None

    def integrity_check(self) -> str:
        """``"ok"`` when the table's indexes (the ``sha256`` uniqueness among them) are valid."""
        bad = self._con.execute(
            "SELECT i.indexrelid::regclass::text FROM pg_index i WHERE "
            "i.indrelid = 'measurement'::regclass AND NOT (i.indisvalid AND i.indisready)"
        ).fetchall()
        return "ok" if not bad else "invalid index(es): " + ", ".join(r[0] for r in bad)

    def close(self):
        self._con.close()
