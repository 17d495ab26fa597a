"""The command line says the same things the same way in every command: a usage error names its command and
exits 2, a shared option's help gives the same units and its real default."""

from __future__ import annotations

from pathlib import Path

import pytest

from vibkit.cli import main

ROOT = Path(__file__).resolve().parents[2]
LEON = str(ROOT / "data" / "field" / "leon-tensioner.csv")


def _usage_error(argv, capsys) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err, err
    return err


@pytest.mark.parametrize(
    "argv, prog, extra",
    [
        (["report", LEON, "-o", "x.pdf", "--makrer", "5"], "vibkit report", "--makrer 5"),
        (["fleet", "add", "x.csv", "--markr", "3"], "vibkit fleet add", "--markr 3"),
        (["pitch", LEON, "--speed", "0.5", "--bnad", "2:3", "extra"], "vibkit pitch", "--bnad 2:3 extra"),
    ],
)
def test_unknown_option_names_its_command(argv, prog, extra, capsys):
    err = _usage_error(argv, capsys)
    assert err == f"{prog}: error: unrecognized arguments: {extra} (run '{prog} --help' for the options)"


def test_unknown_option_leaves_nothing_in_the_namespace():
    from vibkit.cli.app import _parser

    args = _parser().parse_args(["pitch", LEON, "--speed", "0.5"])
    assert not [k for k in vars(args) if k.startswith("_")]
