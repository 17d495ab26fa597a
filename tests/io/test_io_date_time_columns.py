"""A logger that writes the date and the time of day in two columns (``Date,Time,acc``): the two are read together
as the clock, so the start has its calendar date and a record that runs past midnight stays continuous."""

from __future__ import annotations

from datetime import datetime, timedelta

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording

FS = 200.0


def _write(path, start, n, date_fmt, time_fmt="%H:%M:%S.%f", header="Date,Time,acc_g", sep=","):
    rows = []
    for i in range(n):
        t = start + timedelta(seconds=i / FS)
        rows.append(
            f"{t.strftime(date_fmt)}{sep}{t.strftime(time_fmt)}{sep}{0.01 * np.sin(2 * np.pi * 3.75 * i / FS):.6f}"
        )
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def test_iso_date_and_time_columns_are_one_clock(tmp_path):
    p = _write(tmp_path / "r.csv", datetime(2026, 5, 4, 7, 30), 2000, "%Y-%m-%d")
    rec = read_recording(p)
    assert list(rec.data_vars) == ["acc"]  # neither Date nor Time is a channel
    assert rec.attrs["start_time"].startswith("2026-05-04 07:30:00")
    assert rec.attrs["sample_rate_hz"] == pytest.approx(FS, rel=1e-9)
    np.testing.assert_allclose(rec.time.values, np.arange(2000) / FS, atol=1e-9)
    assert "column 'Date' (dates) and column 'Time' (times of day) together" in rec.attrs["history"]


def test_a_record_past_midnight_stays_continuous(tmp_path):
    p = _write(tmp_path / "r.csv", datetime(2026, 5, 4, 23, 59, 59), 1000, "%d.%m.%Y")  # 5 s, across midnight
    rec = read_recording(p)
    assert rec.attrs["start_time"] == "2026-05-04T23:59:59"  # dotted: day.month.year; stated as ISO 8601
    np.testing.assert_allclose(np.diff(rec.time.values), 1 / FS, atol=1e-9)  # no jump back of a day
    assert rec.time.values[-1] == pytest.approx(999 / FS, abs=1e-9)


def test_time_column_given_still_takes_the_date(tmp_path):
    p = _write(tmp_path / "r.csv", datetime(2026, 5, 14, 7, 30), 400, "%d/%m/%Y", header="Time,Date,acc_g")
    p.write_text(
        "\n".join(",".join((c.split(",")[1], c.split(",")[0], c.split(",")[2])) for c in p.read_text().splitlines())
        + "\n"
    )  # columns Time, Date, acc as another logger orders them
    rec = read_recording(p, time_column="Time")
    assert rec.attrs["start_time"] == "2026-05-14T07:30:00"  # day 14: day/month/year
    assert list(rec.data_vars) == ["acc"]


def test_an_ambiguous_date_is_refused_naming_the_option(tmp_path):
    p = _write(tmp_path / "r.csv", datetime(2026, 3, 1, 10, 0), 300, "%d/%m/%Y")  # 01/03: March 1st or January 3rd
    with pytest.raises(RecordingError, match=r"could be day/month/year or month/day/year.*date_order="):
        read_recording(p)
    rec = read_recording(p, date_order="dmy")
    assert rec.attrs["start_time"] == "2026-03-01T10:00:00"
