"""Broken files: one clear line naming the file, the line and what was expected; never a result."""

import os

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording

from support.contracts import recording_error

GOOD = "time (s),acc_z (m/s^2)\n0.00,0.1\n0.01,0.2\n0.02,0.3\n0.03,0.4\n"


def expect(path, line, *words):
    err = recording_error(path, lambda: read_recording(path), *words, line=line)
    assert err.path == os.fspath(path) and err.line == line
    return str(err)


@pytest.fixture
def write(tmp_path):
    def _write(content, name="broken.csv"):
        p = tmp_path / name
        p.write_bytes(content if isinstance(content, bytes) else content.encode())
        return p

    return _write


def test_a_good_file_reads(write):
    ds = read_recording(write(GOOD))
    np.testing.assert_allclose(ds["acc_z"].values, [0.1, 0.2, 0.3, 0.4])


def test_missing_file(tmp_path):
    expect(tmp_path / "nope.csv", None, "file not found")


def test_folder_instead_of_file(tmp_path):
    expect(tmp_path, None, "folder")


def test_empty(write):
    expect(write(b""), None, "empty (0 bytes)")


def test_blank_lines_only(write):
    expect(write("\n  \n\n"), None, "only blank lines")


def test_header_only(write):
    expect(write("# logger export\ntime (s),acc_z (m/s^2)\n"), 2, "no data rows", "below the header")


def test_comments_only(write):
    expect(write("# a\n# b\n"), 2, "only comment lines")


def test_text_in_numbers(write):
    bad = GOOD.replace("0.02,0.3", "0.02,abc")
    expect(write(bad), 4, "expected a number in column 'acc_z (m/s^2)', found 'abc'")


def test_text_in_the_first_data_row(write):
    bad = GOOD.replace("0.00,0.1", "0.00,abc")
    expect(write(bad), 2, "expected a number in column 'acc_z (m/s^2)', found 'abc'")


def test_text_in_the_time_column(write):
    expect(write(GOOD.replace("0.02,", "zz,")), 4, "expected a time in column 'time (s)', found 'zz'")


def test_infinite_value_is_missing_like_nan(write):
    """An infinity (1e999, inf, -Infinity) is no measurement: read as NaN, which the analyses interpolate or cut
    as they do NaN, and the history says so; in the time column it stays an error."""
    for cell in ("1e999", "inf", "-Infinity"):
        rec = read_recording(write(GOOD.replace("0.2", cell)))
        values = np.asarray(rec[list(rec.data_vars)[0]].values)
        assert np.isnan(values[1]) and np.isfinite(values[[0, 2, 3]]).all(), cell
        assert "1 infinite value(s) (first on line 3) read as missing, like NaN" in rec.attrs["history"], cell
    expect(write(GOOD.replace("0.02,", "1e999,")), 4, "time")


def test_time_going_backwards(write):
    bad = "time (s),x (m)\n0.0,1\n0.1,2\n0.05,3\n0.2,4\n"
    expect(write(bad), 4, "time goes backwards", "0.05 s after 0.1 s", "repair_time=True")


def test_repeated_time_stamp(write):
    bad = "time (s),x (m)\n0.0,1\n0.1,2\n0.1,3\n0.2,4\n"
    expect(write(bad), 4, "repeats the previous row")


def test_ragged_row_short(write):
    bad = GOOD.replace("0.02,0.3", "0.02")
    expect(write(bad), 4, "expected 2 fields (as in the header on line 1), found 1")


def test_ragged_first_data_row(write):
    bad = GOOD.replace("0.00,0.1", "0.00")
    expect(write(bad), 2, "expected 2 fields, found 1")


def test_ragged_row_long(write):
    bad = GOOD.replace("0.02,0.3", "0.02,0.3,7")
    expect(write(bad), 4, "expected 2 fields", "found 3")


def test_binary_garbage(write):
    rng = np.random.default_rng(5)
    expect(write(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes(), "garbage.csv"), None, "binary content")


def test_binary_garbage_without_nul_bytes(write):
    rng = np.random.default_rng(6)
    junk = rng.integers(1, 32, 4096, dtype=np.uint8).tobytes()
    expect(write(junk, "junk.csv"), None, "binary content")


def test_binary_garbage_named_like_miniseed(write):
    expect(write(b"\x00\x01garbage" * 100, "x.mseed"), None, "binary content", "waveform format obspy reads")


def test_binary_garbage_named_like_netcdf(write):
    expect(write(b"\x00\x01garbage" * 100, "x.nc"), None, "cannot read as netCDF")


def test_one_sample(write):
    expect(write("time (s),x (m)\n0.0,1\n"), 2, "only one data row", "at least 2 samples")


def test_all_nan(write):
    expect(write("time (s),x (m)\nnan,nan\nNaN,\n,nan\n"), 2, "all values are missing")


def test_all_nan_channel(write):
    msg = expect(write("time (s),x (m)\n0.0,nan\n0.1,\n0.2,NaN\n"), None, "all values in column 'x (m)' are missing")
    assert "lines 2-4" in msg


def test_no_time_and_no_rate(write):
    expect(write("x (m)\n1\n2\n3\n"), 1, "no time column and no sample rate")


def test_unknown_time_unit(write):
    expect(write("time (fortnights),x (m)\n0,1\n1,2\n"), 1, "time column 'time (fortnights)' has unit")


def test_unknown_channel(write):
    with pytest.raises(RecordingError, match=r"line 1: no channel 'acc_x'; channels: 'acc_z \(m/s\^2\)'"):
        read_recording(write(GOOD), channel="acc_x")


def test_error_is_a_value_error_and_pickles(write):
    import pickle

    err = RecordingError("data/x.csv", 17, "expected a number in column 'acc_z', found 'abc'")
    assert isinstance(err, ValueError)
    assert str(err) == "data/x.csv, line 17: expected a number in column 'acc_z', found 'abc'"
    back = pickle.loads(pickle.dumps(err))
    assert (back.path, back.line, str(back)) == (err.path, err.line, str(err))
