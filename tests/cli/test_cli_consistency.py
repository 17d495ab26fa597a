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


def _option_help(command, flag):
    import argparse

    from vibkit.cli.app import _parser

    parser = _parser()
    for name in command.split():
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[name]
    action = next(a for a in parser._actions if flag in a.option_strings)
    return " ".join((action.help % {"default": action.default} if action.help else "").split())


@pytest.mark.parametrize("command", ["pitch", "spectrum", "links", "report", "ride", "fleet add"])
def test_speed_help_gives_the_units_it_takes(command):
    text = _option_help(command, "--speed")
    assert "m/s, or 0.49m/s, 49cm/s, 29.4m/min, 96.5ft/min" in text and "[m/s]" not in text, text
    assert "(default: the --escalator profile's, else " in text, text


def test_fleet_add_speed_help_says_the_file_speed_is_taken():
    text = _option_help("fleet add", "--speed")
    assert "else the speed the file states" in text and "else required" not in text, text


@pytest.mark.parametrize("command", ["pitch", "spectrum", "report", "fleet add"])
def test_nominal_pitch_help_gives_the_units_it_takes(command):
    text = _option_help(command, "--nominal-pitch")
    assert "m, or 133.33mm, 13.333cm, 5.25in" in text and "[m]" not in text, text


@pytest.mark.parametrize("command", ["pitch", "spectrum", "report", "fleet status", "fleet report"])
def test_limits_help_gives_the_format_and_default(command):
    text = _option_help(command, "--limits")
    assert "watch,plan,replace [%]: three increasing percentages, comma-separated (default 1.5,2,3)" in text, text


@pytest.mark.parametrize("flag", ["--force", "--overwrite"])
def test_fleet_report_takes_overwrite_as_force(flag):
    from vibkit.cli.app import _parser

    assert _parser().parse_args(["fleet", "report", "-o", "x.pdf", flag]).force is True


@pytest.mark.parametrize(
    "value, read",
    [
        ("0.05", "'0.05' is 0.05 m = 50 mm"),
        ("0.01", "'0.01' is 0.01 m = 10 mm"),
        ("0.004", "'0.004' is 0.004 m = 4 mm"),
    ],
)
def test_min_excess_bare_number_says_how_it_was_read(value, read, capsys):
    err = _usage_error(["links", LEON, "--min-excess", value], capsys)
    assert f"argument --min-excess: {read} (a bare number is metres" in err, err
    assert f"give the unit, e.g. {value}mm" in err, err


@pytest.mark.parametrize(
    "value, metres", [("0.05mm", 5e-5), ("0.003", 3e-3), ("0.0002", 2e-4), ("4mm", 4e-3), ("0", 0.0)]
)
def test_min_excess_with_its_unit_or_a_plausible_bare_number(value, metres):
    from vibkit.cli.links import excess_length

    assert excess_length(value) == pytest.approx(metres)


@pytest.mark.parametrize(
    "argv",
    [["links", LEON], ["report", LEON, "-o", "x.pdf"], ["fleet", "add", LEON]],
    ids=lambda argv: " ".join(argv[:2]) if argv[0] == "fleet" else argv[0],
)
@pytest.mark.parametrize("value, s", [("12.4s", 12.4), ("12.4", 12.4), ("850ms", 0.85), ("2.5min", 150.0), ("0", 0.0)])
def test_marker_takes_a_time_unit(argv, value, s):
    from vibkit.cli.app import _parser

    assert _parser().parse_args([*argv, "--marker", value]).marker == pytest.approx(s)


@pytest.mark.parametrize("value", ["12.4h", "abc", "-1s"])
def test_marker_refuses_an_unknown_unit_or_a_negative_time(value, capsys):
    err = _usage_error(["links", LEON, f"--marker={value}"], capsys)
    assert err.startswith("vibkit links: error: argument --marker: expected a time"), err
