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


PHYPHOX = str(ROOT / "data" / "field" / "layouts" / "phyphox.csv")


@pytest.mark.parametrize(
    "argv, text",
    [
        (["ride", PHYPHOX, "--segment", "3:1"], "vibkit ride: error: argument --segment: '3:1': expected 0 <= START"),
        (["ride", PHYPHOX, "--segment", "a"], "vibkit ride: error: argument --segment: 'a': expected START:END"),
        (["report", LEON, "-o", "x.pdf", "--segment", "3:1"], "vibkit report: error: argument --segment: '3:1'"),
        (["ride", PHYPHOX, "--weighting", "Wd,Wk"], "argument --weighting: 'Wd,Wk': 2 weightings for the three axes"),
        (["ride", PHYPHOX, "--weighting", "x=Wd,x=Wk"], "argument --weighting: 'x=Wd,x=Wk': axis x is given twice"),
    ],
)
def test_bad_segment_and_weighting_are_usage_errors(argv, text, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _usage_error(argv, capsys)
    assert err.startswith(f"vibkit {argv[0]}: error: ") and text in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "argv, prog",
    [
        (["simulate", "leon", "-o", "-", "--json"], "vibkit simulate"),
        (["report", LEON, "-o", "-", "--json"], "vibkit report"),
        (["fleet", "report", "-o", "-", "--json", "--db", "fleet.sqlite"], "vibkit fleet report"),
    ],
)
def test_stdout_output_and_json_are_a_usage_error(argv, prog, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == (
        f"{prog}: error: -o - writes the output to stdout, and so does --json: give one of them "
        f"(run '{prog} --help' for the options)\n"
    )
    assert list(tmp_path.iterdir()) == []
