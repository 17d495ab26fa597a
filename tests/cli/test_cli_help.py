"""``--help`` of every command and subcommand: exit 0, no traceback, at most 100 columns.

The commands are found by walking the parser (a command added later is covered without editing
this test).  ``COLUMNS=100``: argparse wraps the option help to the terminal; the examples in the
epilogs are written by hand and must fit by themselves.

``--channel``'s help says what each command analyses without it (every channel, or which one).
"""

import argparse
import json
from pathlib import Path

import pytest

from vibkit.cli import main
from vibkit.cli.app import _parser

WIDTH = 100
SHEET = Path(__file__).resolve().parents[2] / "data" / "field" / "layouts" / "spanish-spreadsheet.csv"


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


def _channel_help(command):
    parser = _parser()
    for name in command:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[name]
    return " ".join(next(a for a in parser._actions if "--channel" in a.option_strings).help.split())


@pytest.mark.parametrize(
    "command, default",
    [
        (("pitch",), "every vibration channel"),
        (("spectrum",), "every vibration channel"),
        (("report",), "every vibration channel"),
        (("links",), "the first in a length unit"),
        (("compare",), "every vibration channel"),  # compare decides as pitch and report do
        (("fleet", "add"), "every vibration channel"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, tuple) else None,
)
def test_channel_help_says_what_the_command_analyses_without_it(command, default):
    assert f"(default: {default}" in _channel_help(command)


def test_spectrum_without_channel_analyses_every_channel(capsys):
    """What the help of pitch and spectrum says: a file of two vibration channels gives a row for each."""
    rc = main(["spectrum", str(SHEET), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 1 and [c["channel"] for c in out["channels"]] == ["aceleracion", "desplazamiento"]
