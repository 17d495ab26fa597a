"""The fast path (rows parsed by pandas' C reader) gives exactly the dataset of the line-by-line reader.

Every file is read twice, through ``read_recording`` (fast path, falling back when it must) and
through the line-by-line reader alone; the datasets must be identical but for the one history line
that says which parser read the rows.
"""

import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vibkit.io import RecordingError, read_recording
from vibkit.io.text import csv as vcsv
from vibkit.io.text.fastpath import _HEAD_BYTES

LAYOUTS = Path(__file__).resolve().parents[2] / "data" / "field" / "layouts"
FIELD = LAYOUTS.parent
FAST_NOTE = "parsed by pandas' C reader"


def slow(path, **kw):
    data = Path(path).read_bytes()
    return vcsv._read_csv(os.fspath(path), data, fast=False, **kw)


def outcome(fn):
    try:
        return fn()
    except RecordingError as err:
        return err


def same(fast, ref):
    """Identical datasets (or identical errors) but for the fast path's history line."""
    if isinstance(ref, Exception) or isinstance(fast, Exception):
        assert type(fast) is type(ref) and str(fast) == str(ref), (fast, ref)
        return
    hist = [h for h in fast.attrs["history"].splitlines() if FAST_NOTE not in h]
    assert hist == ref.attrs["history"].splitlines()
    a, b = fast.copy(), ref.copy()
    a.attrs.pop("history"), b.attrs.pop("history")
    xr.testing.assert_identical(a, b)


@pytest.mark.parametrize(
    "name",
    [
        "phyphox.csv",
        "physics-toolbox.csv",
        "endaq.csv",
        "gcdc-x16.csv",
        "spanish-spreadsheet.csv",
        "no-time-column.txt",
    ],
)
def test_layouts_read_the_same_both_ways(name):
    path = LAYOUTS / name
    same(read_recording(path), slow(path))


@pytest.mark.parametrize("name", ["leon-tensioner.csv", "las-palmas-accelerometer.csv"])
def test_field_cases_take_the_fast_path(name):
    ds = read_recording(FIELD / name)
    assert FAST_NOTE in ds.attrs["history"]
    same(ds, slow(FIELD / name))


def test_comment_line_among_the_data_falls_back_and_is_recorded(tmp_path):
    p = tmp_path / "c.csv"
    p.write_text("time (s),x (m)\n0,1\n0.1,2\n# operator left\n0.2,3\n0.3,4\n")
    ds = read_recording(p)
    assert FAST_NOTE not in ds.attrs["history"]
    assert "1 comment line(s) among or after the data skipped (line 4)" in ds.attrs["history"]
    np.testing.assert_array_equal(ds["x"].values, [1e0, 2, 3, 4])


def big_file(tmp_path, rows=60_000, mutate=None, name="big.csv"):
    """A file larger than the 1 MiB head the layout is read from."""
    t = np.arange(rows) / 1000.0
    lines = [f"{a:.3f},{np.sin(a):.9f},{np.cos(a):.9f}" for a in t]
    if mutate:
        mutate(lines)
    p = tmp_path / name
    p.write_text("# Site: test\ntime (s),x (m),y (mm)\n" + "\n".join(lines) + "\n")
    assert p.stat().st_size > _HEAD_BYTES
    return p


def test_file_larger_than_the_head_reads_the_same(tmp_path):
    p = big_file(tmp_path)
    ds = read_recording(p)
    assert FAST_NOTE in ds.attrs["history"] and ds.sizes["time"] == 60_000
    np.testing.assert_allclose(ds["y"].values, np.round(np.cos(np.arange(60_000) / 1000.0), 9) * 1e-3, rtol=1e-15)
    same(ds, slow(p))


@pytest.mark.parametrize(
    "where, edit, line, words",
    [
        (50_000, lambda s: "49.998" + s[6:], 50_003, "time goes backwards"),  # reversed time deep in the file
        (40_000, lambda s: "39.999" + s[6:], 40_003, "repeats the previous row"),  # repeated stamp
        (30_000, lambda s: s.split(",")[0] + ",1.0", 30_003, "expected 3 fields"),  # short ragged row
        (30_000, lambda s: s + ",7", 30_003, "expected 3 fields"),  # long ragged row
        (20_000, lambda s: s.replace(",", ",abc,", 1).rsplit(",", 1)[0], 20_003, "expected a number in column 'x (m)'"),
        (10_000, lambda s: s.split(",")[0][:-1] + "9e999," + ",".join(s.split(",")[1:]), 10_003, "time"),
    ],
)
def test_errors_deep_in_a_big_file_name_the_line(tmp_path, where, edit, line, words):
    def mutate(lines):
        lines[where] = edit(lines[where])

    p = big_file(tmp_path, mutate=mutate)
    with pytest.raises(RecordingError) as info:
        read_recording(p)
    assert str(info.value).startswith(f"{p}, line {line}: ") and words in str(info.value)
    assert "\n" not in str(info.value)


def test_blank_and_padding_lines_keep_line_numbers_right(tmp_path):
    def mutate(lines):
        lines.insert(100, "")
        lines.insert(200, ",,")
        lines[30_000] = "29.990" + lines[30_000][6:]  # after 29.997: backwards, file line 30_003

    p = big_file(tmp_path, mutate=mutate)
    with pytest.raises(RecordingError, match=r"line 30003: time goes backwards"):
        read_recording(p)
    ds = read_recording(p, repair_time=True)
    same(ds, slow(p, repair_time=True))


def test_missing_values_in_a_big_file(tmp_path):
    def mutate(lines):
        for i in (5, 500, 50_000):
            a, b, c = lines[i].split(",")
            lines[i] = f"{a},,{c}" if i != 500 else f"{a},NaN,{c}"

    p = big_file(tmp_path, mutate=mutate)
    ds = read_recording(p)
    assert FAST_NOTE in ds.attrs["history"]
    assert int(np.isnan(ds["x"].values).sum()) == 3
    assert "column 'x (m)': 3 missing value(s) kept as NaN" in ds.attrs["history"]
    same(ds, slow(p))


SETTINGS = settings(
    max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
CELLS = st.sampled_from(
    [
        "0",
        "1",
        "-2.5",
        "1e3",
        "3,5",
        "nan",
        "NaN",
        "",
        " ",
        "abc",
        "inf",
        "1e999",
        '"4"',
        "0.1",
        "12:00:01",
        "2021-01-01T00:00:00",
        "#",
        "7 ",
        " 8",
        "+.5",
        "1.",
        "N/A",
    ]
)


def test_a_comment_line_in_a_text_first_column_reads_as_line_by_line(tmp_path):
    """Found by hypothesis: '#,0,0' under 'abc,0,0' parses whole in pandas, but is a comment line by line."""
    p = tmp_path / "any.csv"
    p.write_bytes(b"abc,0,0\n#,0,0\n")
    same(outcome(lambda: read_recording(p)), outcome(lambda: slow(p)))
    p.write_bytes(b"abc,0,0\nabd,1,1\n  % note,2,2\nabe,3,3\n")
    same(outcome(lambda: read_recording(p)), outcome(lambda: slow(p)))


@SETTINGS
@given(
    rows=st.lists(st.lists(CELLS, min_size=1, max_size=4), min_size=1, max_size=12),
    sep=st.sampled_from([",", ";", "\t", " "]),
    header=st.sampled_from(["", "time (s),x (m)\n", "t;a;b\n", "# note\nindex\ttime\tv (mm/s)\n"]),
    ending=st.sampled_from(["\n", "\r\n"]),
)
def test_fast_and_slow_agree_on_anything(tmp_path, rows, sep, header, ending):
    p = tmp_path / "any.csv"
    text = header + ending.join(sep.join(r) for r in rows) + ending
    p.write_bytes(text.encode())
    fast = outcome(lambda: read_recording(p))
    ref = outcome(lambda: slow(p))
    same(fast, ref)


@SETTINGS
@given(
    n=st.integers(2, 60),
    nchan=st.integers(1, 3),
    seed=st.integers(0, 2**16),
    sep=st.sampled_from([",", ";", "\t", " "]),
    comma=st.booleans(),
    holes=st.booleans(),
    quote=st.booleans(),
)
def test_fast_and_slow_agree_on_tables(tmp_path, n, nchan, seed, sep, comma, holes, quote):
    rng = np.random.default_rng(seed)
    dec = "," if comma and sep != "," else "."
    t = np.cumsum(rng.uniform(0.5, 1.5, n)) * 1e-3
    x = rng.standard_normal((n, nchan)) * 10.0 ** rng.integers(-6, 6)
    cells = [[f"{a:.6f}"] + [f"{v:.9g}" for v in r] for a, r in zip(t, x)]
    if holes:
        cells[rng.integers(n)][1 + rng.integers(nchan)] = ""
    if quote and sep != " ":
        cells = [[f'"{c}"' for c in r] for r in cells]
    head = sep.join(["time_s"] + [f"ch{j}_mm" for j in range(nchan)])
    p = tmp_path / "table.csv"
    p.write_text(head + "\n" + "\n".join(sep.join(c.replace(".", dec) for c in r) for r in cells) + "\n")
    same(outcome(lambda: read_recording(p)), outcome(lambda: slow(p)))
