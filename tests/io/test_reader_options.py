"""The reader's options are declared once (vibkit.runtime.reader_options): read_recording's parameters, the readers'
mapping, the command line's flags and its mapping back all come from the one list, and agree with it both ways."""

from __future__ import annotations

import argparse
import inspect

import pytest

import vibkit
from vibkit.cli.options import READER_FLAGS, add_recording, reader_options
from vibkit.io import registry
from vibkit.runtime.reader_options import READER_OPTIONS, ReaderOptionError, options_of

DECLARED = {o.name: o for o in READER_OPTIONS}


def test_every_declared_option_is_a_parameter_of_read_recording_and_every_parameter_is_declared():
    params = dict(inspect.signature(vibkit.read_recording).parameters)
    params.pop("path")
    assert list(params) == [o.name for o in READER_OPTIONS]  # the same names, in the declared order
    for name, p in params.items():
        assert p.kind is inspect.Parameter.KEYWORD_ONLY, name
        assert p.default == DECLARED[name].default, name


def _parsed(argv):
    parser = argparse.ArgumentParser()
    add_recording(parser)
    return parser, parser.parse_args(["rec.csv", *argv])


def test_every_flag_has_its_option_and_every_option_with_a_flag_is_on_the_command_line():
    parser, _ = _parsed([])
    flags = {s for a in parser._actions for s in a.option_strings}
    declared = {o.flag for o in READER_OPTIONS if o.flag}
    assert declared <= flags, declared - flags
    # the reader's flags on the command line are the declared ones, nothing else (--segment is the command's)
    reading = next(g for g in parser._action_groups if g.title.startswith("reading the recording"))
    assert {s for a in reading._group_actions for s in a.option_strings} - {"--segment"} == declared
    assert READER_FLAGS == {o.name: o.flag for o in READER_OPTIONS if o.flag}
    # each flag's help is its declaration's
    for a in reading._group_actions:
        name = a.dest
        if name in DECLARED:
            assert a.help.startswith(DECLARED[name].help), name


def test_the_parsed_flags_map_back_to_read_recording_arguments():
    _, a = _parsed(
        ["--sample-rate", "200", "--time-column", "none", "--time-unit", "ms", "--units", "az=g", "--repair-time"]
        + ["--delimiter", "semicolon", "--decimal", ",", "--encoding", "cp1252", "--date-order", "dmy"]
    )
    opts = reader_options(a)
    assert opts == {
        "sample_rate": 200.0,
        "time_column": False,
        "time_unit": "ms",
        "units": {"az": "g"},
        "repair_time": True,
        "delimiter": ";",
        "decimal": ",",
        "encoding": "cp1252",
        "date_order": "dmy",
    }
    assert set(opts) <= set(inspect.signature(vibkit.read_recording).parameters)
    a.channel = "az"
    assert reader_options(a, channel=True)["channel"] == "az"


def test_the_readers_are_handed_the_options_of_their_scope():
    assert registry._COMMON == options_of("all") == ("channel", "sample_rate", "resample", "gap_factor", "repair_time")
    assert set(registry._TEXT_OPTIONS) == {o.name for o in READER_OPTIONS if o.scope in ("all", "text")}
    assert {o.name for o in READER_OPTIONS if o.scope == "open"} == {"max_bytes", "format"}


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"sample_rate": -1}, "sample_rate"),
        ({"resample": "cubic"}, "resample"),
        ({"gap_factor": 0.5}, "gap_factor"),
        ({"delimiter": "x"}, "delimiter"),
        ({"decimal": ";"}, "decimal"),
        ({"date_order": "ymd"}, "date_order"),
    ],
)
def test_a_bad_option_value_names_the_option_as_an_attribute(kw, name, tmp_path):
    p = tmp_path / "r.csv"
    p.write_text("time,az\n0,1\n0.01,2\n")
    with pytest.raises(ReaderOptionError) as exc:
        vibkit.read_recording(p, **kw)
    assert exc.value.parameter == name and name in str(exc.value)
    assert isinstance(exc.value, ValueError)  # as before: a bad option is a ValueError


def test_a_bad_unit_names_the_units_option(tmp_path):
    p = tmp_path / "r.csv"
    p.write_text("time,az\n0,1\n0.01,2\n")
    with pytest.raises(ReaderOptionError, match="not a unit vibkit knows") as exc:
        vibkit.read_recording(p, units="furlongs")
    assert exc.value.parameter == "units"
