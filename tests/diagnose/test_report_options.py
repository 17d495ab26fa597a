"""The report's options are declared once (:class:`vibkit.runtime.report_options.ReportOptions`): the library's
signatures and docstrings list exactly its fields, the command line gives each field that has a flag from that flag,
and an unknown option is refused by name."""

import dataclasses
import inspect

import pytest

from vibkit.cli import report as cli_report
from vibkit.cli.app import _parser
from vibkit.diagnose.report import write_report
from vibkit.diagnose.report.context import analyse
from vibkit.runtime.report_options import ReportOptions

FIELDS = [f.name for f in dataclasses.fields(ReportOptions)]


def _report_parser():
    sub = next(a for a in _parser()._actions if a.dest == "command")
    return sub.choices["report"]


def test_the_library_takes_exactly_the_declared_options():
    for func, own in [(write_report, ["recording", "out_path", "overwrite"]), (analyse, ["recording"])]:
        params = inspect.signature(func).parameters
        assert list(params) == own + FIELDS
        for f in dataclasses.fields(ReportOptions):
            assert params[f.name].default == f.default and params[f.name].kind is inspect.Parameter.KEYWORD_ONLY
            assert f"    {f.name} : {f.metadata['takes']}, optional\n" in func.__doc__
        assert "**options" not in func.__doc__


@pytest.mark.parametrize("func", [analyse, write_report])
def test_an_unknown_option_is_refused_by_name(func, tmp_path):
    args = ("rec.csv", tmp_path / "r.pdf") if func is write_report else ("rec.csv",)
    with pytest.raises(TypeError, match=rf"{func.__name__}\(\) got an unexpected keyword argument 'sped' \(its op"):
        func(*args, sped=0.5)


def test_every_flag_of_the_table_is_a_flag_of_the_command():
    flags = {s for a in _report_parser()._actions for s in a.option_strings}
    declared = [f.metadata["flag"] for f in dataclasses.fields(ReportOptions) if f.metadata["flag"]]
    assert set(declared) <= flags
    assert len(declared) == len(set(declared))


def test_the_command_line_gives_each_option_from_its_flag(tmp_path):
    profile_file = tmp_path / "E1.toml"
    argv = [
        "report", "rec.csv", "-o", str(tmp_path / "r.pdf"), "--scene", "sim/leon.toml", "--speed", "0.52",
        "--speed-uncertainty", "0.01", "--channel", "az", "--nominal-pitch", "133.33mm", "--limits", "1,2,4",
        "--sample-rate", "200", "--duration", "3", "--band", "3:5", "--date", "2026-01-02", "--segment", "1:9",
        "--marker", "2.5", "--escalator", str(profile_file), "--time-unit", "ms",
    ]  # fmt: skip
    a = _parser().parse_args(argv)
    profile = object()  # what --escalator names, as the command loads it
    o = cli_report.options_of(a, profile)
    assert o.scene == "sim/leon.toml" and o.profile is profile and o.progress is True
    assert (o.speed, o.speed_sigma, o.channel) == (0.52, 0.01, "az")
    assert o.nominal_pitch == pytest.approx(0.13333, rel=1e-12)
    assert tuple(o.limits_percent) == (1.0, 2.0, 4.0)
    assert (o.duration, tuple(o.band), o.date, tuple(o.segment), o.marker_s) == (3.0, (3.0, 5.0), "2026-01-02",
                                                                                 (1.0, 9.0), 2.5)  # fmt: skip
    # the sample rate reaches the reader with the other reader flags, as before
    assert o.sample_rate is None and o.read_options["sample_rate"] == 200.0 and o.read_options["time_unit"] == "ms"
    # unset: the library's defaults, the scene from the profile where --scene is not given
    bare = _parser().parse_args(["report", "rec.csv", "-o", str(tmp_path / "r.pdf")])
    o = cli_report.options_of(bare, None)
    assert (o.scene, o.speed, o.speed_sigma, o.band, o.duration, o.date, o.segment, o.marker_s) == (None,) * 8
    assert o.hampel_half_window_s == 0.1 and o.hampel_false_alarm_rate == 1e-4


def test_a_percentage_uncertainty_is_passed_as_text(tmp_path):
    a = _parser().parse_args(["report", "rec.csv", "-o", str(tmp_path / "r.pdf"), "--speed-uncertainty", "2%"])
    assert cli_report.options_of(a, None).speed_sigma == "2%"
