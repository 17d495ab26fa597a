"""PostgreSQL roles for a fleet history, on a real server (pgserver, tests/fleet/conftest.py): the SQL of
``vibkit fleet roles`` run by the owner; a technician's login adds visits, a reader's is refused in one line
naming its role and the privilege, and reads the work list; neither may change a stored visit."""

from __future__ import annotations

import json
import os
import urllib.parse
from pathlib import Path

import pytest

from vibkit.cli import main
from vibkit.fleet.postgres_store import READER_ROLE, TECHNICIAN_ROLE, roles_sql

ROOT = Path(__file__).resolve().parents[2]
FLEET = ROOT / "data" / "fleet-example"
ADD = ["--unit", "E07", "--speed", "0.5", "--speed-uncertainty", "0.1%", "--nominal-pitch", "0.13333"]


def _as_user(url, user):
    """The same server and database, logged in as ``user`` (the local socket: pgserver trusts it)."""
    u = urllib.parse.urlsplit(url)
    netloc = user + "@" + u.netloc.rsplit("@", 1)[-1]
    return urllib.parse.urlunsplit(u._replace(netloc=netloc))


def test_roles_sql_names_the_database_and_quotes_it():
    sql = roles_sql('my "fleet"', "vk")
    assert 'GRANT CONNECT ON DATABASE "my ""fleet""" TO vibkit_reader;' in sql
    assert 'GRANT INSERT ON ALL TABLES IN SCHEMA "vk" TO vibkit_technician;' in sql
    assert "UPDATE" not in sql and "DELETE" not in sql  # a stored visit stays as it was


def test_cli_prints_the_sql_for_the_database_of_db(capsys):
    assert main(["fleet", "roles", "--db", "postgresql://owner@fleet-server/escalators"]) == 0
    out = capsys.readouterr().out
    assert out == roles_sql("escalators")
    assert main(["fleet", "roles", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert (d["database"], d["technician"], d["reader"]) == ("fleet", TECHNICIAN_ROLE, READER_ROLE)


@pytest.mark.slow  # a PostgreSQL server, three recordings analysed
def test_technician_adds_reader_only_reads(new_pg_url, capsys):
    import psycopg

    owner = new_pg_url()
    database = urllib.parse.urlsplit(owner).path.lstrip("/")
    # the owner creates the history (its first visit), then gives the roles
    assert main(["fleet", "add", str(FLEET / "E07" / "2024-11-20.csv"), "--db", owner, *ADD]) == 0
    capsys.readouterr()
    assert main(["fleet", "roles", "--db", owner]) == 0
    sql = capsys.readouterr().out
    tech, reader, nobody = (f"{who}_{os.getpid()}_{database[-6:]}" for who in ("tech", "reader", "nobody"))
    with psycopg.connect(owner, autocommit=True) as con:
        con.execute(sql)
        con.execute(sql)  # again: changes nothing, fails on nothing
        con.execute(f"CREATE ROLE {tech} LOGIN IN ROLE {TECHNICIAN_ROLE}")
        con.execute(f"CREATE ROLE {reader} LOGIN IN ROLE {READER_ROLE}")
        con.execute(f"CREATE ROLE {nobody} LOGIN")

    # a reader's fleet add: refused in one line naming the role and what it lacks; nothing stored
    assert main(["fleet", "add", str(FLEET / "E07" / "2025-11-19.csv"), "--db", _as_user(owner, reader), *ADD]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"role '{reader}' may not add visits to this fleet history" in err
    assert "permission denied for table measurement" in err and TECHNICIAN_ROLE in err

    # a technician's works
    assert main(["fleet", "add", str(FLEET / "E07" / "2025-11-19.csv"), "--db", _as_user(owner, tech), *ADD]) == 0
    capsys.readouterr()

    # the reader reads the work list: both visits the owner and the technician stored
    assert main(["fleet", "status", "--json", "--db", _as_user(owner, reader)]) == 0
    units = json.loads(capsys.readouterr().out)["units"]
    assert [u["unit"] for u in units] == ["E07"]
    with psycopg.connect(owner) as con:
        assert con.execute("SELECT count(*) FROM measurement").fetchone()[0] == 2

    # neither changes a stored visit; a login without a role may not even connect
    for who in (tech, reader):
        with psycopg.connect(_as_user(owner, who), autocommit=True) as con:
            for stmt in ("DELETE FROM measurement", "UPDATE measurement SET unit = 'X'"):
                with pytest.raises(psycopg.errors.InsufficientPrivilege):
                    con.execute(stmt)
    assert main(["fleet", "status", "--db", _as_user(owner, nobody)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "permission denied for database" in err and "Traceback" not in err
