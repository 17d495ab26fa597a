"""enDAQ / Slam Stick ``.ide`` files (the ``ide`` extra: idelib), on a real recorder's file from idelib's own test
data (tests/io/endaq/SOURCES.md): the values against what idelib reads from the file, converted from g."""

from __future__ import annotations

import io
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

FILE = Path(__file__).resolve().parent / "endaq" / "SSX_Data.IDE"


def _idelib_arrays(channel_id):
    idelib = pytest.importorskip("idelib")
    doc = idelib.importer.openFile(io.BytesIO(FILE.read_bytes()), quiet=True)
    idelib.importer.readData(doc)
    try:
        ch = doc.channels[channel_id]
        return ch.getSession().arraySlice(), ch.getSession().getSampleRate()
    finally:
        doc.close()


def test_sniffed_by_content_whatever_the_name(tmp_path):
    data = FILE.read_bytes()
    assert detect_format(FILE, data).name == "ide"
    renamed = tmp_path / "recording.bin"
    shutil.copy(FILE, renamed)
    assert detect_format(renamed, data).name == "ide"  # EBML with DocType 'mide', not the suffix
    # another EBML file (Matroska/WebM) is not claimed
    webm = b"\x1a\x45\xdf\xa3\x9f\x42\x86\x81\x01\x42\x82\x84webm" + b"\x00" * 64
    assert detect_format(tmp_path / "clip.webm", webm).name != "ide"


def test_main_accelerometer_read_as_idelib_reads_it():
    arr, rate = _idelib_arrays(8)
    ds = read_recording(FILE)
    assert ds.attrs["reader"] == "vibkit.io.ide"
    names = [v for v in ds.data_vars if v != "segment"]
    assert len(names) == 3
    assert [ds[v].attrs["source_name"] for v in names] == [
        "Main Acceleration/X",
        "Main Acceleration/Y",
        "Main Acceleration/Z",
    ]
    for k, v in enumerate(names):
        assert ds[v].attrs["units"] == "m/s^2"
        np.testing.assert_allclose(ds[v].values, arr[k + 1] * STANDARD_GRAVITY, rtol=1e-12)
    np.testing.assert_allclose(ds.time.values, (arr[0] - arr[0][0]) * 1e-6, atol=1e-12)
    # the rate from the mean step agrees with idelib's own estimate to 0.1 % (the stamps jitter by 8 %)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(rate, rel=1e-3)
    assert ds.attrs["recorder"] == "Slam Stick X (25g+DC)"


def test_channel_names_another_and_refuses_two_clocks():
    arr, _ = _idelib_arrays(32)
    ds = read_recording(FILE, channel=["16g DC Acceleration/X (DC)", "16g DC Acceleration/Z (DC)"])
    names = [v for v in ds.data_vars if v != "segment"]
    assert len(names) == 2 and ds.sizes["time"] == arr.shape[1]
    np.testing.assert_allclose(ds[names[1]].values, arr[3] * STANDARD_GRAVITY, rtol=1e-12)
    with pytest.raises(RecordingError, match=r"channels with their own clocks.*one channel at a time"):
        read_recording(FILE, channel=["Main Acceleration/X", "16g DC Acceleration/X (DC)"])
    with pytest.raises(RecordingError, match=r"no channel 'nope'.*Main Acceleration/X"):
        read_recording(FILE, channel="nope")


def test_without_idelib_one_line_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "idelib", None)  # import idelib raises ImportError
    with pytest.raises(RecordingError, match=r"needs idelib: pip install 'vibkit\[ide\]'") as exc:
        read_recording(FILE)
    assert "\n" not in str(exc.value)


def test_damaged_file_is_one_line(tmp_path):
    pytest.importorskip("idelib")
    bad = tmp_path / "cut.ide"
    bad.write_bytes(FILE.read_bytes()[:200])
    try:
        read_recording(bad)
    except RecordingError as exc:
        assert "\n" not in str(exc) and "cut.ide" in str(exc)
