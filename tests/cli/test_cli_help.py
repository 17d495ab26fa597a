"""``--help`` of every command and subcommand: exit 0, no traceback, at most 100 columns.

The commands are found by walking the parser (a command added later is covered without editing
this test).  ``COLUMNS=100``: argparse wraps the option help to the terminal; the examples in the
epilogs are written by hand and must fit by themselves.
"""

import argparse

import pytest

from vibkit.cli import main
from vibkit.cli.app import _parser

WIDTH = 100


def _commands(parser, prefix=()):
    yield prefix
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _commands(sub, prefix + (name,))


COMMANDS = list(_commands(_parser()))


def test_every_command_is_found():
    names = {" ".join(c) for c in COMMANDS}
    assert {"", "simulate", "fleet", "fleet add", "fleet scan", "fleet status", "fleet report", "bench"} <= names
    assert len(COMMANDS) >= 14


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: " ".join(c) or "vibkit")
def test_help_exits_0_and_fits(command, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    with pytest.raises(SystemExit) as exc:
        main(list(command) + ["--help"])
    assert exc.value.code == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert out.startswith("usage: vibkit")
    wide = [line for line in out.splitlines() if len(line) > WIDTH]
    assert wide == [], f"lines over {WIDTH} columns: {wide}"
