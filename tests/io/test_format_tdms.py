"""NI TDMS files written by npTDMS (the ``tdms`` extra): waveform channels with units and start time."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

FS = 2048.0
T = np.arange(4096) / FS
X = np.sin(2 * np.pi * 30.0 * T)


def _write(path, channels):
    nptdms = pytest.importorskip("nptdms")
    with nptdms.TdmsWriter(str(path)) as w:
        w.write_segment([nptdms.ChannelObject(g, c, data, properties=props) for g, c, data, props in channels])


def _wf(unit, dt=1 / FS):
    return {
        "wf_increment": dt,
        "wf_start_offset": 0.0,
        "unit_string": unit,
        "wf_start_time": np.datetime64("2026-12-07T05:00:00.000000"),
    }


def test_two_channels_with_units_and_start_time(tmp_path):
    p = tmp_path / "daq.tdms"
    _write(p, [("Accel", "x", X, _wf("g")), ("Accel", "y", -X, _wf("m/s^2"))])
    assert detect_format(p, p.read_bytes()).name == "tdms"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.tdms" and list(ds.data_vars) == ["accel_x", "accel_y"]
    assert ds.attrs["sample_rate_hz"] == pytest.approx(FS, rel=1e-12)
    np.testing.assert_allclose(ds["accel_x"].values, X * STANDARD_GRAVITY, rtol=1e-12)
    np.testing.assert_allclose(ds["accel_y"].values, -X, rtol=1e-12)
    assert ds.attrs["start_time"] == "2026-12-07T05:00:00.000000Z"


def test_channels_sampled_differently_need_a_choice(tmp_path):
    p = tmp_path / "mixed.tdms"
    _write(p, [("A", "fast", X, _wf("g")), ("B", "slow", X[::2], _wf("g", 2 / FS))])
    with pytest.raises(RecordingError, match=r"mixed\.tdms: channel 'B/slow' .* read them one at a time"):
        read_recording(p)
    slow = read_recording(p, channel="B/slow")
    assert slow.attrs["sample_rate_hz"] == pytest.approx(FS / 2, rel=1e-12)


def test_index_file_named(tmp_path):
    p = tmp_path / "daq.tdms_index"
    p.write_bytes(b"TDSh" + b"\x00" * 24)
    with pytest.raises(RecordingError, match=r"daq\.tdms_index: a TDMS index file .*expected the \.tdms file"):
        read_recording(p)


def test_missing_extra_named(tmp_path, monkeypatch):
    import sys

    p = tmp_path / "x.tdms"
    p.write_bytes(b"TDSm" + b"\x00" * 64)
    monkeypatch.setitem(sys.modules, "nptdms", None)  # as if npTDMS were not installed
    with pytest.raises(RecordingError, match=r"x\.tdms: reading TDMS files needs npTDMS: pip install 'vibkit\[tdms\]'"):
        read_recording(p)
