"""A large text file is streamed: laid out from its head, parsed in chunks, hashed as it streams.

Every streamed read must give exactly the dataset (values, attrs, history, sha256) or the error of
reading the file whole.  The tests lower the size above which files stream and the rows of a chunk,
so that small files cross chunk boundaries everywhere.
"""

import hashlib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from vibkit.io import RecordingError, largefile, read_recording
from vibkit.io.text import fastpath
from vibkit.io.text.layout import _sniff

DATA = Path(__file__).resolve().parents[2] / "data"
TEXT_FILES = sorted(
    p.relative_to(DATA).as_posix()
    for p in DATA.rglob("*")
    if p.is_file() and p.suffix.lower() in (".csv", ".txt", ".tsv", ".dat")
)


def outcome(path, **kw):
    try:
        return read_recording(path, **kw)
    except RecordingError as err:
        return err


def same(a, b):
    if isinstance(a, Exception) or isinstance(b, Exception):
        assert type(a) is type(b) and str(a) == str(b), (a, b)
        return
    xr.testing.assert_identical(a, b)
    assert a.attrs == b.attrs  # history and sha256 included


@pytest.fixture
def streamed(monkeypatch):
    """Read with every file over 0 bytes streamed, ``rows`` rows to a chunk (a function of rows)."""

    def read(path, rows=7, **kw):
        with monkeypatch.context() as m:
            m.setattr(largefile, "STREAM_BYTES", 0)
            m.setattr(fastpath, "_CHUNK_ROWS", rows)
            return outcome(path, **kw)

    return read


def test_text_files_are_streamed_above_the_size(monkeypatch, tmp_path):
    """A file over STREAM_BYTES is parsed without its bytes read whole (read_all is never called)."""
    p = tmp_path / "a.csv"
    t = np.arange(5000) / 100.0
    p.write_text("time (s),x (m)\n" + "".join(f"{a:.2f},{np.sin(a):.6f}\n" for a in t))
    monkeypatch.setattr(largefile, "STREAM_BYTES", 1000)
    monkeypatch.setattr(fastpath, "_CHUNK_ROWS", 333)

    def whole(self):
        raise AssertionError("the file was read whole")

    monkeypatch.setattr(largefile.LargeFile, "read_all", whole)
    ds = read_recording(p)
    np.testing.assert_array_equal(ds["time"].values, t)
    np.testing.assert_array_equal(ds["x"].values, np.round(np.sin(t), 6))
    assert ds.attrs["sha256"] == hashlib.sha256(p.read_bytes()).hexdigest()


@pytest.mark.parametrize("rel", TEXT_FILES)
def test_every_shipped_text_file_reads_the_same_streamed(streamed, rel):
    same(streamed(DATA / rel), outcome(DATA / rel))


def rows_file(tmp_path, n, mutate=None):
    t = np.arange(n) / 200.0
    lines = [f"{a:.3f},{np.sin(7 * a):.6f},{np.cos(3 * a):.6f}" for a in t]
    if mutate:
        mutate(lines)
    p = tmp_path / "rows.csv"
    p.write_text("# logger: test\ntime (s),x (m),y (mm)\n" + "\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize("rows", [1, 2, 3, 5, 64, 99, 100, 101, 1000])
def test_a_chunk_boundary_anywhere(streamed, tmp_path, rows):
    """Rows crossing the chunk size at every offset: the same values as the whole file and as written."""
    p = rows_file(tmp_path, 300)
    ds = streamed(p, rows=rows)
    same(ds, outcome(p))
    np.testing.assert_array_equal(ds["x"].values, np.round(np.sin(7 * np.arange(300) / 200.0), 6))


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda s: s + ",7", "line 153: expected 3 fields (as in the header on line 2), found 4"),
        (lambda s: s.split(",")[0] + ",1.0", "line 153: expected 3 fields (as in the header on line 2), found 2"),
        (lambda s: "0.500" + s[5:], "line 153: time goes backwards"),
    ],
)
def test_a_bad_line_in_the_second_chunk_is_named(streamed, tmp_path, edit, words):
    def mutate(lines):
        lines[150] = edit(lines[150])  # file line 153: two lines above the data

    p = rows_file(tmp_path, 300, mutate)
    err = streamed(p, rows=100)
    assert isinstance(err, RecordingError) and words in str(err)
    same(err, outcome(p))


def test_blank_and_missing_cells_in_later_chunks(streamed, tmp_path):
    def mutate(lines):
        lines[120] = lines[120].rsplit(",", 1)[0] + ","  # an empty cell
        lines[250] = lines[250].replace(lines[250].split(",")[1], "NaN")
        lines.insert(200, "")  # a blank line (dropped, the line numbers kept)

    p = rows_file(tmp_path, 300, mutate)
    ds = streamed(p, rows=50)
    same(ds, outcome(p))
    assert int(np.isnan(ds["y"].values).sum()) == 1 and int(np.isnan(ds["x"].values).sum()) == 1
    assert ds.sizes["time"] == 300


def test_comment_and_quoted_rows_fall_back_to_the_same_dataset(streamed, tmp_path):
    def mutate(lines):
        lines.insert(180, "# paused")
        lines[20] = '"' + lines[20].replace(",", '","') + '"'

    p = rows_file(tmp_path, 300, mutate)
    same(streamed(p, rows=64), outcome(p))


TEXTS = [
    # head of whole numbers, tail of decimal commas: the tail decides (';' and a decimal comma)
    "t;a\n" + "".join(f"{i};{i}\n" for i in range(5)) + "".join(f"{i};{i},5\n" for i in range(5, 40)),
    # a tab file: ';' and '|' appear nowhere and are one reading
    "time\tx\n" + "".join(f"{i / 10}\t{i * 2}\n" for i in range(50)),
    # ';' only in the metadata of the head, ',' between the data
    "site;Madrid\nrate;100\ntime,x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(60)),
    # a header split by '|' over rows of whitespace
    "time|x|y\n" + "".join(f"{i}  {i * 3}  {i * 5}\n" for i in range(30)),
]


@pytest.mark.parametrize("text", TEXTS)
def test_the_sniff_decides_as_when_trying_every_delimiter(text):
    """Skipping delimiters found nowhere in the text is a shortcut: the same decision as trying them all."""
    lines = text.split("\n")[:-1]
    got = _sniff(lines, None, None, text)
    want = _sniff(lines, None, None)
    assert got[:4] == want[:4] and got[4] == want[4]


def test_head_and_tail_differ(tmp_path):
    """Whole numbers at the head, decimal commas at the tail: read with ';' and the decimal comma."""
    p = tmp_path / "ht.csv"
    p.write_text(TEXTS[0])
    ds = read_recording(p)
    assert "delimiter ';' detected" in ds.attrs["history"] and "decimal comma detected" in ds.attrs["history"]
    np.testing.assert_array_equal(ds["a"].values, [0, 1, 2, 3, 4] + [i + 0.5 for i in range(5, 40)])
