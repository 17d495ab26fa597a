"""The command line in-process: the ``run`` fixture and the one-line error check of a command."""

from __future__ import annotations

import pytest


@pytest.fixture
def run(capsys):
    """Run the CLI; returns (exit code, stdout, stderr), never raising for bad data."""

    from vibkit.cli import main  # here, not at the top: conftest.py imports this module before it sets MPLBACKEND

    def _run(*argv):
        rc = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        assert "Traceback" not in out + err
        return rc, out, err

    return _run


def one_line_error(result, path, *words):
    """``result`` of ``run`` is exit 1 with one stderr line that names ``path`` and holds every word."""
    rc, out, err = result
    assert rc == 1, (rc, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert str(path) in lines[0], lines[0]
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]
