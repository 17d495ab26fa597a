"""--segment START:END: the part of a recording a command analyses, in the file's own time, never cut to fit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vibkit.diagnose.segment import SegmentError, cut_recording, parse_segment, recording_span

from support.chain import family
from support.cli import run  # noqa: F401 (fixture)
from support.recording import recording

FS = 200.0
F1, F2 = 3.0, 3.6  # link-pass fundamentals [Hz] of the first and the second half of the two-tone file


def test_a_cut_keeps_the_samples_inside_in_the_files_own_time():
    t = 100.0 + np.arange(50) / 10.0  # a file whose clock starts at 100 s: 100.0 ... 104.9, spanning 100-105 s
    rec = recording({"az": np.arange(50.0)}, t=t, attrs={"source_file": "clock.csv", "history": "read\n"})
    assert recording_span(rec) == pytest.approx((100.0, 105.0))
    part = cut_recording(rec, (101.0, 102.5))
    np.testing.assert_allclose(part["time"].values, 101.0 + np.arange(15) / 10.0)  # 101.0 <= t < 102.5
    np.testing.assert_array_equal(part["az"].values, np.arange(10.0, 25.0))
    assert part.attrs["source_file"] == "clock.csv" and part.attrs["history"].startswith("read\n")
    assert "segment 101:102.5 s kept (15 samples)" in part.attrs["history"]
    assert cut_recording(rec, None) is rec
    assert cut_recording(rec, (100.0, 105.0)).sizes["time"] == 50  # the whole span is inside


@pytest.mark.parametrize("segment", [(99.0, 101.0), (104.0, 106.0), (0.0, 1000.0), "50:60"])
def test_a_segment_outside_the_recording_names_its_span(segment):
    rec = recording({"az": np.zeros(50)}, t=100.0 + np.arange(50) / 10.0, attrs={"source_file": "clock.csv"})
    with pytest.raises(SegmentError, match=r"not inside clock.csv, which spans 100-105 s"):
        cut_recording(rec, segment)


@pytest.mark.parametrize("text", ["5", "a:b", "3:2", "-1:4", "nan:3"])
def test_a_segment_that_is_no_segment_is_refused(text):
    with pytest.raises(ValueError, match="segment"):
        parse_segment(text)


@pytest.fixture
def two_tone(tmp_path):
    """60 s of a tensioner's displacement [mm]: the link pass at F1 for 30 s, then at F2."""
    t = np.arange(int(60 * FS)) / FS
    x = np.where(t < 30.0, family(t, F1), family(t, F2)) * 0.02
    x = x + 0.002 * np.random.default_rng(3).standard_normal(t.size)
    path = tmp_path / "two_tone.csv"
    np.savetxt(
        path, np.column_stack([t, x]), delimiter=",", header="time (s),displacement (mm)", comments="", fmt="%.6f"
    )
    return path


def test_spectrum_reads_the_part_asked_for(run, two_tone):  # noqa: F811
    """Each half of the file gives its own fundamental, to its sigma (the true values are known)."""
    for seg, f in (("0:30", F1), ("30:60", F2)):
        rc, out, err = run("spectrum", two_tone, "--segment", seg, "--band", "2.5:4.5", "--json")
        d = json.loads(out)
        assert rc == 0, err
        assert abs(d["fundamental_hz"] - f) < max(4 * d["fundamental_sigma_hz"], 1e-3), (seg, d["fundamental_hz"])


@pytest.mark.parametrize(
    "command",
    [
        ["spectrum"],
        ["pitch", "--speed", "0.5"],
        ["links", "--links", "100", "--speed", "0.5"],
        ["compare", "{rec}", "las-palmas"],
        ["report", "-o", "{tmp}/r.pdf"],
        ["ride"],
        ["fleet", "add", "--db", "{tmp}/f.db", "--unit", "E1", "--speed", "0.5", "--nominal-pitch", "0.1333"],
    ],
)
def test_every_command_refuses_a_segment_outside_the_recording(run, two_tone, tmp_path, command):  # noqa: F811
    """Exit 1 with one line that names the recording's span: never a segment cut to what the file holds."""
    argv = [a.format(rec=two_tone, tmp=tmp_path) for a in command]
    if "{rec}" not in command:
        argv.insert(2 if argv[0] == "fleet" else 1, str(two_tone))
    rc, out, err = run(*argv, "--segment", "50:90")
    assert rc == 1, (rc, out, err)
    assert len(err.strip().splitlines()) == 1, err
    assert "segment 50:90 s is not inside two_tone.csv, which spans 0-60 s" in err, err
    assert not (tmp_path / "r.pdf").exists() and not (tmp_path / "f.db").exists()
