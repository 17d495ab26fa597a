"""What the fleet's tests share: a real PostgreSQL server for the session (pgserver), skipped where it cannot start."""

import os
import tempfile
import warnings

import pytest


@pytest.fixture(scope="session")
def pg_server():
    """A PostgreSQL server of this test session (pgserver ships the binaries; as root it runs them as the
    system user 'pgserver', which it creates).  Skipped, with the reason, where it cannot start."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # platformdirs warns when XDG_RUNTIME_DIR is unset
            import pgserver
        import psycopg  # noqa: F401
    except ImportError as exc:
        pytest.skip(f"PostgreSQL tests need pgserver and psycopg (pip install -e '.[test]'): {exc}")
    # its own folder under the system temp dir: as root, pgserver opens every parent folder of the data
    # directory to its 'pgserver' user, which must not loosen pytest's private temp folder
    data = tempfile.mkdtemp(prefix="vibkit-pg-")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            srv = pgserver.get_server(data, cleanup_mode="delete")
    except Exception as exc:  # noqa: BLE001 - report why, skip the server tests
        pytest.skip(f"pgserver could not start a PostgreSQL server in {data}: {type(exc).__name__}: {exc}")
    yield srv
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        srv.cleanup()


_N_DB = [0]


@pytest.fixture
def new_pg_url(pg_server):
    """A function that creates an empty database on the session's server and gives its URL."""
    import psycopg

    def make():
        _N_DB[0] += 1
        name = f"fleetlinks_{os.getpid()}_{_N_DB[0]}"
        with psycopg.connect(pg_server.get_uri(), autocommit=True) as con:
            con.execute(f"CREATE DATABASE {name}")
        return pg_server.get_uri(name)

    return make
